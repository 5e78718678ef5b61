"""Shrinking a batched core to some of its rows while their episodes run on, so that an evaluation's
tail (after its queue of episodes ran dry) steps only rows that still have one."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from socialzoo.env.core import BatchedCore
from socialzoo.nav.navigator import GlobalPlans


def compact_core(core: BatchedCore, rows: Sequence[int] | np.ndarray) -> BatchedCore:
    """A new core of len(rows) rows that continues the episodes of `core`'s `rows`, in that order.

    Carried over, per row: the world state, the global plans and goals, the navigator's recovery
    state, the carrot, the done flags, visibility, the people's bookkeeping so far, recorded people
    and the scripts' state.
    The sight-line cache starts empty: it only saves work (a full test gives the same answers).
    `core` itself is left as it was.

    A row's episode does not depend on the other rows of its batch (every kernel loops per world
    in a fixed order), so a compacted core continues each kept episode exactly as the full one
    would. A task compacts its own per-row arrays beside it (Task.compact).

    Args:
        core: a core whose rows have all been reset from scenarios.
        rows: distinct rows of `core` to keep.

    Returns:
        The compacted core (same configs and map object).

    Raises:
        ValueError: no rows, a repeated row or one outside 0..B-1.
        RuntimeError: `core` was never reset.
    """
    index = np.asarray(rows, dtype=np.intp).reshape(-1)
    b = core.batch_size
    if index.size == 0 or np.any((index < 0) | (index >= b)) or len(np.unique(index)) != index.size:
        raise ValueError(f"compact_core: rows must be distinct rows of 0..{b - 1}, got {index.tolist()}")
    scenarios = [s for s in (core.scenarios[i] for i in index) if s is not None]
    if core.state is None or len(scenarios) != len(index):
        raise RuntimeError("compact_core: the core was never reset")
    navigator = core.navigator
    new = BatchedCore(
        len(index),
        core.num_robots,
        core.max_humans,
        core.world,
        core.walls,
        m=core.map,
        people=core.people.config,
        planner=core.planner,
        recovery=None if navigator is None else navigator.recovery,
        sight_lines=core.sight is not None,
        robot_visible=core.robot_visible,
        contacts_in_step=core.replay.contacts_in_step,
    )
    # A reset sets up every part of a row; the running episode then overwrites what it changed.
    new.reset_rows(np.arange(len(index)), scenarios)
    new.state = core.state.rows(index)
    if navigator is not None:
        assert new.navigator is not None  # built from the same planner as the core's
        plans = navigator.plans
        new.navigator.plans = GlobalPlans(
            paths=plans.paths[index].copy(), lengths=plans.lengths[index].copy()
        )
        copy_rows(navigator, new.navigator, index, b)  # goals, route length left, rerouted
        # Recovery under way (progress, back-off time left, avoided edges): without it a kept
        # robot that was backing off or waiting for progress started over after compaction.
        copy_rows(navigator.recovery_state, new.navigator.recovery_state, index, b)
    new.carrot = core.carrot[index].copy()
    new.done = core.done[index].copy()
    new.visible = core.visible[core.robot_rows(index)].copy()
    # The people's side: counterfactual rows and the people's metrics so far; recorded people;
    # scripted people and doors (who was released, which doors closed). The recorded rows' bank of
    # recordings is the reset's: it holds the kept rows' recordings, and they point there.
    new.people = core.people.rows(index)
    copy_rows(core.replay, new.replay, index, b)
    copy_rows(core.script, new.script, index, b)
    return new


def copy_rows(source: Any, target: Any, index: np.ndarray, size: int) -> None:
    """Set every array attribute of `target` to rows `index` (copies) of `source`'s, each of which
    must have `size` rows: reading them all keeps a new per-row array from being forgotten here.

    Raises:
        RuntimeError: an array attribute that is not per row, naming it.
    """
    for name, value in vars(source).items():
        if isinstance(value, np.ndarray):
            if value.shape[:1] != (size,):
                raise RuntimeError(f"compaction: {type(source).__name__}.{name} is not a per-row array")
            setattr(target, name, value[index].copy())
