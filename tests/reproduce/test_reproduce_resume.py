"""Interrupting and resuming a part stores every item exactly once; other settings never reuse items."""

import json

import pytest

from socialzoo.bench.store import ResultsStore
from socialzoo.reproduce.ledger import Ledger, SettingsMismatch
from socialzoo.reproduce.plan import settings_hash
from socialzoo.reproduce.run import reproduce

pytest.importorskip("torch")


def _curve_trials(work):
    with ResultsStore(work / "rl" / "curves" / "curves.sqlite") as store:
        return [(r["policy"], r["scenario_index"]) for r in store.rows()]


def test_interrupted_part_resumes_and_stores_each_item_once(tmp_path, tiny_settings, monkeypatch):
    settings = tiny_settings()
    calls = {"n": 0}
    real_add = ResultsStore.add

    def add_then_die(self, rows):
        stored = real_add(self, rows)
        calls["n"] += 1
        if calls["n"] == 2:  # killed after two stored trials
            raise KeyboardInterrupt
        return stored

    monkeypatch.setattr(ResultsStore, "add", add_then_die)
    with pytest.raises(KeyboardInterrupt):
        reproduce(tmp_path, settings, parts="rl-curves", progress=False)
    work = tmp_path / settings_hash(settings)
    assert len(_curve_trials(work)) == 2
    started = {a: json.loads((work / "rl" / a / "run.json").read_text())["started"] for a in ("ppo", "dqn")}
    timings = json.loads((work / "timings.json").read_text())["rl-curves"]
    assert [s["finished"] for s in timings["sessions"]] == [False]

    monkeypatch.setattr(ResultsStore, "add", real_add)
    made = {}
    reproduce(tmp_path, settings, parts="rl-curves", progress=False, on_part=made.__setitem__)
    trials = _curve_trials(work)
    # ppo@200, dqn@200 and ref, each on the 2 scenarios, each exactly once.
    assert len(trials) == len(set(trials)) == 3 * settings.curve_trials
    assert made == {"rl-curves": 3 * settings.curve_trials - 2}  # no training repeated
    for algo, when in started.items():
        assert json.loads((work / "rl" / algo / "run.json").read_text())["started"] == when
    timings = json.loads((work / "timings.json").read_text())["rl-curves"]
    assert [s["finished"] for s in timings["sessions"]] == [False, True]
    assert timings["seconds"] == pytest.approx(sum(s["seconds"] for s in timings["sessions"]), abs=0.2)

    reproduce(tmp_path, settings, parts="rl-curves", progress=False, on_part=made.__setitem__)
    assert made == {"rl-curves": 0} and len(_curve_trials(work)) == 3 * settings.curve_trials


def test_changed_settings_never_reuse_items(tmp_path, tiny_settings):
    first, second = tiny_settings(), tiny_settings(demo_env_overrides={"max_steps": 120})
    made = {}
    reproduce(tmp_path, first, parts="demos", progress=False, on_part=made.__setitem__)
    demos = tmp_path / settings_hash(first) / "demos" / "ref_demos.npz"
    before = demos.stat().st_mtime_ns
    reproduce(tmp_path, second, parts="demos", progress=False, on_part=made.__setitem__)
    assert made == {"demos": 1}  # recorded again, in its own folder
    assert settings_hash(first) != settings_hash(second)
    assert (tmp_path / settings_hash(second) / "demos" / "ref_demos.npz").is_file()
    assert demos.stat().st_mtime_ns == before
    run = json.loads((tmp_path / "results" / "run.json").read_text())
    assert run["settings_hash"] == settings_hash(second) and run["settings"] == second.to_json()
    # A folder whose record names other settings is refused, not mixed.
    record = tmp_path / settings_hash(first) / "settings.json"
    data = json.loads(record.read_text())
    data["settings"]["curve_trials"] = 99
    record.write_text(json.dumps(data))
    with pytest.raises(SettingsMismatch, match="other settings"):
        Ledger(tmp_path, first)


def test_ray_backend_trains_and_evaluates_as_tasks(tmp_path, tiny_settings):
    ray = pytest.importorskip("ray")
    settings = tiny_settings()
    ray.init(num_cpus=2, include_dashboard=False)
    try:
        reproduce(tmp_path / "ray", settings, parts="rl-curves", backend="ray", progress=False)
    finally:
        ray.shutdown()
    reproduce(tmp_path / "local", settings, parts="rl-curves", progress=False)
    work = {b: tmp_path / b / settings_hash(settings) for b in ("ray", "local")}
    for algo in ("ppo", "dqn"):
        assert json.loads((work["ray"] / "rl" / algo / "run.json").read_text())["finished"]
    rows = {}
    for backend, folder in work.items():
        with ResultsStore(folder / "rl" / "curves" / "curves.sqlite") as store:
            rows[backend] = {(r["policy"], r["scenario_index"]): r["success"] for r in store.rows()}
    assert len(rows["ray"]) == 3 * settings.curve_trials
    assert {k: v for k, v in rows["ray"].items() if k[0] == "ref"} == {
        k: v for k, v in rows["local"].items() if k[0] == "ref"
    }
    timings = json.loads((work["ray"] / "timings.json").read_text())["rl-curves"]
    assert timings["sessions"][0]["backend"] == "ray"


def test_a_terminated_command_records_its_part_and_resumes(tmp_path):
    """`socialzoo reproduce` stopped by SIGTERM mid-part records the session; a rerun finishes it."""
    import signal
    import subprocess
    import sys
    import time

    from socialzoo.reproduce.plan import quick_settings

    work = tmp_path / settings_hash(quick_settings())
    command = [sys.executable, "-m", "socialzoo", "reproduce", "--out", str(tmp_path), "--quick"]
    child = subprocess.Popen([*command, "--only", "demos", "--no-progress"])
    # Stop it inside the demos part, whose first act is to make its folder (a fixed sleep after the
    # settings file appeared was too short on a loaded machine).
    deadline = time.monotonic() + 120
    while not (work / "demos").is_dir() and child.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert child.poll() is None, "the demos part ended before it could be stopped"
    child.send_signal(signal.SIGTERM)
    assert child.wait(timeout=60) != 0
    sessions = json.loads((work / "timings.json").read_text())["demos"]["sessions"]
    assert [s["finished"] for s in sessions] == [False]
    assert not (work / "demos" / "ref_demos.npz").exists()
    assert subprocess.run([*command, "--only", "demos", "--no-progress"], timeout=300).returncode == 0
    sessions = json.loads((work / "timings.json").read_text())["demos"]["sessions"]
    assert [s["finished"] for s in sessions] == [False, True]
    assert (work / "demos" / "ref_demos.npz").is_file()
