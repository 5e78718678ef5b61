"""Stored trials replayed: found in a benchmark's results store, run again, and their metrics
checked against the stored ones."""

import json
import shutil
import sqlite3

import pytest

from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark
from socialzoo.bench.replay_trials import compare_metrics, find_trials, replay_trial, store_path
from socialzoo.env.metrics import SUMMARY_KEYS
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet

TRIALS = 3


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A tiny benchmark run: GoAlone and Ref on 3 scenarios of a small test set."""
    out = tmp_path_factory.mktemp("replay") / "results"
    test_set = TestSet("open_room", 21, 10, ScenarioConfig(min_humans=3, max_humans=8), name="open-mini")
    config = BenchmarkConfig(
        policies=("goalone", "ref"),
        maps=("open_room",),
        trials=TRIALS,
        env_overrides={"max_steps": 200},
        workers=1,
        batch_size=2,
    )
    run_benchmark(config, out, test_sets={"open_room": test_set}, progress=False, figures=False)
    return out


def test_find_trials(results):
    trials = find_trials(results, 2)
    assert [t.policy for t in trials] == ["goalone", "ref"]
    t = trials[1]
    assert (t.test_set, t.index, t.map) == ("open-mini", 2, "open_room")
    assert t.seed == TestSet("open_room", 21, 10).seed(2)
    assert t.env_config.max_steps == 200 and t.env_config.scenario.max_humans == 8
    assert t.policy_config["corridor_half_width"] == 0.62
    assert set(t.metrics) == set(SUMMARY_KEYS)
    # Filters, and the results.sqlite file itself.
    only = find_trials(store_path(results), 2, policies=["REF"], test_set="open_room")
    assert [x.policy for x in only] == ["ref"] and only[0].metrics == t.metrics


@pytest.mark.parametrize("index", range(TRIALS))
def test_replay_reproduces_the_stored_metrics(results, index):
    for trial in find_trials(results, index):
        done = replay_trial(trial, laser_rays=12, laser_stride=4)
        assert done.mismatches == []
        assert done.code_changed is False
        assert done.trace.num_steps == trial.metrics["steps"]
        for key in SUMMARY_KEYS:  # bit for bit, not only within the check's tolerance
            assert done.trace.metrics[key] == pytest.approx(trial.metrics[key], rel=0, abs=0, nan_ok=True), (
                key
            )


def test_a_changed_store_is_reported(results, tmp_path):
    copy = tmp_path / "results"
    shutil.copytree(results, copy)
    with sqlite3.connect(copy / "results.sqlite") as db:
        db.execute(
            "UPDATE trials SET total_reward = total_reward + 1.0, steps = steps + 3 WHERE scenario_index = 1"
        )
    (trial,) = find_trials(copy, 1, policies=["goalone"])
    done = replay_trial(trial, laser_rays=0)
    assert [m.split(":")[0] for m in done.mismatches] == ["steps", "total_reward"]


def test_missing_trials_name_what_the_store_holds(results, tmp_path):
    with pytest.raises(
        ValueError, match=r"no stored trial of scenario 7.*indices 0\.\.2.*\('ref', 'open-mini'\)"
    ):
        find_trials(results, 7)
    with pytest.raises(ValueError, match=r"no stored trial of scenario 1 on 'gdc1-test'.*indices 0\.\.2"):
        find_trials(results, 1, test_set="gdc1-test")
    with pytest.raises(FileNotFoundError, match="no results store"):
        find_trials(tmp_path, 0)
    # A crowd matrix's folder (socialzoo benchmark --humans sf,orca): the error names its stores.
    for column in ("0-sf", "1-orca"):
        (tmp_path / column).mkdir()
        shutil.copy(store_path(results), tmp_path / column / "results.sqlite")
    with pytest.raises(FileNotFoundError, match=r"folders hold one each: .*0-sf, .*1-orca$"):
        find_trials(tmp_path, 0)


def test_policy_rebuilt_from_its_stored_parameters(results):
    (trial,) = find_trials(results, 0, policies=["ref"])
    assert trial.build_policy().config()["corridor_half_width"] == 0.62
    changed = dict(trial.policy_config, corridor_half_width=0.5)
    other = type(trial)(**{**trial.__dict__, "policy_config": changed})
    assert other.build_policy().config()["corridor_half_width"] == 0.5


def test_latest_run_config_is_preferred(results, tmp_path):
    """A store with an older run of other code: the trial of the latest run is replayed."""
    copy = tmp_path / "results"
    shutil.copytree(results, copy)
    with sqlite3.connect(copy / "results.sqlite") as db:
        columns = [r[1] for r in db.execute("PRAGMA table_info(trials)") if r[1] != "id"]
        names = ", ".join(f'"{c}"' for c in columns)
        picked = ", ".join("'0000000000000000'" if c == "config_hash" else f'"{c}"' for c in columns)
        db.execute(f"INSERT INTO trials ({names}) SELECT {picked} FROM trials WHERE policy = 'ref'")
        db.execute(
            "UPDATE trials SET finished_at = '2999-01-01T00:00:00+00:00' WHERE config_hash = '0000000000000000'"
        )
        run = json.loads(db.execute("SELECT value FROM meta WHERE key = 'config'").fetchone()[0])
    (trial,) = find_trials(copy, 0, policies=["ref"])
    assert trial.config_hash == run["config_hashes"]["ref/open-mini"]


def test_compare_metrics():
    stored = {"success": True, "steps": 10, "time_to_goal": float("nan"), "total_reward": 1.5}
    assert compare_metrics(stored, dict(stored)) == []
    assert compare_metrics(stored, {**stored, "total_reward": 1.5 * (1 + 1e-12)}) == []
    wrong = compare_metrics(stored, {**stored, "steps": 11, "time_to_goal": 2.0})
    assert wrong == ["steps: stored 10, replayed 11", "time_to_goal: stored nan, replayed 2.0"]


def test_a_changed_configuration_is_flagged(results, tmp_path):
    """The config hash recomputed now differs from the stored one: the replay says so."""
    copy = tmp_path / "results"
    shutil.copytree(results, copy)
    with sqlite3.connect(copy / "results.sqlite") as db:
        run = json.loads(db.execute("SELECT value FROM meta WHERE key = 'config'").fetchone()[0])
        run["test_sets"]["open-mini"]["base_seed"] += 1  # as if the test set had been redefined
        db.execute("UPDATE meta SET value = ? WHERE key = 'config'", (json.dumps(run),))
    (trial,) = find_trials(copy, 0, policies=["goalone"])
    done = replay_trial(trial, laser_rays=0)
    assert done.code_changed is True and done.mismatches == []


def test_a_task_ids_trial_names_the_command_that_plays_it(tmp_path):
    # A task id's benchmark (socialzoo benchmark --maps socialzoo/Recorded-v4, ...) stores fixed
    # cases with the task's config, not an EnvConfig: it used to fail with KeyError 'env'.
    from socialzoo.agents.crowd_engineered import CrowdOrcaRobot
    from socialzoo.bench.task_benchmark import TaskId, evaluate_stored

    store = tmp_path / "results.sqlite"
    evaluate_stored(store, TaskId.of("socialzoo/CrowdNav-v1"), "orca", CrowdOrcaRobot(), "val", cases=1)
    command = r"--env socialzoo/CrowdNav-v1 --split val --case 0 --policy orca"
    with pytest.raises(ValueError, match=r"a task id's case .* " + command):
        find_trials(tmp_path, 0)


def test_a_suite_trial_names_the_family_its_replay_needs(tmp_path):
    # A suite's episode is its id's case with the family in the task's config: the hint gives the id
    # and the family (it printed the placeholder "ID" and no family).
    from socialzoo.agents.crowd_engineered import CrowdOrcaRobot
    from socialzoo.bench.task_benchmark import TaskId, evaluate_stored

    task = TaskId.of("socialzoo/CrowdNavSuite-v2")
    task = TaskId(task.env_id, task.task, {**task.kwargs, "family": "crossing"})
    evaluate_stored(
        tmp_path / "results.sqlite",
        task,
        "orca",
        CrowdOrcaRobot(),
        "val",
        cases=1,
        overrides={"time_limit": 10.0},
    )
    given = r"--env socialzoo/CrowdNavSuite-v2 --task-config family=crossing --task-config time_limit=10.0 "
    with pytest.raises(ValueError, match=given + r"--split val --case 0 --policy orca"):
        find_trials(tmp_path, 0)
