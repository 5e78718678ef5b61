"""Shrinking a batched env core to some of its rows while their episodes run on, so that an
evaluation's tail (after its queue of episodes ran dry) steps only rows that still have one.

A row's episode does not depend on the other rows of its batch (every kernel loops per world in
a fixed order), so a compacted core continues each kept episode exactly as the full one would.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from socialzoo.env.core import SocialNavCore
from socialzoo.nav.navigator import GlobalPlans

# Per batch row (leading axis B) arrays of the core that a step reads or writes.
_CORE_ROW_ARRAYS = ("carrot", "prev_action", "target_human", "done", "obs")


def compact_core(core: SocialNavCore, rows: Sequence[int] | np.ndarray) -> SocialNavCore:
    """A new core of len(rows) rows that continues the episodes of `core`'s `rows`, in that order.

    Carried over, per row: the world state, the global plans and goals, the carrot, previous
    action, followed human, done flags, observations, visibility and the episode metrics so far.
    The sight-line cache starts empty: it only saves work (a full test gives the same answers).
    `core` itself is left as it was.

    Args:
        core: a core whose rows have all been reset.
        rows: distinct rows of `core` to keep.

    Returns:
        The compacted core (same config and map object).

    Raises:
        ValueError: no rows, a repeated row or one outside 0..B-1.
        RuntimeError: `core` was never reset.
    """
    index = np.asarray(rows, dtype=np.intp).reshape(-1)
    b, r = core.batch_size, core.num_robots
    if index.size == 0 or np.any((index < 0) | (index >= b)) or len(np.unique(index)) != index.size:
        raise ValueError(f"compact_core: rows must be distinct rows of 0..{b - 1}, got {index.tolist()}")
    robot_rows = (index[:, None] * r + np.arange(r)).reshape(-1)
    scenarios = [s for s in (core.scenarios[i] for i in index) if s is not None]
    if core.state is None or len(scenarios) != len(index):
        raise RuntimeError("compact_core: the core was never reset")
    new = SocialNavCore(core.config, len(index), map_data=core.map)
    # A reset sets up every part of a row; the running episode then overwrites what it changed.
    new.reset_rows(np.arange(len(index)), scenarios)
    new.state = core.state.rows(index)
    plans = core.navigator.plans
    new.navigator.plans = GlobalPlans(paths=plans.paths[index].copy(), lengths=plans.lengths[index].copy())
    new.navigator.goals = core.navigator.goals[index].copy()
    # The navigator's other per-row state (route length left, progress and recovery).
    for name, value in vars(core.navigator).items():
        if isinstance(value, np.ndarray) and name != "goals":
            if value.shape[:1] != (b,):
                raise RuntimeError(f"compact_core: Navigator.{name} is not a per-row array")
            setattr(new.navigator, name, value[index].copy())
    for name in _CORE_ROW_ARRAYS:
        setattr(new, name, getattr(core, name)[index].copy())
    new.visible = core.visible[robot_rows].copy()
    if core.human_obs is not None:
        new.human_obs = core.human_obs[index].copy()
    # The people's side: counterfactual rows and the people's metrics so far.
    new.people = core.people.rows(index)
    # Every array of the metrics is per robot row (B * R); reading them all keeps a new
    # running metric from being forgotten here.
    for name, value in vars(core.metrics).items():
        if isinstance(value, np.ndarray):
            if value.shape[:1] != (b * r,):
                raise RuntimeError(f"compact_core: EpisodeMetrics.{name} is not a per-row array")
            setattr(new.metrics, name, value[robot_rows].copy())
    return new
