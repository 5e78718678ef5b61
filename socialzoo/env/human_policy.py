"""Learned human policies at inference: shared-parameter walkers read from a policy file, run in numpy."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.core.validation import check_choice, check_number
from socialzoo.env.human_agents import human_mirror_signs, human_observation_size
from socialzoo.env.policy_file import (
    FileNetwork,
    PolicyFileError,
    mlp_layers,
    mlp_parts,
    read_policy_file,
    save_policy_file,
)

# The "policy" entry of a learned human policy file's header.
POLICY_NAME = "learned_humans"
ACTION_FRAMES = ("world", "human")


class LearnedHumanPolicy(FileNetwork):
    """Deterministic actions of learned humans from a multilayer perceptron.

    A human policy maps each learned human's observation (socialzoo.env.human_agents, (..., D_h))
    to its action, a desired velocity in [-1, 1]^2 times its preferred speed and the action scale
    the policy was trained with (EnvConfig.human_action_scale), in the frame it was trained with
    (EnvConfig.human_action_frame). Every human of a world uses the same network. The file is a
    socialzoo policy file (safetensors weights plus a JSON header, no pickled code): the layers of
    the network that gives the action's pre-tanh mean, and the observation normalisation it was
    trained with. A mirror-symmetric policy (no handedness) averages the network over the
    situation and its mirror image (socialzoo.env.human_agents.human_mirror_signs), as it was
    trained. People specs name a learned human policy as "learned:PATH" (the "learned" model of
    socialzoo.humans.models; a file written by `socialzoo train humans` or `socialzoo train
    cotrain`).

    Args:
        weights: (W_i (out, in), b_i (out,)) per layer, torch's Linear convention; the last layer
            gives the 2 pre-tanh action means.
        activation: hidden-layer activation, a key of socialzoo.env.policy_file.ACTIVATIONS.
        obs_loc: (D,) observation offset; the network sees (obs - loc) / scale.
        obs_scale: (D,) observation scale.
        num_neighbours: EnvConfig.num_human_neighbours of the observations it was trained on.
        action_frame: EnvConfig.human_action_frame it was trained with ("world" or "human").
        action_scale: EnvConfig.human_action_scale it was trained with (files written before
            the scale existed were trained with 1).
        mirror_symmetric: the pre-tanh mean is (f(obs) + m f(mirror(obs))) / 2, with m = (1, -1):
            the same behaviour on the left and the right (socialzoo.train.mappo.MirrorSymmetric).
        learned_forces: whether the social and wall forces act on the people it walks, as in the
            world it was trained in (HumanConfig.learned_forces; the header's dynamics section,
            true for files written before it existed). `socialzoo train people-bc` trains without
            them: the network's desired velocity alone moves its people.
        relaxation_time: the relaxation time of the people it walks, s, as in the world it was
            trained in (HumanConfig.learned_relaxation_time; the header's dynamics section), or
            None (files written before it existed): the walking world's own.
        header: the policy file's header (kept for config() and reports).

    Raises:
        ValueError: layers that do not chain, a wrong output size, normalisation of the wrong
            size or not finite and positive, an unknown activation or frame, a scale not > 0.
    """

    name = "learned"

    def __init__(
        self,
        weights: Sequence[tuple[np.ndarray, np.ndarray]],
        activation: str,
        obs_loc: np.ndarray,
        obs_scale: np.ndarray,
        num_neighbours: int,
        action_frame: str,
        action_scale: float = 1.0,
        header: dict[str, Any] | None = None,
        *,
        mirror_symmetric: bool = False,
        learned_forces: bool = True,
        relaxation_time: float | None = None,
    ) -> None:
        super().__init__("LearnedHumanPolicy", weights, activation, header)
        check_choice("LearnedHumanPolicy", "action_frame", action_frame, ACTION_FRAMES)
        check_number("LearnedHumanPolicy", "action_scale", action_scale, low=0, low_open=True)
        check_number(
            "LearnedHumanPolicy", "relaxation_time", relaxation_time, low=0, low_open=True, allow_none=True
        )
        if self.layers[-1][0].shape[0] != 2:
            raise ValueError(
                f"LearnedHumanPolicy: the last layer gives {self.layers[-1][0].shape[0]} outputs, not 2"
            )
        size = human_observation_size(num_neighbours)
        if self.input_size != size:
            raise ValueError(
                f"LearnedHumanPolicy: a network of {self.input_size} inputs for observations of {size} "
                f"({num_neighbours} neighbours)"
            )
        self.obs_loc = np.asarray(obs_loc, dtype=np.float32)
        self.obs_scale = np.asarray(obs_scale, dtype=np.float32)
        if self.obs_loc.shape != (size,) or self.obs_scale.shape != (size,):
            raise ValueError(
                f"LearnedHumanPolicy: normalisation of shapes {self.obs_loc.shape}, {self.obs_scale.shape}; "
                f"expected ({size},)"
            )
        if not (
            np.isfinite(self.obs_loc).all()
            and np.isfinite(self.obs_scale).all()
            and (self.obs_scale > 0).all()
        ):
            raise ValueError("LearnedHumanPolicy: normalisation must be finite with scale > 0")
        self.num_neighbours = int(num_neighbours)
        self.action_frame = action_frame
        self.action_scale = float(action_scale)
        self.mirror_symmetric = bool(mirror_symmetric)
        self.learned_forces = bool(learned_forces)
        self.relaxation_time = None if relaxation_time is None else float(relaxation_time)
        self._mirror = human_mirror_signs(self.num_neighbours)

    def env_overrides(self) -> dict[str, Any]:
        """EnvConfig fields the observations and actions of this policy need."""
        return {
            "num_human_neighbours": self.num_neighbours,
            "human_action_frame": self.action_frame,
            "human_action_scale": self.action_scale,
        }

    def act(self, obs: np.ndarray) -> np.ndarray:
        """float64 actions (..., 2) in [-1, 1] for observations (..., D).

        Acting is deterministic: tanh of the network's pre-tanh mean (the mode of the TanhNormal
        the trainer samples from, before the tanh).
        """
        obs = np.asarray(obs)
        if obs.ndim < 1 or obs.shape[-1] != self.input_size or obs.dtype.kind not in "fiu":
            raise ValueError(
                f"LearnedHumanPolicy.act: observations of shape {obs.shape} and dtype {obs.dtype}; expected "
                f"numbers of width {self.input_size} ({self.num_neighbours} neighbours)"
            )
        lead = obs.shape[:-1]
        flat = obs.reshape(-1, self.input_size).astype(np.float32)
        mean = self._mean(flat)
        if self.mirror_symmetric:
            mean = 0.5 * (mean + self._mean(flat * self._mirror) * np.array([1.0, -1.0], dtype=np.float32))
        return np.tanh(mean.astype(np.float64)).reshape(*lead, 2)

    def _mean(self, obs: np.ndarray) -> np.ndarray:
        """(N, 2) the network's pre-tanh mean for (N, D) raw observations."""
        return self.forward((obs - self.obs_loc) / self.obs_scale)

    # ---------------------------------------------------------------- files
    def save(self, path: str | Path, env_id: str, training: dict[str, Any]) -> Path:
        """Write the policy file.

        Args:
            path: the file (parent folders created).
            env_id: the env id and version the policy was trained on ("...-vN").
            training: plain-JSON record of how it was made (algorithm, command, seed, frames).
        """
        tensors, network = mlp_parts(self.layers, self.activation, "tanh_mean")
        tensors = {"obs_loc": self.obs_loc, "obs_scale": self.obs_scale, **tensors}
        header = {
            "policy": POLICY_NAME,
            "network": network | {"mirror_symmetric": self.mirror_symmetric},
            "observation": {
                "kind": "learned_human",
                "num_human_neighbours": self.num_neighbours,
                "size": self.input_size,
                "action_frame": self.action_frame,
                "action_scale": self.action_scale,
            },
            "dynamics": {"learned_forces": self.learned_forces}
            | ({} if self.relaxation_time is None else {"relaxation_time": self.relaxation_time}),
            "env_id": env_id,
            "training": training,
        }
        return save_policy_file(path, tensors, header)

    @classmethod
    def load(cls, path: str | Path) -> LearnedHumanPolicy:
        """The policy saved at `path`.

        Raises:
            PolicyFileError: not a learned human policy file, or an inconsistent one (naming it):
                random bytes, a truncated file and a file of another kind included.
        """
        tensors, header = read_policy_file(path)
        try:
            if header["policy"] != POLICY_NAME:
                raise ValueError(
                    f"a {header['policy']!r} policy, not a learned human policy ({POLICY_NAME!r})"
                )
            network, observation = header["network"], header["observation"]
            if not (isinstance(network, dict) and isinstance(observation, dict)):
                raise ValueError("the header's network and observation must be objects")
            weights = mlp_layers(tensors, network, ("tanh_mean",))
            policy = cls(
                weights,
                str(network["activation"]),
                tensors["obs_loc"],
                tensors["obs_scale"],
                int(observation["num_human_neighbours"]),
                str(observation["action_frame"]),
                float(observation.get("action_scale", 1.0)),
                header,
                mirror_symmetric=_flag(header, "network", "mirror_symmetric"),
                learned_forces=_flag(header, "dynamics", "learned_forces", default=True),
                relaxation_time=header.get("dynamics", {}).get("relaxation_time"),
            )
        except (KeyError, TypeError, ValueError) as err:
            raise PolicyFileError(f"{path}: {err}") from None
        policy.loaded_from(path)
        return policy


def _flag(header: dict[str, Any], section: str, name: str, default: bool = False) -> bool:
    """The true/false entry header[section][name] (`default` when absent: files written before it
    existed)."""
    part = header.get(section, {})
    if not isinstance(part, dict):
        raise ValueError(f"the header's {section} must be an object, got {part!r}")
    value = part.get(name, default)
    if not isinstance(value, bool):
        raise ValueError(f"{section}.{name} must be true or false, got {value!r}")
    return value
