"""Evaluation of CrowdNav-task policies on the task's fixed cases (CrowdNav's 100 validation and 500
test cases), batched by the evaluation loop of every task (socialzoo.bench.episodes.play_cases)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from socialzoo.env.crowd_config import CrowdNavConfig
from socialzoo.scenarios.crowd_cases import SPLIT_SIZE, Split

# A CrowdNav policy: (flat observations (B, D), the task) -> actions (B,) or (B, 2).
CrowdActor = Callable[[np.ndarray, Any], np.ndarray]


@dataclass(frozen=True)
class CrowdEvaluation:
    """The result of one policy on fixed cases.

    The summary reports CrowdNav's test metrics (success, collision and timeout rates, navigation time
    of the successful episodes, the frequency of discomfort over all steps) and ours (path length,
    minimum separation, intrusion ratio, returns), each rate with a 95% Wilson interval and each mean
    with a Student-t interval over the cases (socialzoo.bench.stats).

    Attributes:
        split: "val" or "test".
        episodes: one metrics dict per case, in case order (with its "case" index).
        summary: the aggregate (rates, means, intervals).
    """

    split: str
    episodes: list[dict[str, Any]]
    summary: dict[str, Any]


def evaluate_crowd(
    act: CrowdActor,
    config: CrowdNavConfig,
    split: Split = "test",
    cases: int | None = None,
    batch_size: int = 100,
    *,
    indices: Sequence[int] | None = None,
) -> CrowdEvaluation:
    """Run `act` on the first `cases` cases of a split (all of them by default).

    Args:
        act: the policy: flat observations and the task -> actions.
        config: the task (its observation is read in the flat layout whatever config.observation).
        split: "val" or "test".
        cases: how many cases (default the split's size: 100 or 500).
        batch_size: rows stepped together.
        indices: play only these of the first `cases` cases; the result holds them in case order.

    Raises:
        ValueError: a training split, more cases than the split holds, or an index outside them.
    """
    if config.num_robots != 1:
        raise ValueError(
            f"evaluate_crowd: the fixed cases are CrowdNav's one-robot cases, got num_robots={config.num_robots}"
        )
    if split not in SPLIT_SIZE:
        raise ValueError(f"evaluate_crowd: split must be 'val' or 'test', got {split!r}")
    total = SPLIT_SIZE[split] if cases is None else cases
    if not 1 <= total <= SPLIT_SIZE[split]:
        raise ValueError(
            f"evaluate_crowd: {total} cases asked of the {split} split, which holds {SPLIT_SIZE[split]}"
        )
    todo = list(range(total)) if indices is None else sorted({int(k) for k in indices})
    outside = [k for k in todo if not 0 <= k < total]
    if outside:
        raise ValueError(f"evaluate_crowd: case indices must lie in [0, {total}), got {outside}")
    if not todo:
        raise ValueError("evaluate_crowd: no case to play")
    from socialzoo.bench.episodes import play_cases
    from socialzoo.bench.task_benchmark import summarize

    flat = config.replace(observation="flat")
    played = play_cases("crowdnav", act, split, todo, batch_size, config=flat)
    ordered = [{k: v for k, v in e.items() if k != "seed"} for e in played]  # the episodes without their seed
    return CrowdEvaluation(split=split, episodes=ordered, summary=summarize(ordered))
