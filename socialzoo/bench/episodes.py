"""Episodes of one policy on a task's fixed cases, through the evaluation runner of every task
(socialzoo.bench.runner.BatchedRunner with a CaseSet)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from socialzoo.env.gym_env import robot_row
from socialzoo.env.tasks import make_task

# A policy: (robot 0's observations (B, D), or a dict of (B, ...) for a Dict space, the task) ->
# actions (B,) or (B, ...).
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
    guideline_metrics: bool = False,
    **task_kwargs: Any,
) -> list[dict[str, Any]]:
    """Play `act` on cases `indices` of a split of a one-robot task; the episodes in case order.

    Every row plays one case at a time and takes the next pending case when its episode ends, so N
    cases cost about N / B episodes of wall time. Any task (socialzoo.env.tasks) and any policy with
    act(obs, task) serve.

    Args:
        task: the task's registry name, "module:Class" path or class.
        act: the policy.
        split: a case split of the task (Task.case_splits: "val", "test", ...).
        indices: the cases to play.
        batch_size: rows stepped together (at most one per case).
        config: the task's config (None: its defaults).
        on_episodes: called with the episodes that ended at each step, as they end.
        guideline_metrics: add the guidelines' Table I metrics (`gl_*`) to every episode.
        **task_kwargs: the task's plain config overrides.

    Returns:
        One metrics dict per case (the task's episode metrics with "case" and "seed"), in the
        order of `indices`.

    Raises:
        ValueError: no case, a case twice, a split the task lacks or a case outside it, a task
            with several robots.
    """
    from socialzoo.bench.runner import BatchedRunner, CaseSet, RunSpec, Trial

    todo = [int(k) for k in indices]
    if not todo:
        raise ValueError("play_cases: no case to play")
    if len(set(todo)) != len(todo):
        raise ValueError("play_cases: a case is named twice")
    probe = make_task(task, 1, config, **task_kwargs)
    if probe.num_robots != 1:
        raise ValueError(
            f"play_cases: fixed cases are played by one robot, got num_robots={probe.num_robots}"
        )
    splits = probe.case_splits()
    if split not in splits:
        raise ValueError(f"{probe.name}: options split must be one of {sorted(splits)}, got {split!r}")
    outside = [k for k in todo if not 0 <= k < splits[split]]
    if outside:
        raise ValueError(f"{probe.name}: the {split} split holds {splits[split]} cases; got {outside}")
    name = f"{probe.name}-{split}"
    path = task if isinstance(task, str) else f"{task.__module__}:{task.__qualname__}"
    spec = RunSpec(
        test_sets={name: CaseSet(path, split, splits[split], name)},
        env_configs={name: probe.config},
        policies={"policy": {}},
        batch_size=batch_size,
        guideline_metrics=guideline_metrics,
    )
    episodes: dict[int, dict[str, Any]] = {}

    def deliver(results: list[Any]) -> None:
        done = [{"case": r.trial.index, "seed": r.seed, **r.metrics} for r in results]
        episodes.update((e["case"], e) for e in done)
        if on_episodes is not None:
            on_episodes(done)

    runner = BatchedRunner(spec, stack_policies=False, given={"policy": _RobotZero(act)})
    runner.run([Trial("policy", name, k) for k in todo], on_results=deliver)
    return [episodes[k] for k in todo]


class _RobotZero:
    """A policy of robot 0's observations (B, D) as the runner's policy of (B, R, D) ones (a Dict
    observation's arrays each sliced alike)."""

    reads_core = True

    def __init__(self, act: Actor) -> None:
        self.act_zero = act

    def act(self, observations: Any, task: Any = None) -> np.ndarray:
        actions = np.asarray(self.act_zero(robot_row(observations, slice(None)), task))
        return actions.reshape((actions.shape[0], 1) + actions.shape[1:])
