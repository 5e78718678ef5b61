"""Stable-Baselines3 models as socialzoo policy files: the acting network and the VecNormalize
statistics of a PPO or DQN model, copied into an `MlpPolicy` that runs in numpy."""

from __future__ import annotations

from typing import Any

import numpy as np

from socialzoo.agents.mlp import ACTIVATIONS, MlpPolicy, ObservationNormalizer

# torch activation module name -> MlpPolicy activation.
_ACTIVATIONS = {"Tanh": "tanh", "ReLU": "relu"}


class ExportError(ValueError):
    """A model whose acting network is not a plain MLP over a flat observation."""


def _layers(modules: Any, where: str) -> tuple[list[tuple[np.ndarray, np.ndarray]], list[str]]:
    """(W, b) of every Linear layer of a torch module sequence, and the activations between them."""
    import torch.nn as nn

    weights: list[tuple[np.ndarray, np.ndarray]] = []
    activations: list[str] = []
    for module in modules:
        if isinstance(module, nn.Linear):
            w = module.weight.detach().cpu().numpy().astype(np.float32)
            b = np.zeros(w.shape[0]) if module.bias is None else module.bias.detach().cpu().numpy()
            weights.append((w, b.astype(np.float32)))
        elif type(module).__name__ in _ACTIVATIONS:
            activations.append(_ACTIVATIONS[type(module).__name__])
        elif isinstance(module, (nn.Sequential, nn.Identity, nn.Flatten)):
            inner_w, inner_a = _layers(list(module.children()), where)
            weights += inner_w
            activations += inner_a
        else:
            raise ExportError(
                f"{where}: cannot export a {type(module).__name__} layer (Linear, Tanh, ReLU only)"
            )
    return weights, activations


def _activation(activations: list[str], num_layers: int, where: str) -> str:
    if len(activations) != num_layers - 1 or len(set(activations)) > 1:
        raise ExportError(
            f"{where}: expected one activation kind between each pair of Linear layers, got {activations} "
            f"for {num_layers} layers"
        )
    activation = activations[0] if activations else "tanh"
    assert activation in ACTIVATIONS
    return activation


def _check_flat_features(policy: Any, where: str) -> None:
    from stable_baselines3.common.torch_layers import FlattenExtractor

    if not isinstance(policy.features_extractor, FlattenExtractor):
        raise ExportError(
            f"{where}: features extractor {type(policy.features_extractor).__name__} is not Flatten"
        )


def normalizer_of(vec_normalize: Any) -> ObservationNormalizer | None:
    """The observation normaliser of an SB3 VecNormalize (None: none, or it does not normalise obs)."""
    if vec_normalize is None or not vec_normalize.norm_obs:
        return None
    rms = vec_normalize.obs_rms
    return ObservationNormalizer(
        rms.mean, rms.var, float(vec_normalize.clip_obs), float(vec_normalize.epsilon)
    )


def export_policy(
    model: Any, name: str, observation: dict[str, Any], vec_normalize: Any = None
) -> tuple[MlpPolicy, str]:
    """The acting network of an SB3 PPO or DQN model as an MlpPolicy.

    PPO acts with the argmax of its action logits (features -> policy MLP -> action_net), DQN with the argmax
    of its Q-values (q_net); both take observations normalised as VecNormalize normalises them during
    training. The exported policy gives the same actions as SB3's `model.predict(obs, deterministic=True)` on
    the VecNormalize-d observations, without torch or SB3.

    Args:
        model: a stable_baselines3 PPO (Discrete actions, MlpPolicy) or DQN.
        name: the policy's registry name ("ppo", "dqn").
        observation: the env's EnvConfig.observation as a plain dict (recorded in the file).
        vec_normalize: the VecNormalize the model trained on, or None.

    Returns:
        (policy, output): output is "logits" (PPO) or "q_values" (DQN), for the file header.

    Raises:
        ExportError: a model that is not a plain MLP over flat observations.
    """
    from stable_baselines3 import DQN, PPO

    acting: Any
    if isinstance(model, PPO):
        # The actor's extractor (shared or not); the policy MLP ends with an activation, then
        # action_net gives the logits.
        where, acting, output = "PPO policy", model.policy, "logits"
        modules = [*model.policy.mlp_extractor.policy_net.children(), model.policy.action_net]
    elif isinstance(model, DQN):
        where, acting, output = "DQN q_net", model.q_net, "q_values"
        modules = list(model.q_net.q_net.children())
    else:
        raise ExportError(f"cannot export a {type(model).__name__}: PPO or DQN only")
    _check_flat_features(acting, where)
    weights, acts = _layers(modules, where)
    activation = _activation(acts, len(weights), where)
    return MlpPolicy(name, weights, activation, observation, normalizer_of(vec_normalize)), output
