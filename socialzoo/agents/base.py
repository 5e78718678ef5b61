"""The Policy protocol every baseline implements: a name, and actions for a batch of observations."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    from socialzoo.env.tasks.base import Task


@runtime_checkable
class Policy(Protocol):
    """A policy over the benchmark's discrete actions (0 GoAlone, 1 Halt, 2 Follow, 3 Pass).

    Attributes:
        name: the policy's registry name (socialzoo.agents.POLICIES), e.g. "ref".

    A policy may also set `reads_core = False` to say that its actions depend on the observations
    alone (row by row): runners then give it only the rows it acts for.
    """

    name: str

    def act(self, obs: np.ndarray, task: Task | None = None) -> np.ndarray:
        """Actions for a batch of observations.

        Args:
            obs: (B, D) or (B, R, D) float32 robot observations (socialzoo.env.observation).
            task: the task the observations come from (socialzoo.env.tasks), or None. Engineered
                policies may read what the robots are allowed to see from it (its core's world
                state, sight and carrots); learned policies ignore it.

        Returns:
            int64 actions of shape obs.shape[:-1]: (B,) or (B, R).
        """
        ...

    def config(self) -> dict[str, Any]:
        """The policy's parameters as plain JSON (hashed with the env config by the results store)."""
        ...


@runtime_checkable
class LoadablePolicy(Policy, Protocol):
    """A learned policy: it also loads itself from a file written by its trainer."""

    @classmethod
    def load(cls, path: str | Path) -> LoadablePolicy:
        """The policy saved at `path`."""
        ...


def check_observations(obs: np.ndarray, who: str) -> np.ndarray:
    """Validate a batch of observations: (B, D) or (B, R, D) numbers; returns it as an array.

    Raises:
        ValueError: naming `who` and the bad shape or dtype.
    """
    obs = np.asarray(obs)
    if obs.ndim not in (2, 3):
        raise ValueError(f"{who}: observations must have shape (B, D) or (B, R, D), got {obs.shape}")
    if obs.dtype.kind not in "fiu":
        raise ValueError(f"{who}: observations must be numbers, got dtype {obs.dtype}")
    return obs


def policy_config(policy: Any) -> dict[str, Any]:
    """A policy's `config()`, or {} for a policy that does not define one."""
    method = getattr(policy, "config", None)
    return dict(method()) if callable(method) else {}
