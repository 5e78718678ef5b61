"""Learned policies at inference: a multilayer perceptron read from a policy file, run in numpy."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from socialzoo.agents.base import check_observations
from socialzoo.env.policy_file import ACTIVATIONS as ACTIVATIONS
from socialzoo.env.policy_file import (
    FileNetwork,
    PolicyFileError,
    mlp_layers,
    mlp_parts,
    read_policy_file,
    save_policy_file,
)

if TYPE_CHECKING:
    from socialzoo.env.tasks.base import Task

# What the network's last layer gives: one score per action either way; the greedy action is its argmax.
OUTPUTS = ("logits", "q_values")


class ObservationNormalizer:
    """clip((obs - mean) / sqrt(var + epsilon), -clip, clip), as SB3's VecNormalize applies it.

    Args:
        mean: (D,) running mean of the training observations.
        var: (D,) running variance.
        clip: bound of the normalised values.
        epsilon: added to the variance.
    """

    def __init__(self, mean: np.ndarray, var: np.ndarray, clip: float, epsilon: float) -> None:
        self.mean = np.asarray(mean, dtype=np.float64)
        self.var = np.asarray(var, dtype=np.float64)
        if self.mean.shape != self.var.shape or self.mean.ndim != 1:
            raise ValueError(f"normaliser mean {self.mean.shape} and var {self.var.shape} must be equal (D,)")
        if not (np.isfinite(self.mean).all() and np.isfinite(self.var).all() and (self.var >= 0).all()):
            raise ValueError("normaliser statistics must be finite, with var >= 0")
        if not (clip > 0 and epsilon >= 0):
            raise ValueError(f"normaliser clip must be > 0 and epsilon >= 0, got {clip!r}, {epsilon!r}")
        self.clip = float(clip)
        self.epsilon = float(epsilon)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """Normalised observations, float32, clipped to [-clip, clip]."""
        out = (obs - self.mean) / np.sqrt(self.var + self.epsilon)
        return np.clip(out, -self.clip, self.clip).astype(np.float32)


class MlpPolicy(FileNetwork):
    """A greedy policy over a multilayer perceptron.

    Every neural baseline (PPO and DQN trained with Stable-Baselines3, BC and GAIL trained with TorchRL) is
    saved as the same kind of file (socialzoo.env.policy_file): the layers of the network that maps an
    observation to one score per action (logits or Q-values), and the observation normalisation it was trained
    with. Acting is the greedy action: argmax of the scores. Evaluating needs neither torch nor the training
    library, and batches of any size cost one matrix product per layer.

    Args:
        name: the registry name (e.g. "ppo").
        weights: (W_i (out, in), b_i (out,)) per layer, torch's Linear convention.
        activation: hidden-layer activation, a key of ACTIVATIONS.
        observation: the EnvConfig.observation fields the network was trained on (plain dict).
        normalizer: the training observation normalisation, or None.
        header: the policy file's header (kept for config() and reports).
    """

    # Acts on observations alone (never reads the core), so a runner may pass it any subset of rows.
    reads_core = False

    def __init__(
        self,
        name: str,
        weights: Sequence[tuple[np.ndarray, np.ndarray]],
        activation: str,
        observation: dict[str, Any],
        normalizer: ObservationNormalizer | None = None,
        header: dict[str, Any] | None = None,
    ) -> None:
        super().__init__("MlpPolicy", weights, activation, header)
        self.name = name
        self.observation = dict(observation)
        self.normalizer = normalizer
        if normalizer is not None and normalizer.mean.shape[0] != self.input_size:
            raise ValueError(
                f"MlpPolicy: normaliser of size {normalizer.mean.shape[0]} for a network of {self.input_size} inputs"
            )

    @property
    def num_actions(self) -> int:
        """The number of actions (outputs of the last layer)."""
        return int(self.layers[-1][0].shape[0])

    def scores(self, obs: np.ndarray) -> np.ndarray:
        """(N, A) network outputs (logits or Q-values) for (N, D) observations."""
        obs = np.asarray(obs, dtype=np.float32)
        if obs.ndim != 2 or obs.shape[1] != self.input_size:
            layout = self.observation.get("layout", "?")
            raise ValueError(
                f"{self.name}: observations of width {obs.shape[-1]} given to a policy trained on the "
                f"{layout!r} layout of {self.input_size} numbers (observation {self.observation})"
            )
        x = self.normalizer(obs) if self.normalizer is not None else obs
        return self.forward(x)

    def act(self, obs: np.ndarray, task: Task | None = None) -> np.ndarray:
        """Greedy actions of shape obs.shape[:-1] (see socialzoo.agents.base.Policy.act)."""
        obs = check_observations(obs, f"{self.name}.act")
        lead = obs.shape[:-1]
        scores = self.scores(obs.reshape(-1, obs.shape[-1]))
        return np.argmax(scores, axis=1).astype(np.int64).reshape(lead)

    # ---------------------------------------------------------------- files
    def save(self, path: str | Path, header: dict[str, Any]) -> Path:
        """Write the policy file (header: env_id and training record; the network part is filled in)."""
        output = header.get("network", {}).get("output", "logits")
        tensors, network = mlp_parts(self.layers, self.activation, output)
        full = {
            **header,
            "policy": self.name,
            "network": network,
            "observation": self.observation,
            "normalization": None,
        }
        if self.normalizer is not None:
            tensors["obs_mean"] = self.normalizer.mean
            tensors["obs_var"] = self.normalizer.var
            full["normalization"] = {"clip": self.normalizer.clip, "epsilon": self.normalizer.epsilon}
        return save_policy_file(path, tensors, full)

    @classmethod
    def load(cls, path: str | Path) -> MlpPolicy:
        """The policy saved at `path` (see socialzoo.env.policy_file for the checks).

        Raises:
            PolicyFileError: not a policy file, or not an MLP policy, or an inconsistent one (naming
                the file): random bytes, a truncated file and a file of another kind included.
        """
        tensors, header = read_policy_file(path)
        network = header["network"]
        try:
            weights = mlp_layers(tensors, network, OUTPUTS)
            normalizer = None
            norm = header.get("normalization")
            if norm is not None:
                normalizer = ObservationNormalizer(
                    tensors["obs_mean"], tensors["obs_var"], float(norm["clip"]), float(norm["epsilon"])
                )
            policy = cls(
                str(header["policy"]),
                weights,
                str(network["activation"]),
                header["observation"],
                normalizer,
                header,
            )
        except (KeyError, TypeError, ValueError) as err:
            raise PolicyFileError(f"{path}: {err}") from None
        policy.loaded_from(path)
        return policy


def without_normalisation(path: str | Path, out: str | Path) -> Path:
    """The policy file at `path` written to `out` without its observation normalisation: the
    network fed raw observations, as the reference code evaluated PPO (SPEC section 11,
    socialzoo.env.quirks.ReferenceQuirks.ppo_eval_without_normalisation). The header records it
    ("evaluated_without_normalisation": true); a file without normalisation is copied as it is.

    Raises:
        PolicyFileError: `path` is not an MLP policy file.
    """
    policy = MlpPolicy.load(path)
    header = {**policy.header, "evaluated_without_normalisation": True}
    policy.normalizer = None
    return policy.save(out, header)


def evaluation_file(name: str, path: str | Path, quirks: Any, folder: str | Path) -> Path:
    """The file to evaluate learned policy `name` from under an env config's `quirks`
    (socialzoo.env.quirks.ReferenceQuirks): `path` itself, or, for PPO with
    ppo_eval_without_normalisation on, its copy without normalisation in `folder`
    (<stem>.unnormalised.safetensors)."""
    path = Path(path)
    if name != "ppo" or not getattr(quirks, "ppo_eval_without_normalisation", False):
        return path
    Path(folder).mkdir(parents=True, exist_ok=True)
    return without_normalisation(path, Path(folder) / f"{path.stem}.unnormalised{path.suffix}")
