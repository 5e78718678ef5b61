"""The batched runner and its backends: every trial exactly once with the batch kept full, and the
same rows whatever the batching, the number of processes, or the backend (local or Ray)."""

import itertools
import math
import os
import signal
import socket
import subprocess
import sys
import time

import pytest

from socialzoo.bench.runner import (
    BatchedRunner,
    RayAddressError,
    Trial,
    TrialResult,
    _drain,
    check_ray_address,
    evaluate,
    make_spec,
    split_trials,
)
from socialzoo.env.metrics import SUMMARY_KEYS
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet

MAX_STEPS = 150


@pytest.fixture(scope="module")
def test_set(rooms_map_path):
    path = rooms_map_path
    return TestSet(str(path), 11, 30, ScenarioConfig(min_humans=2, max_humans=6), name="rooms-test")


def spec_for(test_set, batch_size):
    return make_spec(
        ["goalone", "ref"], [test_set], batch_size=batch_size, env_overrides={"max_steps": MAX_STEPS}
    )


def trials_for(count):
    return [Trial(p, "rooms-test", k) for p in ("goalone", "ref") for k in range(count)]


def as_rows(results):
    """Comparable plain rows (NaN replaced by a marker)."""

    def clean(v):
        return "nan" if isinstance(v, float) and math.isnan(v) else v

    return [(r.trial, r.map, r.seed, tuple(clean(r.metrics[k]) for k in SUMMARY_KEYS)) for r in results]


@pytest.fixture(scope="module")
def sequential(test_set):
    """One episode at a time (batch of 1), in this process."""
    return evaluate(trials_for(5), spec_for(test_set, 1), workers=1)


def test_every_trial_once_and_the_batch_stays_full(test_set):
    trials = trials_for(7)
    batch = 4
    delivered, active = [], []

    def on_step(task, row_trial, obs, actions, result):
        active.append(sum(t is not None for t in row_trial))
        assert obs.shape == task.obs.shape and actions.shape == (batch, 1)

    results = BatchedRunner(spec_for(test_set, batch)).run(
        trials, on_results=delivered.extend, on_step=on_step
    )
    assert [r.trial for r in results] == trials
    assert sorted(r.trial for r in delivered) == sorted(trials)  # each exactly once, as it finished
    assert all(r.metrics["steps"] <= MAX_STEPS for r in results)
    assert all(r.seed == test_set.seed(r.trial.index) for r in results)
    # Full until the queue runs dry, then only draining.
    first_short = next(i for i, n in enumerate(active) if n < batch)
    assert all(n == batch for n in active[:first_short])
    tail = active[first_short:]
    assert all(a >= b for a, b in itertools.pairwise(tail))
    # Greedy refill bound: a trial starts as soon as a row frees up.
    steps = [r.metrics["steps"] for r in results]
    assert len(active) <= sum(steps) / batch + max(steps)


def test_results_do_not_depend_on_the_batch_and_the_tail_shrinks(test_set, sequential):
    trials = trials_for(5)
    by_batch, stats = {}, {}
    for batch in (1, 3, 8):
        runner = BatchedRunner(spec_for(test_set, batch))
        by_batch[batch] = as_rows(runner.run(trials))
        stats[batch] = runner.stats
    assert by_batch[1] == by_batch[3] == by_batch[8] == as_rows(sequential)
    # B = 8, 10 trials: the queue runs dry after 2 finishes; then the core is shrunk to its live
    # rows (at most a quarter of its rows idle), so the tail steps far fewer rows than 8 per step.
    shrunk = stats[8]
    assert shrunk.compactions >= 1
    assert shrunk.tail_row_steps < 0.75 * 8 * shrunk.tail_steps
    full = BatchedRunner(spec_for(test_set, 8), compact_tail=False)
    assert as_rows(full.run(trials)) == by_batch[8]
    assert full.stats.compactions == 0
    assert full.stats.tail_row_steps == 8 * full.stats.tail_steps
    assert (full.stats.tail_steps, full.stats.body_steps) == (shrunk.tail_steps, shrunk.body_steps)
    assert shrunk.tail_row_steps < full.stats.tail_row_steps
    # Nothing queued behind a batch of 1: every step is a tail step of one row.
    assert stats[1].compactions == 0 and stats[1].tail_row_steps == stats[1].tail_steps


def test_batched_equals_sequential(test_set, sequential):
    batched = evaluate(trials_for(5), spec_for(test_set, 4), workers=1)
    assert as_rows(batched) == as_rows(sequential)


def test_two_workers_equal_one_worker(test_set, sequential):
    got = []
    two = evaluate(trials_for(5), spec_for(test_set, 3), workers=2, on_results=got.extend)
    assert as_rows(two) == as_rows(sequential)
    assert sorted(r.trial for r in got) == sorted(trials_for(5))


def test_ray_backend_equals_local(test_set, sequential):
    ray = pytest.importorskip("ray")
    try:
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    except Exception as err:  # Ray may be unable to start in a restricted sandbox
        pytest.skip(f"Ray could not start: {err}")
    try:
        got = []
        results = evaluate(
            trials_for(5), spec_for(test_set, 3), backend="ray", workers=2, on_results=got.extend
        )
    finally:
        ray.shutdown()
    assert as_rows(results) == as_rows(sequential)
    assert len(got) == len(results)


def closed_port():
    """A local TCP port that nothing listens on (bound, then closed)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_ray_address_nothing_answers_at_fails_in_seconds_naming_it(test_set, capsys, tmp_path):
    # ray.init(address=...) waited over two minutes on an address nothing answered at.
    pytest.importorskip("ray")
    port = closed_port()
    for address in (f"127.0.0.1:{port}", f"ray://localhost:{port}"):
        start = time.monotonic()
        with pytest.raises(RayAddressError, match=rf"cannot reach the Ray cluster at '{address}'.*refused"):
            evaluate(trials_for(1), spec_for(test_set, 1), backend="ray", address=address)
        assert time.monotonic() - start < 10.0
    with pytest.raises(RayAddressError, match="names no host"):
        check_ray_address("ray://:10001")
    for address in (None, "auto", "local", "anyscale://my-cluster"):  # left to Ray
        check_ray_address(address)
    # The command says it in one line (exit 2), before any trial.
    from socialzoo.cli import main

    argv = [
        "benchmark",
        "--policies",
        "goalone",
        "--maps",
        test_set.map_name,
        "--trials",
        "1",
        "--no-figures",
    ]
    argv += ["--backend", "ray", "--address", f"127.0.0.1:{port}", "--out", str(tmp_path), "--no-progress"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"socialzoo benchmark: error: cannot reach the Ray cluster at '127.0.0.1:{port}'")
    assert len(err.splitlines()) == 1


def serve_once(reply):
    """A local port whose one connection gets `reply` once the client has spoken (None: silence)."""
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)

    def answer():
        connection, _ = server.accept()
        with connection, server:
            connection.recv(64)
            if reply is not None:
                connection.sendall(reply)
            time.sleep(1.0)

    threading.Thread(target=answer, daemon=True).start()
    return server.getsockname()[1]


def test_a_ray_address_where_another_server_answers_fails_naming_it(monkeypatch):
    # ray.init waited minutes (over 4, then killed) on a port that accepts but is no Ray server,
    # e.g. the dashboard's 8265 given as the cluster's address.
    monkeypatch.delenv("RAY_USE_TLS", raising=False)
    port = serve_once(b"HTTP/1.0 400 Bad request\r\n\r\n")
    start = time.monotonic()
    with pytest.raises(RayAddressError, match=rf"'127.0.0.1:{port}' \(127.0.0.1:{port} answers, but not as"):
        check_ray_address(f"127.0.0.1:{port}")
    assert time.monotonic() - start < 5.0
    with pytest.raises(RayAddressError, match=r"no answer within 0\.5 s"):
        check_ray_address(f"ray://127.0.0.1:{serve_once(None)}", timeout=0.5)
    check_ray_address(f"127.0.0.1:{serve_once(bytes([0, 0, 24, 4, 0, 0, 0, 0, 0]))}")  # gRPC's SETTINGS
    monkeypatch.setenv("RAY_USE_TLS", "1")  # a TLS handshake is not HTTP/2's: only the connection counts
    check_ray_address(f"127.0.0.1:{serve_once(None)}")


def test_a_chunk_run_again_delivers_every_trial(test_set):
    """Ray reruns the chunk of a worker that died from its start: its first trials arrive twice, and
    the drain waits for the trials still missing instead of stopping at as many results as trials."""
    a, b, c = trials_for(3)[:3]
    queue = [[a, b], [a], [b, c]]  # the chunk's first attempt gave a and b, then its rerun a, b, c
    got = []

    def get(timeout):
        if not queue:
            raise LookupError  # empty
        return [TrialResult(t, "rooms", 0, {}) for t in queue.pop(0)]

    _drain(3, get, LookupError, list, lambda task: None, 1, got.append)
    assert [[r.trial for r in batch] for batch in got] == [[a, b], [a], [b, c]]


def test_split_and_bad_input(test_set):
    chunks = split_trials(trials_for(5), 3)
    assert sorted(t for c in chunks for t in c) == sorted(trials_for(5))
    assert len(split_trials(trials_for(1), 8)) == 2
    spec = spec_for(test_set, 2)
    with pytest.raises(ValueError, match="unknown backend 'slurm'"):
        evaluate(trials_for(1), spec, backend="slurm")
    with pytest.raises(ValueError, match="unknown policy 'pips'"):
        evaluate([Trial("pips", "rooms-test", 0)], spec)
    with pytest.raises(ValueError, match="unknown test set 'gdc1-test'"):
        evaluate([Trial("ref", "gdc1-test", 0)], spec)
    with pytest.raises(ValueError, match=r"outside 0\.\.29"):
        evaluate([Trial("ref", "rooms-test", 30)], spec)
    with pytest.raises(ValueError, match="unknown policy 'nope'"):
        make_spec(["nope"], [test_set])
    assert evaluate([], spec) == []


def test_observation_only_policies_act_on_their_rows_with_the_same_results(test_set, tmp_path, monkeypatch):
    """Learned policies (reads_core = False) get only their rows; results do not depend on the mix."""
    import numpy as np

    from socialzoo.agents.mlp import MlpPolicy
    from socialzoo.env.policy_file import current_env_version

    specs = []
    for i in range(2):
        rng = np.random.default_rng(i)
        policy = MlpPolicy(
            "ppo", [(rng.normal(size=(4, 107)), rng.normal(size=4))], "relu", {"layout": "paper"}
        )
        header = {"env_id": f"socialzoo/ActionSelection-v{current_env_version()}", "training": {}}
        specs.append(f"ppo:{policy.save(tmp_path / f'p{i}.safetensors', header)}")
    spec = make_spec([*specs, "goalone"], [test_set], batch_size=5, env_overrides={"max_steps": MAX_STEPS})
    trials = [Trial(p, "rooms-test", k) for p in [*specs, "goalone"] for k in range(3)]
    seen = []
    runner = BatchedRunner(spec, stack_policies=False)
    original = MlpPolicy.act

    def recording(self, obs, core=None):
        seen.append(obs.shape[0])
        return original(self, obs, core)

    monkeypatch.setattr(MlpPolicy, "act", recording)
    mixed = runner.run(trials)
    monkeypatch.undo()
    assert max(seen) < 5  # never the whole batch of 5
    alone = [
        evaluate(
            [t], make_spec([t.policy], [test_set], batch_size=1, env_overrides={"max_steps": MAX_STEPS})
        )[0]
        for t in trials
    ]
    assert as_rows(mixed) == as_rows(alone)
    # Stacked (socialzoo.bench.policy_stack: both files share a network shape): the same results.
    assert as_rows(BatchedRunner(spec).run(trials)) == as_rows(alone)


# A parent that starts both kinds of worker pool (the evaluation's and the trainings'), each worker
# busy for two minutes, prints the workers' pids and waits to be killed.
_POOL_PARENT = """
import multiprocessing, os, threading, time
from concurrent.futures import ProcessPoolExecutor
from socialzoo.bench.runner import _init_worker
from socialzoo.reproduce.backend import _run_local

ctx = multiprocessing.get_context("spawn")
pool = ProcessPoolExecutor(max_workers=1, mp_context=ctx, initializer=_init_worker,
                           initargs=(ctx.Queue(), os.getpid()))
pool.submit(time.sleep, 120)
threading.Thread(target=_run_local, args=(time.sleep, [120, 120], 2), daemon=True).start()
deadline = time.monotonic() + 60
while len(multiprocessing.active_children()) < 3 and time.monotonic() < deadline:
    time.sleep(0.1)
time.sleep(5)  # the workers' initializers have run
print(*[p.pid for p in multiprocessing.active_children()], flush=True)
time.sleep(120)
"""


def _alive(pid):
    try:
        state = next(line for line in open(f"/proc/{pid}/status") if line.startswith("State:"))
    except (FileNotFoundError, ProcessLookupError):
        return False
    return "zombie" not in state


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_workers_end_when_their_parent_is_killed(tmp_path):
    # Found killing `socialzoo benchmark --workers 2` with SIGKILL: both workers were still there
    # ten minutes later, waiting on their dead parent's queue; trainings would train on to the end.
    parent = subprocess.Popen(
        [sys.executable, "-c", _POOL_PARENT], stdout=subprocess.PIPE, text=True, cwd=str(tmp_path)
    )
    try:
        workers = [int(p) for p in parent.stdout.readline().split()]
    finally:
        parent.kill()
        parent.wait()
    assert len(workers) >= 3
    deadline = time.monotonic() + 20
    while any(map(_alive, workers)) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = [pid for pid in workers if _alive(pid)]
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert not left, f"workers {left} outlived their killed parent"


def test_worker_processes_play_a_family_registered_in_this_one(tmp_path, monkeypatch):
    """A family of one's own, registered by register_family (docs/architecture.md), played by two
    worker processes: a spawned worker never ran register_family and ended in KeyError: unknown
    scenario family. The RunSpec carries it and the runner registers it there."""
    from socialzoo.bench.runner import CaseSet, RunSpec
    from socialzoo.env.config import EnvConfig
    from socialzoo.scenarios.catalogue import FAMILIES, register_family

    (tmp_path / "my_families_own.py").write_text(
        "from socialzoo.scenarios.catalogue import SeedSplit\n"
        "from socialzoo.scenarios.families import HallwayHeadOn\n"
        "class HeadOnOwn(HallwayHeadOn):\n"
        "    name = 'head_on_own'\n"
        "    splits = {'test': SeedSplit(0, 4)}\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    from my_families_own import HeadOnOwn  # registers nothing at import: only this process does

    register_family(HeadOnOwn)
    try:
        spec = RunSpec(
            test_sets={"own": CaseSet("action_selection", "test", 4)},
            env_configs={"own": EnvConfig(family="head_on_own", max_steps=MAX_STEPS)},
            policies={"goalone": {}},
            batch_size=2,
        )
        assert [f.name for f in spec.families] == ["head_on_own"]
        trials = [Trial("goalone", "own", k) for k in range(4)]
        assert as_rows(evaluate(trials, spec, workers=2)) == as_rows(evaluate(trials, spec, workers=1))
    finally:
        FAMILIES.pop("head_on_own", None)
