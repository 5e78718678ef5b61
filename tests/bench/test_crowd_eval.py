"""CrowdNav-task evaluation on fixed cases, the engineered robots, the episode page and the command."""

import json

import numpy as np
import pytest

from socialzoo.agents import make_policy
from socialzoo.agents.crowd_engineered import CrowdOrcaRobot, CrowdSocialForceRobot
from socialzoo.bench.crowd_eval import evaluate_crowd
from socialzoo.bench.store import ResultsStore
from socialzoo.cli import main
from socialzoo.env.crowd_config import CrowdNavConfig

CONFIG = CrowdNavConfig.variant("SocialForce")


def _straight(obs, core):
    actions = np.zeros((len(obs), 2), dtype=np.float32)
    actions[:, 1] = 1.0  # due north, where the goal is
    return actions


def test_every_case_is_played_once_whatever_the_batch():
    a = evaluate_crowd(_straight, CONFIG, "val", cases=7, batch_size=3)
    b = evaluate_crowd(_straight, CONFIG, "val", cases=7, batch_size=7)
    assert [e["case"] for e in a.episodes] == list(range(7))
    np.testing.assert_equal(
        a.episodes, b.episodes
    )  # each case plays the same whatever the batch (NaN == NaN)
    s = a.summary
    assert s["episodes"] == 7 and s["success_rate"] + s["collision_rate"] + s[
        "timeout_rate"
    ] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="holds 100"):
        evaluate_crowd(_straight, CONFIG, "val", cases=101)
    with pytest.raises(ValueError, match="split"):
        evaluate_crowd(_straight, CONFIG, "train", cases=1)


def test_engineered_robots_reach_the_goal_of_an_empty_arena():
    empty = CONFIG.replace(cases={"num_humans": 0})
    for robot in (CrowdOrcaRobot(), CrowdSocialForceRobot()):
        result = evaluate_crowd(robot.act, empty, "val", cases=3)
        assert result.summary["success_rate"] == 1.0, robot.name
        assert 8.0 <= result.summary["navigation_time"] <= 9.5  # 7.7 m at 1 m/s, then the last step
    with pytest.raises(ValueError, match="unknown policy"):
        make_policy("teleport", task="crowdnav")


def test_an_episode_is_recorded_for_the_viewer():
    from socialzoo.bench.replay import record_case

    trace, task = record_case("socialzoo/CrowdNavSocialForce-v1", CrowdOrcaRobot(), "test", 3, label="orca")
    assert (
        trace.outcome in ("success", "collision", "time limit") and trace.num_steps == trace.metrics["steps"]
    )
    assert trace.num_humans == 5
    # The charts draw the step's force and blame; their means are the episode's metrics.
    assert trace.force.mean() == pytest.approx(trace.metrics["mean_force"])
    assert trace.blame.mean() == pytest.approx(trace.metrics["mean_blame"]) and trace.force.max() > 0
    scene = task.viewer_scene("case 3", "", [trace])
    assert scene.robot_length == pytest.approx(0.6) and scene.map_name == "arena"


def test_the_command_writes_tables_and_reuses_finished_policies(tmp_path, capsys):
    args = [
        "crowdnav",
        "eval",
        "--variant",
        "SocialForce",
        "--cases",
        "4",
        "--policies",
        "orca",
        "--out",
        str(tmp_path),
    ]
    assert main(args) == 0
    store = tmp_path / "results.sqlite"
    with ResultsStore(store) as results:
        assert sorted(r["scenario_index"] for r in results.rows(policy="orca")) == [0, 1, 2, 3]
    assert (tmp_path / "crowdnav.md").read_text().count("| orca |") == 1
    assert (tmp_path / "success.png").stat().st_size > 5_000
    table = (tmp_path / "crowdnav.csv").read_text()
    capsys.readouterr()
    assert main(args) == 0 and "0 episodes played, 4 read from the store" in capsys.readouterr().out
    assert (tmp_path / "crowdnav.csv").read_text() == table  # read back, the same numbers
    # Two more cases: only those are played.
    assert main([*args[:5], "6", *args[6:]]) == 0
    assert "2 episodes played, 4 read from the store" in capsys.readouterr().out
    page = tmp_path / "case.html"
    assert (
        main(["crowdnav", "replay", "--variant", "SocialForce", "--policies", "orca", "--out", str(page)])
        == 0
    )
    assert page.stat().st_size > 10_000
    walls = tmp_path / "walls"
    assert (
        main(
            [
                "crowdnav",
                "eval",
                "--variant",
                "Walls",
                "--cases",
                "2",
                "--policies",
                "orca",
                "--out",
                str(walls),
            ]
        )
        == 0
    )
    with ResultsStore(walls / "results.sqlite") as results:
        assert len(results.rows(policy="orca")) == 2
    ids = tmp_path / "ids"
    both = "socialzoo/CrowdNav-v1,socialzoo/CrowdNavSquare-v1"
    assert main(["benchmark", "--maps", both, "--policies", "orca", "--trials", "3", "--out", str(ids)]) == 0
    assert "| orca |" in (ids / "CrowdNavSquare-v1" / "crowdnav.md").read_text()
    assert main(["benchmark", "--maps", "socialzoo/CrowdNav-v1,gdc1", "--out", str(ids)]) == 2
    assert "cannot be mixed" in capsys.readouterr().err
    assert main(["crowdnav", "eval", "--policies", "wizard", "--out", str(tmp_path)]) == 2
    assert "unknown policy 'wizard'; policies of task 'crowdnav'" in capsys.readouterr().err


def test_the_shipped_learned_policy_crosses_the_crowd():

    from socialzoo.agents import SHIPPED_DIR

    policy = make_policy("crowdnav", task="crowdnav")
    record = json.loads((SHIPPED_DIR / "crowdnav.run.json").read_text())
    assert record["command"].startswith("socialzoo train crowdnav ") and "--seed" in record["command"]
    assert policy.header["training"]["seed"] == record["seed"] and record["finished"]
    config = CrowdNavConfig.variant("", action=policy.action_kind)
    result = evaluate_crowd(policy.act, config, "test", cases=40)
    assert result.summary["success_rate"] >= 0.85  # 0.998 over all 500 test cases


def test_stored_episodes_resume_after_an_interruption_and_follow_the_policy(tmp_path):
    from socialzoo.bench.task_benchmark import TaskId, config_hash, evaluate_stored, summarize

    config = CrowdNavConfig.variant("")
    task = TaskId.of("socialzoo/CrowdNav-v1")
    fresh = evaluate_crowd(CrowdOrcaRobot().act, config, "val", cases=6, batch_size=2)

    class Interrupted(CrowdOrcaRobot):
        calls = 0

        def act(self, obs, core):
            Interrupted.calls += 1
            if Interrupted.calls > 70:  # some episodes have ended by now, not all
                raise KeyboardInterrupt
            return super().act(obs, core)

    store = tmp_path / "results.sqlite"
    robot = Interrupted()
    with pytest.raises(KeyboardInterrupt):
        evaluate_stored(store, task, "orca", robot, "val", cases=6, batch_size=2)
    Interrupted.calls = -(10**6)
    episodes, played = evaluate_stored(store, task, "orca", robot, "val", cases=6, batch_size=2)
    assert 0 < played < 6  # the episodes stored before the interruption were not played again
    # The stored episodes also hold the guidelines' Table I metrics (gl_*); the rest are evaluate_crowd's.
    assert all(any(k.startswith("gl_") for k in e) for e in episodes)
    episodes = [{k: v for k, v in e.items() if not k.startswith("gl_")} for e in episodes]
    np.testing.assert_equal(episodes, fresh.episodes)
    np.testing.assert_equal(summarize(episodes), fresh.summary)
    assert evaluate_stored(store, task, "orca", robot, "val", cases=6)[1] == 0
    # Other settings of the policy or of the task are other episodes; the spec alone is a name.
    other = CrowdOrcaRobot(safety_space=0.1)
    assert config_hash(config, "val", "orca", other) != config_hash(config, "val", "orca", robot)
    assert config_hash(config.replace(time_limit=20.0), "val", "orca", robot) != config_hash(
        config, "val", "orca", robot
    )
    assert evaluate_stored(store, task, "orca", other, "val", cases=2)[1] == 2
    assert evaluate_stored(store, task, "orca", robot, "val", cases=2, overrides={"time_limit": 20.0})[1] == 2
    # A learned policy's file is part of its key: a retrained file under the same path is new.
    from socialzoo.agents import SHIPPED_DIR

    file = tmp_path / "crowdnav.safetensors"
    file.write_bytes((SHIPPED_DIR / "crowdnav.safetensors").read_bytes())
    learned = make_policy(f"crowdnav:{file}", task="crowdnav")
    before = config_hash(config, "val", f"crowdnav:{file}", learned)
    file.write_bytes(file.read_bytes() + b" ")
    assert config_hash(config, "val", f"crowdnav:{file}", learned) != before


def test_a_subset_of_cases_plays_as_in_the_full_run():
    full = evaluate_crowd(_straight, CONFIG, "val", cases=5, batch_size=2)
    part = evaluate_crowd(_straight, CONFIG, "val", cases=5, batch_size=2, indices=[4, 1])
    np.testing.assert_equal(part.episodes, [full.episodes[1], full.episodes[4]])
    with pytest.raises(ValueError, match="indices"):
        evaluate_crowd(_straight, CONFIG, "val", cases=5, indices=[5])


def test_a_learner_of_five_people_evaluates_on_twenty_through_its_nearest_five(tmp_path, capsys):
    args = [
        "crowdnav",
        "eval",
        "--variant",
        "20",
        "--cases",
        "3",
        "--policies",
        "crowdnav",
        "--out",
        str(tmp_path),
    ]
    assert main(args) == 2 and "reads observations of 46 numbers" in capsys.readouterr().err
    assert main([*args, "--observed-people", "5"]) == 0
    assert "3 episodes played, 0 read from the store" in capsys.readouterr().out
    assert "socialzoo/CrowdNav20-v1, observed_people=5, test cases" in (tmp_path / "crowdnav.md").read_text()
    # The store keeps each config's episodes apart: the same robot with every person observed plays anew.
    orca = [
        "crowdnav",
        "eval",
        "--variant",
        "20",
        "--cases",
        "2",
        "--policies",
        "orca",
        "--out",
        str(tmp_path),
    ]
    assert main([*orca, "--observed-people", "5"]) == 0
    assert "2 episodes played, 0 read from the store" in capsys.readouterr().out
    assert main(orca) == 0 and "2 episodes played, 0 read from the store" in capsys.readouterr().out
