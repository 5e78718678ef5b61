"""Training seeds as an axis of the protocol: one run folder, policy and curve per seed, resumed
seed by seed, the kept checkpoint chosen on validation, and trainings spread over processes or
Ray workers."""

import json
import os
import shutil
import sys
import time
from pathlib import Path

import pytest

from socialzoo.bench.runner import start_local_ray
from socialzoo.reproduce.backend import run_tasks
from socialzoo.reproduce.plan import settings_hash
from socialzoo.reproduce.results import load
from socialzoo.reproduce.run import reproduce

pytest.importorskip("torch")

RUNS = ("ppo", "dqn", "ppo-s1", "dqn-s1")


def pid_after_a_nap(_):
    time.sleep(1.0)
    return os.getpid()


def pid_after_meeting(task):
    """(pid, met): the task leaves its mark in a shared folder and waits for the other's; two tasks
    run one after the other never meet (the first gives up), whatever the machine's load."""
    folder, me, other = task
    (Path(folder) / me).touch()
    deadline = time.monotonic() + 120.0
    while not (Path(folder) / other).exists():
        if time.monotonic() > deadline:
            return os.getpid(), False
        time.sleep(0.05)
    return os.getpid(), True


def niceness(_):
    return os.nice(0)


def test_every_seed_trains_its_own_run_and_curve_and_resumes_alone(tmp_path, tiny_settings):
    settings = tiny_settings(seeds=2)
    made = {}
    reproduce(tmp_path, settings, parts="rl-curves", progress=False, on_part=made.__setitem__)
    work = tmp_path / settings_hash(settings)
    records = {run: json.loads((work / "rl" / run / "run.json").read_text()) for run in RUNS}
    assert {run: r["seed"] for run, r in records.items()} == {"ppo": 0, "dqn": 0, "ppo-s1": 1, "dqn-s1": 1}
    assert all(r["finished"] and r["results"]["best_checkpoint"]["step"] == 200 for r in records.values())
    results = load(tmp_path / "results")
    labels = {r["label"] for r in results["rl_curves"]}
    assert labels == {*RUNS, "ref"}  # every seed is a curve
    assert [(r["run"], int(r["seed"])) for r in results["selection"]] == [
        ("ppo", 0),
        ("dqn", 0),
        ("ppo-s1", 1),
        ("dqn-s1", 1),
    ]
    report = (tmp_path / "REPRODUCTION.md").read_text()
    assert "## Checkpoint choice by validation" in report and "| training seeds | 2 (0, 1) | 1 |" in report
    assert "--seeds 2" in results["run"]["command"]

    # One seed's run lost: only that one trains again.
    shutil.rmtree(work / "rl" / "dqn-s1")
    reproduce(tmp_path, settings, parts="rl-curves", progress=False, on_part=made.__setitem__)
    assert made["rl-curves"] >= 1
    for run in ("ppo", "dqn", "ppo-s1"):
        assert json.loads((work / "rl" / run / "run.json").read_text())["started"] == records[run]["started"]
    assert json.loads((work / "rl" / "dqn-s1" / "run.json").read_text())["finished"]


def test_local_trainings_run_side_by_side_in_worker_processes():
    pids = run_tasks(pid_after_a_nap, [0, 1], backend="local", workers=2)
    assert len(set(pids)) == 2 and os.getpid() not in pids
    assert run_tasks(pid_after_a_nap, [0], backend="local", workers=2) == [os.getpid()]


def test_a_local_ray_started_for_the_tasks_runs_them_at_the_usual_priority():
    # Ray's default niceness (15) starved its tasks behind any other job on a shared machine.
    ray = pytest.importorskip("ray")
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])  # tests are not importable there
    assert not ray.is_initialized()
    assert run_tasks(niceness, [0, 1], backend="ray", workers=2) == [os.nice(0)] * 2
    assert not ray.is_initialized()  # the Ray started for the tasks is shut down after them


def test_ray_spreads_the_trainings_over_two_workers(tmp_path, tiny_settings):
    ray = pytest.importorskip("ray")
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])  # tests are not importable there
    start_local_ray(2)
    try:
        meeting = tmp_path / "meeting"
        meeting.mkdir()
        tasks = [(str(meeting), "a", "b"), (str(meeting), "b", "a")]
        results = run_tasks(pid_after_meeting, tasks, backend="ray", workers=2)
        pids = [pid for pid, _ in results]
        assert len(set(pids)) == 2 and os.getpid() not in pids
        assert all(met for _, met in results)  # side by side, not one after the other
        settings = tiny_settings(seeds=2)
        reproduce(tmp_path, settings, parts="rl-curves", backend="ray", progress=False)
    finally:
        ray.shutdown()
    work = tmp_path / settings_hash(settings)
    for run in RUNS:
        record = json.loads((work / "rl" / run / "run.json").read_text())
        assert record["finished"] and "ray" in record["command"]  # trained in a Ray worker
