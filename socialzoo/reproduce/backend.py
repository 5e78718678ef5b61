"""Independent tasks (trainings, every seed of every learner) run side by side: in `workers` local processes, or as
Ray tasks; evaluations have their own paths (socialzoo.bench.runner.evaluate)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Any

from socialzoo.bench.runner import BACKENDS, Backend, check_backend

logger = logging.getLogger(__name__)

__all__ = ["BACKENDS", "Backend", "check_backend", "run_tasks"]


def run_tasks(
    function: Callable[[Any], Any], inputs: Sequence[Any], *, backend: str = "local", workers: int = 2
) -> list[Any]:
    """[function(x) for x in inputs]: on "local", in this process (1 worker or 1 input) or in
    `workers` spawned processes; on "ray", as Ray tasks (one CPU each).

    `function` must be importable by name (a module-level function) and the inputs picklable.
    Each task stores its own result as it finishes (a training run folder), so when one fails or
    the run is interrupted, the finished ones are kept; the first error is raised after the others
    ended.

    Each training uses one CPU thread (the trainers' `threads`), so on the local backend `workers`
    processes train `workers` policies at once (socialzoo.bench.runner.spawn_pool). A Ray already
    initialised (a cluster, or `ray.init(num_cpus=2)` in a test) is used as it is; otherwise a local
    Ray with `workers` CPUs is started and shut down after, its workers at the usual priority
    (socialzoo.bench.runner.ray_session).
    """
    check_backend(backend)
    if len(inputs) <= 1 or (backend == "local" and workers <= 1):
        return [function(x) for x in inputs]
    if backend == "local":
        return _run_local(function, inputs, workers)
    import ray

    from socialzoo.bench.runner import ray_session

    with ray_session(workers):
        task = ray.remote(num_cpus=1, max_retries=0)(function)
        refs = [task.remote(x) for x in inputs]
        try:
            ray.wait(refs, num_returns=len(refs))
        except BaseException:
            for ref in refs:
                ray.cancel(ref, force=True)
            raise
        return [ray.get(ref) for ref in refs]


def _run_local(function: Callable[[Any], Any], inputs: Sequence[Any], workers: int) -> list[Any]:
    """The inputs in min(workers, len(inputs)) spawned processes, results in input order."""
    import os
    from concurrent.futures import wait

    from socialzoo.bench.runner import exit_with_parent, spawn_pool

    # A worker ends when this process is killed outright (it would otherwise train on, then wait forever).
    with spawn_pool(min(workers, len(inputs)), exit_with_parent, (os.getpid(),)) as pool:
        futures = [pool.submit(function, x) for x in inputs]
        wait(futures)
        return [f.result() for f in futures]
