"""The torch networks of the imitation trainers (BC, GAIL) and their export to MlpPolicy files."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from torch import nn

from socialzoo.agents.mlp import MlpPolicy, ObservationNormalizer
from socialzoo.nav.subpolicies import NUM_ACTIONS
from socialzoo.train.checks import Activation

ACTIVATION_MODULES: dict[str, type[nn.Module]] = {"tanh": nn.Tanh, "relu": nn.ReLU}
# Normalised observations are clipped to +-NORM_CLIP (as SB3's VecNormalize does).
NORM_CLIP = 10.0
NORM_EPSILON = 1e-8
# Variance floor: an entry that hardly varied in the demonstrations (a far human slot, an action
# never taken) must not turn a small deviation at test time into a saturated input.
MIN_VARIANCE = 1e-2


def normalizer_stats(obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(mean, var) of observations (N, D), float64; var floored at MIN_VARIANCE."""
    obs = np.asarray(obs, dtype=np.float64)
    if obs.ndim != 2 or len(obs) == 0:
        raise ValueError(f"normalizer_stats needs observations of shape (N >= 1, D), got {obs.shape}")
    return obs.mean(axis=0), np.maximum(obs.var(axis=0), MIN_VARIANCE)


class Normalize(nn.Module):
    """clip((x - mean) / sqrt(var + epsilon), -clip, clip) with fixed (D,) statistics (buffers)."""

    mean: torch.Tensor
    var: torch.Tensor

    def __init__(self, mean: np.ndarray, var: np.ndarray) -> None:
        super().__init__()
        self.register_buffer("mean", torch.as_tensor(np.asarray(mean), dtype=torch.float64))
        self.register_buffer("var", torch.as_tensor(np.asarray(var), dtype=torch.float64))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Normalised observations as VecNormalize computes them, clipped, float32."""
        # In float64, as ObservationNormalizer computes it, so the exported policy acts identically.
        out = (x.to(torch.float64) - self.mean) / torch.sqrt(self.var + NORM_EPSILON)
        return out.clamp(-NORM_CLIP, NORM_CLIP).to(torch.float32)

    def to_numpy(self) -> ObservationNormalizer:
        """The same normalisation as an ObservationNormalizer."""
        return ObservationNormalizer(self.mean.cpu().numpy(), self.var.cpu().numpy(), NORM_CLIP, NORM_EPSILON)


def mlp(
    in_size: int,
    hidden: Sequence[int],
    out_size: int,
    activation: Activation,
    normalizer: tuple[np.ndarray, np.ndarray] | None,
) -> nn.Sequential:
    """Normalize by the observations' (mean, var) unless `normalizer` is None -> [Linear ->
    activation] per hidden size -> Linear; in_size is the observation width D."""
    layers: list[nn.Module] = []
    sizes = [in_size, *hidden, out_size]
    for i in range(len(sizes) - 1):
        layers.append(nn.Linear(sizes[i], sizes[i + 1]))
        if i < len(sizes) - 2:
            layers.append(ACTIVATION_MODULES[activation]())
    net = nn.Sequential(*layers)
    if normalizer is not None:
        net = nn.Sequential(Normalize(*normalizer), *net)
    return net


def policy_network(
    obs_size: int,
    hidden: Sequence[int],
    activation: Activation,
    normalizer: tuple[np.ndarray, np.ndarray] | None,
    generator: torch.Generator | None = None,
) -> nn.Sequential:
    """The policy MLP: observation (N, D) -> logits (N, 4); its weights drawn from `generator`.

    A policy network is a fixed observation normaliser (statistics of the demonstrations) followed by an MLP
    that gives one logit per sub-policy. TorchRL wraps it as a ProbabilisticActor over one-hot actions (the
    encoding of socialzoo.env.torchrl_single); `to_mlp_policy` copies the same layers into the numpy MlpPolicy
    that the benchmark loads, which acts greedily (argmax of the logits, the actor's mode).
    """
    net = mlp(obs_size, hidden, NUM_ACTIONS, activation, normalizer)
    init_linear(net, generator)
    return net


def init_linear(net: nn.Module, generator: torch.Generator | None, last_gain: float = 0.01) -> None:
    """Orthogonal weights (gain sqrt(2), the last layer `last_gain`), zero biases, from `generator`
    (never the global torch RNG when a generator is given)."""
    linears = [m for m in net.modules() if isinstance(m, nn.Linear)]
    for i, layer in enumerate(linears):
        gain = last_gain if i == len(linears) - 1 else float(np.sqrt(2.0))
        nn.init.orthogonal_(layer.weight, gain=gain, generator=generator)
        nn.init.zeros_(layer.bias)


class Discriminator(nn.Module):
    """GAIL's discriminator D(s, a): the probability that a transition is the expert's.

    The observation (width obs_size) is normalised with the demonstrations' (mean, var), the
    action is one-hot; a tanh MLP of `hidden` sizes, its initial weights from `generator`, gives
    one logit l = log D - log(1 - D).
    """

    def __init__(
        self,
        obs_size: int,
        hidden: Sequence[int],
        normalizer: tuple[np.ndarray, np.ndarray],
        generator: torch.Generator | None = None,
    ) -> None:
        super().__init__()
        self.normalize = Normalize(*normalizer)
        self.net = mlp(obs_size + NUM_ACTIONS, hidden, 1, "tanh", None)
        init_linear(self.net, generator, last_gain=1.0)

    def logits(self, observation: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
        """(N, 1) logits of (N, D) observations and (N, 4) one-hot actions."""
        return self.net(torch.cat((self.normalize(observation), action.to(torch.float32)), dim=-1))

    def forward(self, observation: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
        """(N, 1) probabilities D(s, a) (what TorchRL's GAILLoss reads under "d_logits")."""
        return torch.sigmoid(self.logits(observation, action))


def make_actor(net: nn.Module) -> Any:
    """A TorchRL ProbabilisticActor over one-hot actions: "observation" -> "logits" -> "action"
    (OneHotCategorical), writing the action's log-probability as PPO needs it."""
    from tensordict.nn import TensorDictModule
    from torchrl.data import OneHot
    from torchrl.modules import OneHotCategorical, ProbabilisticActor

    return ProbabilisticActor(
        TensorDictModule(net, in_keys=["observation"], out_keys=["logits"]),
        in_keys=["logits"],
        out_keys=["action"],
        spec=OneHot(NUM_ACTIONS),
        distribution_class=OneHotCategorical,
        return_log_prob=True,
    )


def to_mlp_policy(name: str, net: nn.Sequential, observation: Any, activation: Activation) -> MlpPolicy:
    """The numpy MlpPolicy computing the same logits as the trained `net` (see `policy_network`,
    built with `activation`), registered as `name` ("bc", "gail"), for the env's ObservationConfig
    `observation` (or its plain dict)."""
    normalizer = next((m.to_numpy() for m in net if isinstance(m, Normalize)), None)
    is_config = dataclasses.is_dataclass(observation) and not isinstance(observation, type)
    obs = dataclasses.asdict(observation) if is_config else dict(observation)
    return MlpPolicy(name, linear_layers(net), activation, obs, normalizer)


def linear_layers(net: nn.Sequential) -> list[tuple[np.ndarray, np.ndarray]]:
    """(W, b) of the network's Linear layers, in order, as numpy copies."""
    return [
        (m.weight.detach().cpu().numpy().copy(), m.bias.detach().cpu().numpy().copy())
        for m in net
        if isinstance(m, nn.Linear)
    ]


def benchmark_env_id(map_name: str) -> str:
    """The registered benchmark env id of a map (its version is checked when a policy file loads).

    Raises:
        ValueError: a map without a benchmark id.
    """
    from socialzoo.env.registration import BENCHMARK_IDS

    for env_id, kwargs in BENCHMARK_IDS.items():
        if kwargs.get("map") == map_name:
            return env_id
    maps = sorted(str(k.get("map")) for k in BENCHMARK_IDS.values())
    raise ValueError(f"no benchmark env id for map {map_name!r}; benchmark maps: {maps}")


def policy_header(algo: str, data: Any, run_record: dict[str, Any], **training: Any) -> dict[str, Any]:
    """The header of an imitation policy file: the env id of the demonstrations' map and the
    training record (algorithm, seed, command, arguments, demonstrations, plus `training`)."""
    from socialzoo import __version__

    return {
        "env_id": benchmark_env_id(data.map),
        "training": {
            "algo": algo,
            "seed": run_record.get("seed"),
            "command": run_record.get("command"),
            "args": run_record.get("args"),
            "package_version": __version__,
            # The file as run.json names it (relative to the run folder), not as it was given.
            "demonstrations": {**data.record(), "file": run_record.get("args", {}).get("demos")},
            **training,
        },
    }
