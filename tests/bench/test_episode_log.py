"""Episode logs (socialzoo.bench.episode_log): a log of hand-made trajectories scores what the
arrays score directly, a recorded replay becomes a log that agrees with the env's own metrics, and
a log that breaks the schema is a named error naming the file and the field, with nothing written."""

import dataclasses
import json
import math

import numpy as np
import pytest

from socialzoo.bench.episode_log import (
    EpisodeLogError,
    log_metrics,
    make_episode_log,
    read_episode_log,
    schema,
    schema_path,
    trace_episode_log,
    validate_log,
    write_episode_log,
)
from socialzoo.bench.guideline_metrics import GuidelineParams, episode_metrics
from socialzoo.render.replay_data import EpisodeTrace, ReplayScene

WALLS = np.array([[0, 0, 6, 0], [6, 0, 6, 3], [6, 3, 0, 3], [0, 3, 0, 0]], dtype=float)


def _episodes():
    """Three hand-made episodes as make_episode_log / episode_metrics keyword arguments."""
    t = np.arange(7)
    straight = dict(dt=0.5, robot_pos=np.stack([1 + 0.5 * t, np.ones(7)], axis=1), goal=[4, 1])
    # People coming and going (absent: NaN positions), with their velocities, and the walls.
    people = np.stack(
        [np.stack([5 - 0.5 * t, np.full(7, 1.3)], axis=1), np.stack([t * 0.3, 2.5 + 0 * t], axis=1)], 1
    )
    mask = np.array([[True, True]] * 3 + [[True, False]] * 2 + [[False, True]] * 2)
    people = np.where(mask[..., None], people, np.nan)
    crowd = dict(
        straight,
        people_pos=people,
        people_mask=mask,
        people_vel=np.where(mask[..., None], [[-1.0, 0.0], [0.6, 0.0]], np.nan),
        people_radius=[0.2, 0.25],
        walls=WALLS,
        robot_radius=0.3,
        time_limit=3.0,
    )
    # Another robot with a goal, the simulator's flags, a route distance and a shortest path.
    others = np.stack([np.stack([1 + 0 * t, 2.5 - 0.2 * t], axis=1)], axis=1)
    team = dict(
        straight,
        robot_vel=np.tile([1.0, 0.0], (7, 1)),
        others_pos=others,
        others_goal=[[1.0, 1.5]],
        human_contact=[False, False, True, True, False, False, False],
        wall_contact=[False] * 7,
        goal_distance=3.5 - 0.5 * t,
        shortest_path_length=2.9,
    )
    return {"straight": straight, "crowd": crowd, "team": team}


def _direct(kw):
    """episode_metrics of the same arrays (its names for the log's fields)."""
    arrays = dict(kw)
    if "shortest_path_length" in arrays:
        arrays["shortest_path"] = arrays.pop("shortest_path_length")
    arrays.setdefault("robot_radius", 0.3)
    arrays.setdefault("goal_radius", 0.5)
    return episode_metrics(**arrays)


@pytest.mark.parametrize("name", ["straight", "crowd", "team"])
def test_a_log_scores_what_its_arrays_score(name, tmp_path):
    kw = _episodes()[name]
    log = make_episode_log(
        robot_radius=kw.get("robot_radius", 0.3),
        goal_radius=0.5,
        label=name,
        **{k: v for k, v in kw.items() if k != "robot_radius"},
    )
    path = write_episode_log(tmp_path / f"{name}.json", log)
    back = read_episode_log(path)
    assert back == json.loads(json.dumps(log))
    from_log, direct = log_metrics(back), _direct(kw)
    assert list(from_log) == list(direct)
    for key, value in direct.items():
        assert from_log[key] == pytest.approx(value, nan_ok=True), key


def test_the_hand_made_crowd_by_hand():
    # The robot (radius 0.3) drives (1,1) -> (4,1) at 1 m/s, reaching the goal (4,1) radius 0.5 at
    # x = 3.5, sample 5 (2.5 s). Person 0 (radius 0.2) walks from (5,1.3) towards it at 1 m/s: at
    # sample 2 the robot is at x = 2, the person at x = 4: gap sqrt(4 + 0.09) - 0.5 = 1.545; the
    # person leaves after sample 4 (robot 3, person 3: gap 0.3 - 0.5 = -0.2, a contact at sample 4,
    # and at sample 3: |(1, 0.3)| - 0.5 = 0.544). Person 1 (radius 0.25, y = 2.5) is 1.5 m off the
    # robot's line: gaps >= 1.5 - 0.55 = 0.95.
    found = log_metrics(make_episode_log(goal_radius=0.5, **_episodes()["crowd"]))
    assert found["gl_human_collisions"] == 1 and not found["gl_success"]
    assert found["gl_min_distance_to_human"] == pytest.approx(-0.2)
    # Compliance: samples 0..5 (the episode ends at the goal); person 0's gaps at samples 0..4 are
    # |(4, 0.3)|-0.5, |(3, 0.3)|-0.5, |(2, 0.3)|-0.5, 0.544, -0.2 -> samples 0..3 comply, 4 does not,
    # 5 (person 0 gone) does: 5 / 6.
    assert found["gl_personal_space_compliance"] == pytest.approx(5 / 6)
    # Walls y = 0 and y = 3 (x from 0 to 6): the robot centre is 1 m from y = 0 all along: 0.7.
    assert found["gl_clearing_distance_min"] == pytest.approx(0.7)
    assert found["gl_clearing_distance_avg"] == pytest.approx(0.7)
    # Head on with a 0.3 m offset: |(d - c t, 0.3)| = 0.5 -> d - c t = 0.4, c the closing speed:
    # sample 0, the robot at rest (no velocities in the log), d = 4, c = 1: 3.6 s; sample 1, d = 3,
    # c = 2: 1.3 s; sample 2: 0.8 s; sample 3: 0.3 s; sample 4: overlapping -> 0.
    assert found["gl_min_time_to_collision"] == 0.0
    earlier = log_metrics(
        make_episode_log(
            goal_radius=0.5,
            **{
                **_episodes()["crowd"],
                "people_mask": np.array(
                    [[True, True]] * 3 + [[True, False], [False, False]] + [[False, True]] * 2
                ),
            },
        )
    )
    assert earlier["gl_min_time_to_collision"] == pytest.approx(0.3)


def test_schema_is_shipped_and_describes_every_field():
    assert schema_path().is_file()
    doc = schema()
    assert doc["properties"]["format"]["const"] == "socialzoo-episode-log"
    assert set(doc["required"]) == {"format", "version", "time", "robot"}
    for name, prop in doc["properties"]["robot"]["properties"].items():
        assert prop.get("description"), f"robot.{name} has no description"


def _good():
    return make_episode_log(**_episodes()["crowd"], goal_radius=0.5)


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        (lambda log: log["robot"].pop("goal"), "robot", "'goal' is a required property"),
        (
            lambda log: log["robot"]["positions"].__setitem__(2, "x"),
            "robot.positions[2]",
            "is not of type 'array'",
        ),
        (lambda log: log["robot"]["positions"].__setitem__(3, [1.0]), "robot.positions[3]", "too short"),
        (lambda log: log.__setitem__("version", 2), "version", "1 was expected"),
        (lambda log: log["people"][1].__setitem__("radius", -1), "people[1].radius", "less than the minimum"),
        (lambda log: log.__setitem__("extra", 1), "(top level)", "'extra' was unexpected"),
        (lambda log: log["people"][0]["positions"].pop(), "people[0].positions", "has 6 entries, time has 7"),
        (lambda log: log["time"].__setitem__(3, 1.6), "time", "evenly spaced"),
        (lambda log: log["time"].__setitem__(3, 0.0), "time", "must increase"),
        (
            lambda log: log["robot"]["positions"][1].__setitem__(0, float("nan")),
            "robot.positions[1][0]",
            "finite",
        ),
        (lambda log: log["walls"][2].__setitem__(1, float("inf")), "walls[2][1]", "finite"),
        (lambda log: log.__setitem__("time_limit", float("nan")), "time_limit", "finite"),
        (
            lambda log: log.__setitem__(
                "other_robots",
                [
                    {
                        "radius": 0.3,
                        "positions": log["robot"]["positions"],
                        "goal": [0, 0],
                        "goal_radius": float("nan"),
                    }
                ],
            ),
            "other_robots[0].goal_radius",
            "finite",
        ),
    ],
)
def test_a_broken_log_is_a_named_error_and_nothing_is_written(change, field, words, tmp_path):
    log = _good()
    change(log)
    out = tmp_path / "bad.json"
    with pytest.raises(EpisodeLogError, match=r"bad\.json") as info:
        write_episode_log(out, log)
    assert info.value.field == field and words in info.value.problem, str(info.value)
    assert not out.exists() and list(tmp_path.iterdir()) == []
    # The same log read from a file names that file.
    src = tmp_path / "read_me.json"
    src.write_text(json.dumps(log))
    with pytest.raises(EpisodeLogError, match=r"read_me\.json: ") as info:
        read_episode_log(src)
    assert info.value.field == field


def test_unreadable_files_are_named_errors(tmp_path):
    with pytest.raises(EpisodeLogError, match=r"missing\.json: \(file\): cannot be read"):
        read_episode_log(tmp_path / "missing.json")
    (tmp_path / "junk.json").write_text("{not json")
    with pytest.raises(EpisodeLogError, match=r"junk\.json: \(file\): is not JSON"):
        read_episode_log(tmp_path / "junk.json")
    with pytest.raises(EpisodeLogError, match=r"<log>: \(top level\): .*is not of type 'object'"):
        validate_log([1, 2])


def test_a_replay_trace_becomes_a_log():
    # A hand-made trace: the robot (footprint 0.5 x 0.43: disc radius hypot / 2 = 0.3298) drives at
    # 1 m/s along y = 1 from x = 1, dt 0.5; the goal (3,1) radius 0.5 is reached at x = 2.5, sample
    # 3 (1.5 s). The trace flags a human contact after step 2 (sample 2): no success.
    steps, t = 4, np.arange(5) * 0.5
    pose = np.stack([1 + t, np.ones(5), np.zeros(5)], axis=1)
    trace = EpisodeTrace(
        label="ref",
        dt=0.5,
        robot_pose=pose,
        robot_vel=np.tile([1.0, 0.0], (5, 1)),
        goal=np.array([3.0, 1.0, 0.0]),
        human_pos=np.tile([5.0, 2.0], (5, 1, 1)),
        human_vel=np.zeros((5, 1, 2)),
        carrot=pose[:, :2],
        plans=(np.array([[1.0, 1.0], [3.0, 1.0]]),),
        plan_index=np.zeros(5, int),
        laser_angles=np.zeros(0),
        laser_steps=np.array([0]),
        laser_ranges=np.zeros((1, 0)),
        laser_max_range=10.0,
        action=np.zeros(steps, int),
        target_human=np.full(steps, -1),
        reward=np.zeros(steps),
        force=np.zeros(steps),
        blame=np.zeros(steps),
        human_collisions=np.array([0, 1, 0, 0]),
        wall_collision=np.zeros(steps, bool),
    )
    scene = ReplayScene(
        title="t",
        map_name="room",
        walls=WALLS,
        bounds=(0, 0, 6, 3),
        robot_length=0.5,
        robot_width=0.43,
        human_radius=0.2,
        goal_radius=0.5,
    )
    log = trace_episode_log(trace, scene, time_limit=30.0)
    assert log["robot"]["radius"] == pytest.approx(math.hypot(0.5, 0.43) / 2)
    assert log["collisions"]["human"] == [False, False, True, False, False]
    assert log["robot"]["velocities"][1] == [1.0, 0.0] and log["time"][-1] == 2.0
    found = log_metrics(log)
    assert not found["gl_success"] and found["gl_human_collisions"] == 1 and found["gl_path_length"] == 1.5
    assert found["gl_aggregated_time"] == 1.5
    assert found["gl_clearing_distance_min"] == pytest.approx(1 - math.hypot(0.5, 0.43) / 2)


def test_a_recorded_episode_agrees_with_the_env(rooms_map_path, tmp_path):
    # A real episode of GoAlone among people: the log's success, time to goal and path length are
    # the env's own (the log carries the env's contact flags).
    from socialzoo.agents import make_policy
    from socialzoo.bench.replay import benchmark_scenario, record_episode, replay_scene
    from socialzoo.env.config import EnvConfig
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.generator import ScenarioConfig

    config = EnvConfig(
        map=str(rooms_map_path), max_steps=400, scenario=ScenarioConfig(min_humans=2, max_humans=3)
    )
    m = load_map(config.map)
    trace = record_episode(config, benchmark_scenario(config, 1, m), make_policy("goalone"), world_map=m)
    log = trace_episode_log(trace, replay_scene(config, m, "t"))
    found = log_metrics(read_episode_log(write_episode_log(tmp_path / "ep.json", log)))
    env = trace.metrics
    assert found["gl_success"] == bool(env["success"])
    if env["success"]:
        assert found["gl_time_to_goal"] == pytest.approx(env["time_to_goal"])
    assert found["gl_path_length"] == pytest.approx(env["distance_travelled"])
    assert found["gl_human_collisions"] <= env["human_collisions"]  # contact stretches <= contact steps


def test_thresholds_reach_the_log_path():
    log = make_episode_log(**_episodes()["crowd"], goal_radius=0.5)
    strict = log_metrics(log, GuidelineParams(personal_space=2.0))
    assert strict["gl_personal_space_compliance"] < log_metrics(log)["gl_personal_space_compliance"]


def test_float32_and_rounded_stamps_are_evenly_spaced_a_dropped_sample_is_not():
    # A JAX or torch simulator keeps time in float32: a minute at 40 Hz strays from k dt by a few
    # microseconds, which is one step for the metrics (dt the mean step).
    n, dt = 2401, 0.025
    pos = np.stack([np.linspace(0.0, 30.0, n), np.zeros(n)], axis=1)
    log = make_episode_log(dt=dt, robot_pos=pos, goal=[30, 0], robot_radius=0.3, goal_radius=0.005)
    log["time"] = (np.arange(n, dtype=np.float32) * np.float32(dt)).tolist()
    validate_log(log)
    assert log_metrics(log)["gl_time_to_goal"] == pytest.approx(60.0, rel=1e-6)
    # Stamps rounded to the millisecond at 10 Hz.
    slow = make_episode_log(dt=0.1, robot_pos=pos[:50], goal=[30, 0], robot_radius=0.3, goal_radius=0.2)
    slow["time"] = [round(0.1 * k + 0.0004 * (-1) ** k, 3) for k in range(50)]
    validate_log(slow)
    # A dropped sample (one step of 2 dt) is named, with the step.
    dropped = dict(log, time=[dt * k for k in range(n + 1) if k != 100])
    with pytest.raises(EpisodeLogError, match=r"time\[99\] to time\[100\] is 0\.05 s, the mean step 0\.025"):
        validate_log(dropped)


def test_a_long_log_is_checked_entry_by_entry_outside_jsonschema(monkeypatch):
    # jsonschema walked every sample through $ref and oneOf: a log of 10,000 samples and 200 people
    # took minutes to check. It now sees one entry of each per-sample array that passes the quick
    # test of its entries, and every entry of an array that does not.
    import jsonschema

    n = 400
    t = np.arange(n)
    people = np.stack([np.stack([t * 0.01, np.full(n, 2.0 + j)], axis=1) for j in range(3)], axis=1)
    log = make_episode_log(
        dt=0.1,
        robot_pos=np.stack([t * 0.01, np.zeros(n)], axis=1),
        goal=[10, 0],
        robot_radius=0.3,
        goal_radius=0.2,
        people_pos=people,
        human_contact=np.zeros(n, dtype=bool),
    )
    seen = []
    iter_errors = jsonschema.Draft202012Validator.iter_errors
    monkeypatch.setattr(
        jsonschema.Draft202012Validator,
        "iter_errors",
        lambda self, instance, *a: seen.append(instance) or iter_errors(self, instance, *a),
    )
    validate_log(log)
    walked = seen[0]
    assert len(walked["time"]) == len(walked["robot"]["positions"]) == 1
    assert [len(p["positions"]) for p in walked["people"]] == [1, 1, 1]
    assert len(walked["collisions"]["human"]) == 1 and len(log["time"]) == n
    # Errors deep in a long array are jsonschema's, at the entry, as before.
    for where, change, words in [
        (
            "people[1].positions[350]",
            lambda g: g["people"][1]["positions"].__setitem__(350, [1.0]),
            "too short",
        ),
        (
            "collisions.human[9]",
            lambda g: g["collisions"]["human"].__setitem__(9, 1),
            "not of type 'boolean'",
        ),
        ("robot.positions[399][1]", lambda g: g["robot"]["positions"][399].__setitem__(1, True), "'number'"),
        ("time[5]", lambda g: g["time"].__setitem__(5, "0.5"), "not of type 'number'"),
    ]:
        broken = json.loads(json.dumps(log))
        change(broken)
        with pytest.raises(EpisodeLogError) as info:
            validate_log(broken)
        assert info.value.field == where and words in info.value.problem, str(info.value)


def test_a_file_of_several_episodes_or_a_huge_wrong_value_is_a_short_error(tmp_path):
    log = _good()
    many = tmp_path / "many.json"
    many.write_text(json.dumps([log, log]))
    with pytest.raises(
        EpisodeLogError, match=r"many\.json: \(top level\): a list of 2 entries is not of type 'object'"
    ) as info:
        read_episode_log(many)
    assert "one JSON object per file" in str(info.value) and len(str(info.value)) < 200
    # jsonschema quotes the value it refuses: a whole array of samples was megabytes of message.
    log["robot"]["positions"] = {"xy": log["robot"]["positions"] * 100}
    with pytest.raises(EpisodeLogError) as info:
        validate_log(log)
    assert info.value.field == "robot.positions" and "is not of type 'array'" in info.value.problem
    assert len(str(info.value)) < 200, str(info.value)


def test_a_person_without_velocities_beside_one_with_them():
    # Person 0 gives velocities, person 1 does not: person 0's are used (they were all dropped
    # for the positions' when any person lacked them) and a null velocity at a present sample is
    # taken from the positions (it scored no time to collision there).
    log = make_episode_log(
        dt=1.0, robot_pos=[[0, 0], [0, 0], [0, 0]], goal=[9, 9], robot_radius=0.3, goal_radius=0.1
    )
    # Person 0 stands 3 m away but reports walking at the robot at 1 m/s: (3 - 0.5) / 1 = 2.5 s.
    walker = {"radius": 0.2, "positions": [[3, 0]] * 3, "velocities": [[-1, 0]] * 3}
    # Person 1 walks away, far off: no collision course.
    far = {"radius": 0.2, "positions": [[0, 8], [0, 9], [0, 10]]}
    assert log_metrics({**log, "people": [walker, far]})["gl_min_time_to_collision"] == 2.5
    # Person 2 steps from 4.5 m to 3.5 m towards the robot, its velocity null at sample 1:
    # (3.5 - 0.5) / 1 = 3 s from its positions (not "never").
    stepper = {
        "radius": 0.2,
        "positions": [[5.5, 0], [4.5, 0], [3.5, 0]],
        "velocities": [[-1, 0], None, None],
    }
    assert log_metrics({**log, "people": [stepper]})["gl_min_time_to_collision"] == 3.0


def test_the_log_of_a_crowdnav_episode_has_the_robot_s_own_disc():
    """The CrowdNav robot is a disc of 0.3 m, drawn as a 0.6 m square: its log took the circle round
    the square (0.42 m), so ORCA on frontal approach, test case 0, read an overlap (-0.07 m) and a
    time to collision of 0 where the live path read 0.05 m and 4.8 s."""
    from socialzoo.agents import make_policy
    from socialzoo.bench.replay import record_task_episode
    from socialzoo.env.tasks import make_task

    task = make_task("crowdnav", 1)
    task.reset(np.array([0]), {"split": next(iter(task.case_splits())), "cases": [0]})
    trace = record_task_episode(task, make_policy("orca", task=task), label="orca", laser_rays=0)
    scene = task.viewer_scene("t", "", [trace])
    log = trace_episode_log(trace, scene)
    radius = float(task.config.robot.radius)
    found = log_metrics(log)
    pos, people = np.asarray(trace.robot_pose)[:, None, :2], np.asarray(trace.human_pos)
    gaps = np.linalg.norm(people - pos, axis=2) - radius - scene.human_radius
    gaps = np.where(np.asarray(trace.human_present), gaps, np.inf)
    assert gaps.min() > 0 and found["gl_min_distance_to_human"] == pytest.approx(
        gaps.min()
    )  # ends at its goal
    assert log["robot"]["radius"] == scene.robot_radius == radius
    # A box footprint keeps the circle round it.
    assert trace_episode_log(trace, dataclasses.replace(scene, robot_radius=None))["robot"]["radius"] == (
        pytest.approx(math.hypot(2 * radius, 2 * radius) / 2)
    )


def test_a_robot_outside_the_cooperative_set_is_written_without_a_goal():
    # Trajectories marks another robot outside the cooperative set with a NaN goal; make_episode_log
    # wrote that NaN into the log and refused its own log ("other_robots[1].goal[0]: must be a finite
    # number"). The log's way to say it is a robot without a goal.
    t = np.arange(5.0)
    arrays = dict(
        dt=1.0,
        robot_pos=np.stack([t, 0 * t], axis=1),
        goal=[4, 0],
        robot_radius=0.3,
        goal_radius=0.2,
        others_pos=np.stack([np.stack([t, 0 * t + 5], axis=1), np.full((5, 2), 9.0)], axis=1),
        others_goal=[[4, 5], [np.nan, np.nan]],
    )
    log = make_episode_log(**arrays)
    assert "goal" in log["other_robots"][0] and "goal" not in log["other_robots"][1]
    assert log_metrics(log)["gl_aggregated_time"] == episode_metrics(**arrays)["gl_aggregated_time"] == 4.0
