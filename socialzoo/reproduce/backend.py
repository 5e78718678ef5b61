"""Independent tasks (trainings) run here one after another, or as Ray tasks side by side.

Evaluations have their own Ray path (socialzoo.bench.runner.evaluate with backend="ray"); this
module spreads the trainings. A Ray already initialised (a cluster, or `ray.init(num_cpus=2)` in a
test) is used as it is; otherwise a local Ray with `workers` CPUs is started and shut down after.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Any, Literal

logger = logging.getLogger(__name__)

Backend = Literal["local", "ray"]
BACKENDS: tuple[str, ...] = ("local", "ray")


def check_backend(backend: str) -> str:
    """`backend`, or ValueError naming it and the known ones."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    return backend


def run_tasks(
    function: Callable[[Any], Any], inputs: Sequence[Any], *, backend: str = "local", workers: int = 2
) -> list[Any]:
    """[function(x) for x in inputs], locally in order or as Ray tasks (one CPU each).

    Each task stores its own result as it finishes (a training run folder), so when one fails or
    the run is interrupted, the finished ones are kept; the first error is raised after the others
    ended.
    """
    check_backend(backend)
    if backend == "local" or len(inputs) <= 1:
        return [function(x) for x in inputs]
    import ray

    started = False
    if not ray.is_initialized():
        ray.init(num_cpus=workers, include_dashboard=False, logging_level=logging.WARNING)
        started = True
    try:
        task = ray.remote(num_cpus=1, max_retries=0)(function)
        refs = [task.remote(x) for x in inputs]
        try:
            ray.wait(refs, num_returns=len(refs))
        except BaseException:
            for ref in refs:
                ray.cancel(ref, force=True)
            raise
        return [ray.get(ref) for ref in refs]
    finally:
        if started:
            ray.shutdown()
