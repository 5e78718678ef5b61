"""Demonstrations as the imitation trainers use them: the first N transitions of a recording."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.agents.demonstrations import DemonstrationError, load_demonstrations
from socialzoo.nav.subpolicies import NUM_ACTIONS


@dataclass(frozen=True)
class DemoSteps:
    """A prefix of a demonstration recording.

    Attributes:
        path: the recording.
        obs: (N, D) float32 observations the demonstrator acted on.
        action: (N,) int64 its sub-policy indices.
        episodes: number of episodes the prefix touches.
        map: the map the demonstrations were recorded on.
        observation: the env's observation config (plain dict) of the recording.
        metadata: the recording's metadata.
    """

    path: Path
    obs: np.ndarray
    action: np.ndarray
    episodes: int
    map: str
    observation: dict[str, Any]
    metadata: dict[str, Any]

    def __len__(self) -> int:
        return len(self.action)

    def one_hot(self) -> np.ndarray:
        """(N, 4) float32 one-hot actions."""
        return np.eye(NUM_ACTIONS, dtype=np.float32)[self.action]

    def record(self) -> dict[str, Any]:
        """What a training record says about the data (plain JSON)."""
        config = self.metadata.get("config", {})
        return {
            "file": str(self.path),
            "steps": len(self),
            "episodes": self.episodes,
            "map": self.map,
            "policy": config.get("policy"),
            "base_seed": config.get("base_seed"),
            "config_hash": self.metadata.get("config_hash"),
        }


def check_steps(path: str | Path, total: int, steps: int, what: str = "demonstration steps") -> None:
    """Refuse `steps` asked of a recording at `path` that holds `total`.

    Raises:
        socialzoo.agents.demonstrations.DemonstrationError: steps > total (naming the file and both
            counts).
    """
    if steps > total:
        raise DemonstrationError(
            f"{path} holds {total} {what}, {steps} asked; record more episodes "
            f"(`socialzoo demos --episodes N --out {path}`) or ask for fewer steps"
        )


def load_demo_steps(path: str | Path, steps: int | None = None) -> DemoSteps:
    """The first `steps` transitions (all when None) of the recording at `path`.

    The LfD experiment trains every size on a prefix of ONE recording (the paper's sizes 155,400 / 116,600 /
    77,700 / 38,800 / 3,500 of about 155,000 Ref steps), so a smaller set is always part of a larger one. The
    recording's metadata says which map and observation layout it was made on; trainers build their env and
    their policy header from it.

    Raises:
        ValueError: `steps` < 1.
        socialzoo.agents.demonstrations.DemonstrationError: an unreadable file, one that holds fewer
            steps than asked (naming the file and both counts), or one whose actions are not
            sub-policy indices.
    """
    path = Path(path)
    arrays, meta = load_demonstrations(path)
    total = len(arrays["action"])
    if steps is None:
        steps = total
    if total == 0:
        raise DemonstrationError(f"{path} holds no demonstration steps")
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise ValueError(f"{path}: demonstration steps must be an int >= 1, got {steps!r}")
    check_steps(path, total, steps)
    action = arrays["action"][:steps].astype(np.int64)
    if action.min() < 0 or action.max() >= NUM_ACTIONS:
        raise DemonstrationError(f"{path}: actions outside 0..{NUM_ACTIONS - 1}")
    env = meta.get("env_config", {})
    return DemoSteps(
        path=path,
        obs=arrays["obs"][:steps].astype(np.float32),
        action=action,
        episodes=len(np.unique(arrays["episode"][:steps])),
        map=str(env.get("map", meta.get("config", {}).get("map", "gdc1"))),
        observation=dict(env.get("observation", {})),
        metadata=meta,
    )
