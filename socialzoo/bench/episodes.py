"""Episodes of one policy on a task's fixed cases, batched: every row plays one case at a time and
takes the next pending case when its episode ends, so N cases cost about N / B episodes of wall
time. Any task (socialzoo.env.tasks) and any policy with act(obs, core) serve; the results are the
task's episode metrics, per case.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from socialzoo.env.tasks import make_task

# A policy: (robot 0's observations (B, D), the task's core) -> actions (B,) or (B, ...).
Actor = Callable[[np.ndarray, Any], np.ndarray]


def play_cases(
    task: Any,
    act: Actor,
    split: str,
    indices: Sequence[int],
    batch_size: int = 100,
    *,
    config: Any = None,
    on_episodes: Callable[[list[dict[str, Any]]], None] | None = None,
    **task_kwargs: Any,
) -> list[dict[str, Any]]:
    """Play `act` on cases `indices` of a split of a one-robot task; the episodes in case order.

    Args:
        task: the task's registry name, "module:Class" path or class.
        act: the policy.
        split: a case split of the task (Task.case_splits: "val", "test", ...).
        indices: the cases to play.
        batch_size: rows stepped together (at most one per case).
        config: the task's config (None: its defaults).
        on_episodes: called with the episodes that ended at each step, as they end.
        **task_kwargs: the task's plain config overrides.

    Returns:
        One metrics dict per case (the task's episode metrics with "case" and "seed"), in the
        order of `indices`.

    Raises:
        ValueError: no case, a case twice, a split the task lacks or a case outside it, a task
            with several robots.
    """
    todo = [int(k) for k in indices]
    if not todo:
        raise ValueError("play_cases: no case to play")
    if len(set(todo)) != len(todo):
        raise ValueError("play_cases: a case is named twice")
    rows = min(batch_size, len(todo))
    env = make_task(task, rows, config, **task_kwargs)
    if env.num_robots != 1:
        raise ValueError(f"play_cases: fixed cases are played by one robot, got num_robots={env.num_robots}")
    shape = (rows, 1) + tuple(env.action_space.shape or ())
    idle = np.asarray(env.idle_action())
    playing = np.array(todo[:rows])
    seeds = np.zeros(rows, dtype=np.uint64)
    seeds[:] = env.reset(np.arange(rows), {"split": split, "cases": playing})
    next_case = rows
    active = np.ones(rows, dtype=bool)
    episodes: dict[int, dict[str, Any]] = {}
    while active.any():
        observations = env.observations()
        actions = np.array(act(observations[:, 0], env.core), copy=True)  # type: ignore[attr-defined]
        actions = actions.reshape(shape)
        actions[~active] = idle  # rows out of cases stand still
        step = env.step(actions)
        ended = np.flatnonzero(active & (step.terminated[:, 0] | step.truncated[:, 0]))
        if len(ended) == 0:
            continue
        done = []
        for row, summary in zip(ended.tolist(), env.episode_metrics(ended), strict=True):
            case = int(playing[row])
            episodes[case] = {"case": case, "seed": int(seeds[row]), **summary}
            done.append(episodes[case])
        if on_episodes is not None:
            on_episodes(done)
        refill = []
        for row in ended.tolist():
            if next_case < len(todo):
                playing[row] = todo[next_case]
                next_case += 1
                refill.append(row)
            else:
                active[row] = False
        if refill:
            seeds[refill] = env.reset(np.array(refill), {"split": split, "cases": playing[refill]})
        # Finished rows keep stepping (their results are no longer read) until all are done.
    return [episodes[k] for k in todo]
