"""Batched evaluation of policies on fixed test sets: a pool of B env rows works through a queue of trials,
refilling each row as its episode ends, locally over processes or on a Ray cluster."""

from __future__ import annotations

import contextlib
import logging
import math
import multiprocessing
import os
import queue as queue_module
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal

import numpy as np

from socialzoo.agents import Policy, make_policy
from socialzoo.bench.compaction import RunStats
from socialzoo.bench.progress import progress_bar
from socialzoo.core.validation import check_int
from socialzoo.env.config import EnvConfig
from socialzoo.scenarios.scenario_sets import TestSet, get_test_set

logger = logging.getLogger(__name__)

Backend = Literal["local", "ray"]
BACKENDS: tuple[str, ...] = ("local", "ray")


def check_backend(backend: str, where: str = "backend") -> str:
    """`backend`, or ValueError naming `where` (e.g. "BenchmarkConfig.backend"), the value and the
    known ones."""
    if backend not in BACKENDS:
        raise ValueError(f"{where}: unknown backend {backend!r}; known: {', '.join(BACKENDS)}")
    return backend


# Seconds without any result, once every worker has returned, before the run is declared lost.
_DRAIN_TIMEOUT = 60.0
# Tail: shrink the core when at most this share of its rows is live (here and in the drive check,
# socialzoo.bench.drive_check). A compaction costs ~2-3 steps; 0.75 steps 19% fewer tail rows than
# 0.5 (gdc1-quick, B = 64), in 12 compactions instead of 6.
SHRINK = 0.75


@dataclass(frozen=True, order=True)
class Trial:
    """One episode to run: a policy on scenario `index` of a test set.

    Attributes:
        policy: the policy's registry name.
        test_set: the test set's name (a key of RunSpec.test_sets).
        index: the scenario index in the test set.
    """

    policy: str
    test_set: str
    index: int


@dataclass(frozen=True)
class TrialResult:
    """A finished trial.

    Attributes:
        trial: the trial.
        map: the map's name.
        seed: the scenario's seed.
        metrics: the episode's metrics (socialzoo.env.metrics.SUMMARY_KEYS) of robot 0.
    """

    trial: Trial
    map: str
    seed: int
    metrics: dict[str, Any]


@dataclass(frozen=True)
class CaseSet:
    """A task's fixed cases as a test set of the runner (socialzoo.env.tasks: Task.case_splits).

    Attributes:
        task: the task's registry name or "module:Class" path.
        split: the case split ("val", "test", ...).
        count: how many of its cases (the first `count`).
        name: the test set's name in results (default "<task>-<split>").
        map_name: the name results give the world (default the task's).
    """

    __test__: ClassVar[bool] = False  # not a pytest test class

    task: str
    split: str
    count: int
    name: str = ""
    map_name: str = ""

    def __len__(self) -> int:
        return self.count


@dataclass(frozen=True, kw_only=True)
class RunSpec:
    """Everything a worker needs to run trials; plain picklable values.

    Attributes:
        test_sets: test sets by name: the action-selection task's scenario lists (TestSet), or any
            task's fixed cases (CaseSet).
        env_configs: the task config of each test set, by test set name (an EnvConfig for a
            TestSet; the task's config object, or None for its defaults, for a CaseSet).
        policies: make_policy keyword arguments of each policy, by registry name.
        batch_size: env rows stepped together (B).
        human_metrics: add the humans' episode metrics (socialzoo.bench.human_metrics) to every
            trial's metrics.
        guideline_metrics: add the guidelines' Table I metrics (socialzoo.bench.guideline_recorder,
            the `gl_*` names) to every trial's metrics.
        families: set from env_configs: the scenario families they play that this process
            registered (socialzoo.scenarios.catalogue.register_family), which the BatchedRunner
            registers in a worker process that never ran register_family.
    """

    test_sets: Mapping[str, TestSet | CaseSet]
    env_configs: Mapping[str, Any]
    policies: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    batch_size: int = 64
    human_metrics: bool = False
    guideline_metrics: bool = False
    families: tuple[Any, ...] = field(init=False, default=())

    def __post_init__(self) -> None:
        from socialzoo.scenarios.catalogue import added_families

        check_int("RunSpec", "batch_size", self.batch_size, low=1)
        played = (getattr(config, "family", None) for config in self.env_configs.values())
        object.__setattr__(self, "families", added_families(played))
        for name, config in self.env_configs.items():
            if getattr(config, "num_learned_humans", 0):
                raise ValueError(
                    f"RunSpec: env config {name!r} has num_learned_humans = {config.num_learned_humans}, human "
                    "agents that a learner drives; the runner drives none. Learned people are the env's own: "
                    "EnvConfig.people.models = 'learned:PATH' (or a mix)"
                )
        missing = sorted(set(self.test_sets) - set(self.env_configs))
        if missing:
            raise ValueError(f"RunSpec.env_configs lacks the test set(s) {missing}")

    def check(self, trials: Iterable[Trial]) -> None:
        """Raise ValueError naming a trial whose policy or test set the spec does not know."""
        for t in trials:
            if t.test_set not in self.test_sets:
                raise ValueError(
                    f"trial {t}: unknown test set {t.test_set!r}; known: {sorted(self.test_sets)}"
                )
            if t.policy not in self.policies:
                raise ValueError(f"trial {t}: unknown policy {t.policy!r}; known: {sorted(self.policies)}")
            count = len(self.test_sets[t.test_set])
            if not 0 <= t.index < count:
                raise ValueError(f"trial {t}: scenario index outside 0..{count - 1} of {t.test_set!r}")


def env_config_for(test_set: TestSet, **overrides: Any) -> EnvConfig:
    """The benchmark env config of a test set: its map and scenario settings, plus `overrides`
    (EnvConfig.replace keywords, e.g. max_steps=400)."""
    return EnvConfig(map=test_set.map_name, scenario=test_set.cfg).replace(**overrides)


def make_spec(
    policies: Sequence[str] | Mapping[str, Mapping[str, Any]],
    test_sets: Sequence[str | TestSet],
    *,
    batch_size: int = 64,
    env_overrides: Mapping[str, Any] | None = None,
) -> RunSpec:
    """A RunSpec for policies (names, or names -> make_policy kwargs) on test sets (names or objects).

    Policy names are registry names, or "NAME:PATH" for a policy loaded from a file.

    Raises:
        ValueError: an unknown policy name (or a missing file); KeyError: an unknown test set name.
    """
    from socialzoo.agents import check_policy_spec

    kwargs = {p: {} for p in policies} if not isinstance(policies, Mapping) else dict(policies)
    for name in kwargs:
        check_policy_spec(name)
    sets = {}
    for ts in test_sets:
        obj = get_test_set(ts) if isinstance(ts, str) else ts
        sets[obj.name or obj.map_name] = obj
    overrides = dict(env_overrides or {})
    configs = {name: env_config_for(ts, **overrides) for name, ts in sets.items()}
    return RunSpec(test_sets=sets, env_configs=configs, policies=kwargs, batch_size=batch_size)


ResultSink = Callable[[list[TrialResult]], None]
StepHook = Callable[[Any, list[Trial | None], np.ndarray, np.ndarray, Any], None]


class BatchedRunner:
    """Runs trials in this process, B env rows at a time, refilling rows as episodes end.

    Trials are run test set by test set (one task of B rows per test set: the action-selection
    task's scenarios, or any task's fixed cases); within a test set, trials of several
    policies share the batch (each policy acts on the whole batch, its rows take its actions).
    Once no trial is left to start, the core is shrunk to the rows still running whenever a
    quarter of its rows or more have finished (Task.compact, where the task can), so the tail steps
    few finished rows; results are the same either way.

    Args:
        spec: test sets, env configs, policies and batch size.
        compact_tail: shrink the core in the tail (off: finished rows halt until the test set
            is done, as with a step hook, where rows keep their numbers).
        stack_policies: learned policies of one network shape (a run's checkpoints) act as one
            stack (socialzoo.bench.policy_stack.MlpStack: the same actions, one product per
            layer); off: each acts on its own rows.
        given: policy objects by name (anything with act(obs, task)), used instead of building
            those names from the registry (spec.policies must still name them).
    """

    def __init__(
        self,
        spec: RunSpec,
        *,
        compact_tail: bool = True,
        stack_policies: bool = True,
        given: Mapping[str, Any] | None = None,
    ) -> None:
        from socialzoo.scenarios.catalogue import register_family

        for family in spec.families:  # a no-op where they were registered
            register_family(family)
        self.spec = spec
        self.compact_tail = compact_tail
        self.stack_policies = stack_policies
        self.stats = RunStats()
        # Policies given as objects (any act(obs, task)) instead of built from the registry.
        self.given = dict(given or {})
        self._policies: dict[tuple[str, str], Policy] = {}

    def policy(self, name: str, task: str = "action_selection") -> Policy:
        """The policy `name` for a task, built once (or the one given under that name)."""
        if name in self.given:
            return self.given[name]
        if (name, task) not in self._policies:
            self._policies[(name, task)] = make_policy(name, task=task, **self.spec.policies[name])
        return self._policies[(name, task)]

    def run(
        self, trials: Sequence[Trial], on_results: ResultSink | None = None, on_step: StepHook | None = None
    ) -> list[TrialResult]:
        """Run every trial once.

        Args:
            trials: the trials; each is run exactly once, in an order chosen for batching.
            on_results: called with the trials that finished at each step, as they finish.
            on_step: called after every step with (the task, trial of each row or None,
                the observations (B, R, D) the actions were chosen on (a copy), actions (B, R),
                the task's own step record (TaskStep.detail: the action-selection task's
                StepResult)), before finished rows are refilled. With a hook the batch is never
                shrunk, so a row keeps its number for the whole test set.

        Returns:
            The results, in the order of `trials`.
        """
        self.spec.check(trials)
        self.stats = RunStats()
        results: dict[Trial, TrialResult] = {}

        def collect(batch: list[TrialResult]) -> None:
            for r in batch:
                results[r.trial] = r
            if on_results is not None:
                on_results(batch)

        from socialzoo.bench.policy_stack import single_blas_thread

        by_set: dict[str, list[Trial]] = {}
        for t in dict.fromkeys(trials):
            by_set.setdefault(t.test_set, []).append(t)
        with single_blas_thread():  # small products: BLAS threads only wait (policy_stack)
            for name in sorted(by_set):
                self._run_test_set(
                    name, sorted(by_set[name], key=lambda t: (t.index, t.policy)), collect, on_step
                )
        return [results[t] for t in trials]

    def _run_test_set(
        self, name: str, trials: list[Trial], collect: ResultSink, on_step: StepHook | None
    ) -> None:
        from socialzoo.env.tasks import make_task

        test_set = self.spec.test_sets[name]
        config = self.spec.env_configs[name]
        b = min(self.spec.batch_size, len(trials))
        task_name = test_set.task if isinstance(test_set, CaseSet) else "action_selection"
        task = make_task(task_name, b, config)
        world = (test_set.map_name or task.name) if isinstance(test_set, CaseSet) else task.core.map.name  # type: ignore[attr-defined]
        pending = deque(trials)

        def start(rows: list[int], started: list[Trial]) -> np.ndarray:
            """Reset `rows` onto the trials' cases; their scenario seeds."""
            indices = [t.index for t in started]
            if isinstance(test_set, CaseSet):
                options: dict[str, Any] = {"split": test_set.split, "cases": indices}
            else:
                options = {"scenarios": [test_set.scenario(k, task.core.map) for k in indices]}  # type: ignore[attr-defined]
            return task.reset(np.asarray(rows), options)

        row_trial: list[Trial | None] = [pending.popleft() for _ in range(b)]
        seeds = np.zeros(b, dtype=np.uint64)
        seeds[:] = start(list(range(b)), [t for t in row_trial if t is not None])
        humans = self._human_tracker(task)
        if humans is not None:
            humans.reset(np.arange(b), task.world_state)
        table_one = self._guideline_recorder(task)
        shape = tuple(task.action_space.shape or ())
        idle = task.idle_action()
        actions = np.empty((b, task.num_robots) + shape, dtype=np.asarray(idle).dtype)
        done = np.zeros((b, task.num_robots), dtype=bool)
        stacks = self._stacks(dict.fromkeys(t.policy for t in trials), task.name)
        stacked_names = {name for _, index in stacks for name in index}
        compact = self.compact_tail and on_step is None
        stats = self.stats
        while True:
            policy_rows: dict[str, list[int]] = {}
            for row, t in enumerate(row_trial):
                if t is not None:
                    policy_rows.setdefault(t.policy, []).append(row)
            if not policy_rows:
                break
            actions[...] = idle
            observations = task.observations()
            for stack, index in stacks:
                # Several learned policies of one network shape (checkpoints): one product per layer.
                stacked = [(index[name], rows) for name, rows in policy_rows.items() if name in index]
                if not stacked:
                    continue
                stack_rows = np.concatenate([np.asarray(r) for _, r in stacked])
                which = np.concatenate([np.full(len(r), i) for i, r in stacked])
                obs_rows = observations[stack_rows]
                chosen = stack.act(
                    obs_rows.reshape(-1, obs_rows.shape[-1]), np.repeat(which, task.num_robots)
                )
                actions[stack_rows] = chosen.reshape((len(stack_rows), task.num_robots) + shape)
            for policy_name, rows in policy_rows.items():
                if policy_name in stacked_names:
                    continue
                policy = self.policy(policy_name, task.name)
                if getattr(policy, "reads_core", True):
                    chosen = np.asarray(policy.act(observations, task)).reshape(actions.shape)
                    actions[rows] = chosen[rows]
                else:
                    # A policy of observations alone acts on its own rows only: many checkpoints can
                    # share a batch without each one computing every row.
                    own = observations[rows]
                    if isinstance(own, np.ndarray) and own.ndim == 3:  # (rows, R, D): one (rows R, D) batch
                        own = own.reshape(-1, own.shape[-1])
                    actions[rows] = np.asarray(policy.act(own)).reshape((len(rows), task.num_robots) + shape)
            obs = observations.copy() if on_step is not None else observations
            before = task.world_state
            step = task.step(actions)
            done |= step.terminated | step.truncated
            if table_one is not None:
                table_one.record(task, step)
            if humans is not None:
                humans.update(
                    before, task.world_state, step.detail.events.human_blocked, config.dt, done.all(axis=1)
                )
            if pending:
                stats.body_steps += 1
                stats.body_row_steps += task.batch_size
            else:
                stats.tail_steps += 1
                stats.tail_row_steps += task.batch_size
            if on_step is not None:
                on_step(task, row_trial, obs, actions, step.detail if step.detail is not None else step)
            active = np.array([t is not None for t in row_trial])
            finished = np.flatnonzero(active & done.all(axis=1))
            if len(finished) == 0:
                continue
            summaries = task.episode_metrics(finished)
            for recorder in (humans, table_one):
                if recorder is not None:
                    for summary, extra in zip(summaries, recorder.summaries(finished), strict=True):
                        summary.update(extra)
            done_batch = []
            for row, summary in zip(finished.tolist(), summaries, strict=True):
                t = row_trial[row]
                assert t is not None
                done_batch.append(TrialResult(t, world, int(seeds[row]), summary))
            collect(done_batch)
            refill_rows, refill = [], []
            for row in finished.tolist():
                t = pending.popleft() if pending else None
                row_trial[row] = t
                if t is not None:
                    refill_rows.append(row)
                    refill.append(t)
            if refill_rows:
                seeds[refill_rows] = start(refill_rows, refill)
                done[refill_rows] = False
                if humans is not None:
                    humans.reset(np.array(refill_rows), task.world_state)
                if table_one is not None:
                    table_one.reset(np.array(refill_rows), task)
            live = [row for row, t in enumerate(row_trial) if t is not None]
            if table_one is not None:
                table_one.forget(np.array(live, dtype=np.intp))
            if compact and not pending and 0 < len(live) <= SHRINK * len(row_trial):
                smaller = task.compact(np.array(live))
                if smaller is None:
                    continue
                task = smaller
                if humans is not None:
                    humans = humans.rows(live)
                if table_one is not None:
                    table_one = table_one.rows(live)
                row_trial = [row_trial[row] for row in live]
                seeds, done = seeds[live], done[live]
                actions = np.empty((len(live), task.num_robots) + shape, dtype=actions.dtype)
                stats.compactions += 1

    def _stacks(
        self, names: Iterable[str], task: str = "action_selection"
    ) -> list[tuple[Any, dict[str, int]]]:
        """(MlpStack, {policy name: index in it}) for each group of two or more of these policies
        that share a network shape (socialzoo.bench.policy_stack), unless `stack_policies` is off."""
        from socialzoo.bench.policy_stack import MlpStack, stack_key

        if not self.stack_policies:
            return []
        groups: dict[Any, list[str]] = {}
        for name in names:
            key = stack_key(self.policy(name, task))
            if key is not None:
                groups.setdefault(key, []).append(name)
        return [
            (MlpStack([self.policy(n, task) for n in group]), {n: i for i, n in enumerate(group)})  # type: ignore[misc]
            for group in groups.values()
            if len(group) > 1
        ]

    def _guideline_recorder(self, task: Any) -> Any:
        """The Table I recorder of the task's rows (their episodes just started), or None when the
        spec does not ask for the metrics."""
        if not self.spec.guideline_metrics:
            return None
        from socialzoo.bench.guideline_recorder import GuidelineRecorder

        recorder = GuidelineRecorder(task)
        recorder.reset(np.arange(task.batch_size), task)
        return recorder

    def _human_tracker(self, task: Any) -> Any:
        """The humans' episode metrics of an action-selection task's rows, or None when the spec
        does not ask for them."""
        if not self.spec.human_metrics:
            return None
        from socialzoo.bench.human_metrics import HumanEpisodeMetrics

        core = task.core
        world = core.world
        return HumanEpisodeMetrics(
            core.batch_size,
            core.max_humans,
            core.num_robots,
            core.walls,
            world.human_collision_distance,
            world.human.waypoint_radius,
        )


def run_chunk(trials: Sequence[Trial], spec: RunSpec, sink: ResultSink | None = None) -> list[TrialResult]:
    """Run trials in this process with a BatchedRunner (the unit of work of every backend)."""
    return BatchedRunner(spec).run(trials, on_results=sink)


def split_trials(trials: Sequence[Trial], parts: int) -> list[list[Trial]]:
    """Deal trials round-robin into at most `parts` non-empty chunks (similar mixes of policies
    and test sets in every chunk)."""
    ordered = sorted(dict.fromkeys(trials), key=lambda t: (t.test_set, t.index, t.policy))
    parts = max(1, min(parts, len(ordered)))
    return [ordered[i::parts] for i in range(parts)]


# ---------------------------------------------------------------------------- local processes
_WORKER_QUEUE: Any = None


def exit_with_parent(parent_pid: int, interval: float = 1.0) -> None:
    """In a pool's worker process: end the process once `parent_pid` is no longer its parent.

    A pool's worker waits on queues its parent feeds. When the parent is killed outright (SIGKILL,
    the kernel's OOM killer), nothing tells the worker: it finishes the task in hand and then waits
    for the next one forever. A daemon thread checks every `interval` seconds whether the worker
    has been handed to another parent, and ends the process at once if so. Ctrl-C and other
    catchable signals are handled by the parent itself, which ends its workers.

    Args:
        parent_pid: the pid of the process that started the pool (its os.getpid()).
        interval: seconds between checks.
    """

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(interval)
        os._exit(1)

    threading.Thread(target=watch, name="socialzoo-exit-with-parent", daemon=True).start()


def _init_worker(result_queue: Any, parent_pid: int) -> None:
    global _WORKER_QUEUE
    _WORKER_QUEUE = result_queue
    exit_with_parent(parent_pid)


def _chunk(trials: list[Trial], spec: RunSpec, result_queue: Any = None) -> int:
    """A worker's chunk (either backend): its results go to `result_queue`, else to the local process's."""
    run_chunk(trials, spec, sink=(_WORKER_QUEUE if result_queue is None else result_queue).put)
    return len(trials)


@contextlib.contextmanager
def spawn_pool(workers: int, initializer: Callable[..., None], initargs: tuple[Any, ...]) -> Iterator[Any]:
    """A ProcessPoolExecutor of `workers` spawned processes (both backends' local pool: the
    evaluation's and the trainings'), each started with initializer(*initargs).

    Spawned, not forked: the parent may hold threads (torch, tqdm's monitor) that fork would copy
    mid-state. On any exception in the block (Ctrl-C included) the worker processes are ended at
    once, since concurrent.futures offers no way to stop running tasks before Python 3.14
    (ProcessPoolExecutor.terminate_workers): an interrupted run would otherwise wait for every task
    to finish.
    """
    from concurrent.futures import ProcessPoolExecutor

    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(
        max_workers=workers, mp_context=context, initializer=initializer, initargs=initargs
    )
    try:
        yield pool
    except BaseException:
        for process in list(getattr(pool, "_processes", {}).values()):
            process.terminate()
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _evaluate_local(chunks: list[list[Trial]], spec: RunSpec, deliver: ResultSink) -> None:
    if len(chunks) == 1:
        run_chunk(chunks[0], spec, sink=deliver)
        return
    result_queue = multiprocessing.get_context("spawn").Queue()
    with spawn_pool(len(chunks), _init_worker, (result_queue, os.getpid())) as pool:
        futures = [pool.submit(_chunk, chunk, spec) for chunk in chunks]
        _drain(
            sum(len(c) for c in chunks),
            lambda timeout: result_queue.get(timeout=timeout),
            queue_module.Empty,
            lambda: [f for f in futures if f.done()],
            lambda f: f.result(),
            len(futures),
            deliver,
        )


def _drain(
    expected: int,
    get: Callable[[float], list[TrialResult]],
    empty: type[BaseException],
    finished: Callable[[], list[Any]],
    result_of: Callable[[Any], Any],
    num_tasks: int,
    deliver: ResultSink,
) -> None:
    """Deliver results from a queue until `expected` distinct trials arrived; re-raise a failed task's error.

    A trial may arrive twice: Ray runs a chunk again from its start when its worker dies (a task's
    max_retries), so counting results instead of trials would stop before the rerun's new ones.
    """
    arrived: set[Trial] = set()
    idle_since: float | None = None
    while len(arrived) < expected:
        try:
            batch = get(0.1)
        except empty:
            done = finished()
            for task in done:
                result_of(task)  # raises the worker's exception
            if len(done) == num_tasks:
                idle_since = idle_since or time.monotonic()
                if time.monotonic() - idle_since > _DRAIN_TIMEOUT:
                    raise RuntimeError(
                        f"workers finished but only {len(arrived)} of {expected} results arrived"
                    ) from None
            continue
        idle_since = None
        deliver(batch)
        arrived.update(r.trial for r in batch)


# ---------------------------------------------------------------------------- Ray
class RayAddressError(ValueError):
    """A Ray cluster address that nothing answers at; the message names the address."""


# Seconds to wait for a Ray address to accept a connection: a cluster answers in milliseconds,
# while ray.init waits on an unreachable one for minutes before it gives up.
RAY_CONNECT_TIMEOUT = 5.0
# The port Ray listens on when an address names none: the client server's, else the GCS's.
_RAY_PORTS = {"ray": 10001, "": 6379}


def check_ray_address(address: str | None, timeout: float = RAY_CONNECT_TIMEOUT) -> None:
    """Check that a Ray cluster's HOST:PORT or ray://HOST[:PORT] accepts a TCP connection within
    `timeout` seconds and answers it as Ray's servers do (gRPC: an HTTP/2 SETTINGS frame), before
    ray.init waits minutes on an address nothing answers at, or where another server listens (the
    dashboard's 8265). None, "auto", "local" and other schemes (resolved by Ray itself) are left to
    ray.init; with RAY_USE_TLS set, only the connection is checked.

    Raises:
        RayAddressError: the host is unknown, or refuses or does not answer a connection on the port,
            or something other than a gRPC server answers.
    """
    import socket
    from urllib.parse import urlsplit

    if not address or address.lower() in ("auto", "local"):
        return
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "", address
    elif scheme.lower() != "ray":
        return
    try:
        parts = urlsplit(f"//{rest}")
        host, port = parts.hostname, parts.port or _RAY_PORTS[scheme.lower()]
    except ValueError as err:
        raise RayAddressError(f"Ray address {address!r}: {err}") from None
    if not host:
        raise RayAddressError(f"Ray address {address!r} names no host (HOST:PORT or ray://HOST:PORT)")
    try:
        with socket.create_connection((host, port), timeout=timeout) as connection:
            if os.environ.get("RAY_USE_TLS", "0").lower() in ("1", "true"):
                return  # the handshake is TLS's
            # HTTP/2's client preface; a gRPC server's own begins with a SETTINGS frame (type 4).
            connection.sendall(b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0]))
            reply = b""
            while len(reply) < 9 and (more := connection.recv(9 - len(reply))):
                reply += more
    except OSError as err:
        reason = f"no answer within {timeout:g} s" if isinstance(err, TimeoutError) else err.strerror or err
        raise RayAddressError(
            f"cannot reach the Ray cluster at {address!r} ({host}:{port}: {reason})"
        ) from None
    if reply[3:4] != b"\x04":
        raise RayAddressError(
            f"cannot reach the Ray cluster at {address!r} ({host}:{port} answers, but not as Ray's gRPC "
            "servers do: a head's GCS is at HOST:6379, its client server at ray://HOST:10001)"
        )


def start_local_ray(num_cpus: int) -> None:
    """ray.init of a local Ray with num_cpus CPUs whose workers run at the usual priority.

    Ray's default runs workers at niceness 15, so that they yield to every other job: on a shared
    machine two trainings of 2,000 steps took 415 s as Ray tasks against 21 s in local processes.
    The work here is the job, so its workers compete on equal terms (as local processes do).
    """
    import ray

    ray.init(
        num_cpus=num_cpus,
        include_dashboard=False,
        logging_level=logging.WARNING,
        _system_config={"worker_niceness": 0},
    )


@contextlib.contextmanager
def ray_session(workers: int, address: str | None = None) -> Iterator[None]:
    """Ray for the block: the one already initialised (a cluster, or `ray.init(num_cpus=2)` in a
    test) as it is; else the cluster at `address` (checked first: check_ray_address), else a local
    Ray of `workers` CPUs (start_local_ray); one this call started is shut down after."""
    import ray

    started = not ray.is_initialized()
    if started and address:
        check_ray_address(address)
        ray.init(address=address, logging_level=logging.WARNING)
    elif started:
        start_local_ray(workers)
    try:
        yield
    finally:
        if started:
            ray.shutdown()


def _evaluate_ray(
    trials: list[Trial], spec: RunSpec, workers: int | None, address: str | None, deliver: ResultSink
) -> None:
    import ray
    from ray.util.queue import Empty, Queue

    with ray_session(workers or 2, address):
        if workers is None:
            workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
        chunks = split_trials(trials, workers)
        result_queue = Queue(actor_options={"num_cpus": 0})
        task = ray.remote(num_cpus=1)(_chunk)
        refs = [task.remote(chunk, spec, result_queue) for chunk in chunks]
        try:
            _drain(
                len(trials),
                lambda timeout: result_queue.get(timeout=timeout),
                Empty,
                lambda: ray.wait(refs, num_returns=len(refs), timeout=0)[0],
                ray.get,
                len(refs),
                deliver,
            )
        except BaseException:
            for ref in refs:
                ray.cancel(ref, force=True)
            raise
        finally:
            result_queue.shutdown()


# ---------------------------------------------------------------------------- entry point
def evaluate(
    trials: Sequence[Trial],
    spec: RunSpec,
    *,
    backend: Backend = "local",
    workers: int | None = 2,
    address: str | None = None,
    on_results: ResultSink | None = None,
    progress: bool = False,
    desc: str = "trials",
) -> list[TrialResult]:
    """Run trials on a backend; results reach `on_results` in this process as trials finish.

    Args:
        trials: the trials (duplicates are run once).
        spec: test sets, env configs, policies and batch size.
        backend: "local" (this machine: `workers` processes, or this process for 1 worker) or
            "ray" (a Ray cluster at `address`, or a local Ray started with `workers` CPUs).
        workers: processes (local) or chunks (Ray; None: one per CPU of the cluster).
        address: Ray cluster address (e.g. "auto" or "ray://host:10001"); Ray backend only.
        on_results: called with each group of finished trials, in this process.
        progress: show finished trials, rate and time left (socialzoo.bench.progress: a tqdm bar
            on a terminal, a line every 10% or 30 s in a log).
        desc: the progress label.

    Returns:
        The results, in the order of `trials` (first occurrence).

    Raises:
        ValueError: an unknown backend, a bad worker count, or a trial the spec does not know;
            any exception of a worker.
        RayAddressError: a Ray address nothing answers at (a ValueError; within seconds).
    """
    check_backend(backend)
    check_int("evaluate", "workers", workers, low=1, allow_none=True)
    if address is not None and backend != "ray":
        raise ValueError("address is for the Ray backend (--backend ray)")
    unique = list(dict.fromkeys(trials))
    spec.check(unique)
    results: dict[Trial, TrialResult] = {}
    bar = progress_bar(len(unique), desc, enabled=progress and bool(unique), unit="trial")
    start = time.perf_counter()

    def deliver(batch: list[TrialResult]) -> None:
        fresh = [r for r in batch if r.trial not in results]
        for r in fresh:
            results[r.trial] = r
        bar.update(len(fresh))
        if on_results is not None and fresh:
            on_results(fresh)

    try:
        if unique:
            if backend == "local":
                _evaluate_local(split_trials(unique, workers or 1), spec, deliver)
            else:
                _evaluate_ray(unique, spec, workers, address, deliver)
    finally:
        bar.close()
    elapsed = time.perf_counter() - start
    if unique:
        rate = len(unique) / elapsed if elapsed > 0 else math.inf
        logger.info("%d trials in %.1f s (%.2f trials/s, backend %s)", len(unique), elapsed, rate, backend)
    return [results[t] for t in unique]
