"""The live path of Table I (socialzoo.bench.guideline_recorder) against the log path
(socialzoo.bench.episode_log): hand-made trajectories score the same through both; and the runner
adds the metrics to every episode, the same whatever the batch."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from socialzoo.bench.episode_log import log_metrics, make_episode_log, read_episode_log, write_episode_log
from socialzoo.bench.episodes import play_cases
from socialzoo.bench.guideline_metrics import GUIDELINE_KEYS
from socialzoo.bench.guideline_recorder import GuidelineRecorder
from socialzoo.core.config import WorldConfig
from socialzoo.core.state import WorldState
from socialzoo.env.config import EnvConfig
from socialzoo.env.core import BatchedCore
from socialzoo.env.world import robot_collisions
from socialzoo.maps.map_file import load_map

DT = 0.025


def _hand_made(kind: str) -> dict[str, np.ndarray]:
    """Robot 0 drives along the hallway's corridor (y = 4.5) at speeds set by hand; one person
    walks towards it, one stands by the wall."""
    n = 240
    t = np.arange(n) * DT
    if kind == "cruise":
        speed = np.minimum(1.2, 2.0 * t)
    elif kind == "stop_and_go":
        speed = np.where((t > 2.0) & (t < 3.5), 0.0, 1.0)
    else:  # "into the person": fast, straight at it
        speed = np.full(n, 1.5)
    x = 9.0 + np.concatenate(([0.0], np.cumsum(speed[1:] * DT)))
    robot = np.stack([x, np.full(n, 4.5)], axis=1)
    walker = np.stack([15.0 - 0.8 * t, np.full(n, 4.5 + (0.0 if kind == "into" else 0.7))], axis=1)
    stander = np.tile([12.0, 3.8], (n, 1))
    people = np.stack([walker, stander], axis=1)
    vel = np.stack([np.tile([-0.8, 0.0], (n, 1)), np.zeros((n, 2))], axis=1)
    return {"robot": robot, "speed": speed, "people": people, "people_vel": vel}


def _states(traj: dict[str, np.ndarray]) -> list[WorldState]:
    n = len(traj["robot"])
    goal = np.array([[[20.0, 4.5, 0.0]]])
    out = []
    for k in range(n):
        out.append(
            WorldState(
                robot_pose=np.array([[[*traj["robot"][k], 0.0]]]),
                robot_vel=np.array([[[traj["speed"][k], 0.0]]]),
                robot_goal=goal,
                human_pos=traj["people"][k][None].copy(),
                human_vel=traj["people_vel"][k][None].copy(),
                human_pref_speed=np.ones((1, 2)),
                human_mask=np.ones((1, 2), dtype=bool),
                human_route=np.zeros((1, 2, 1, 2)),
                human_route_len=np.ones((1, 2), dtype=np.int64),
                human_waypoint=np.zeros((1, 2), dtype=np.int64),
                human_direction=np.ones((1, 2), dtype=np.int64),
                step_count=np.array([k]),
                noise_key=np.zeros(1, dtype=np.uint64),
            )
        )
    return out


@pytest.mark.parametrize("kind", ["cruise", "stop_and_go", "into"])
def test_hand_made_trajectories_score_the_same_live_and_through_a_json_log(kind, tmp_path):
    m = load_map("hallway")
    world = WorldConfig()
    config = EnvConfig(map="hallway", max_steps=2400)
    core = BatchedCore(1, 1, 2, world, m.wall_index, m=m)
    task = SimpleNamespace(core=core, config=config, batch_size=1)
    states = _states(_hand_made(kind))
    # Live: the recorder samples the core's state as the runner does after every step.
    core.state = states[0]
    recorder = GuidelineRecorder(task)
    recorder.reset(np.array([0]), task)
    for s in states[1:]:
        core.state = s
        recorder.record(task)
    live = recorder.summaries(np.array([0]))[0]
    # Log: the same trajectories and the world's contact flags written as JSON and read back.
    flags = [robot_collisions(s, m.wall_index, world) for s in states]
    traj = _hand_made(kind)
    log = make_episode_log(
        dt=DT,
        robot_pos=traj["robot"],
        robot_vel=np.stack([traj["speed"], np.zeros(len(traj["speed"]))], axis=1),
        goal=[20.0, 4.5],
        robot_radius=math.hypot(world.robot.length, world.robot.width) / 2,
        goal_radius=config.goal_radius,
        people_pos=traj["people"],
        people_vel=traj["people_vel"],
        people_radius=world.human.radius,
        walls=m.walls,
        shortest_path_length=11.0,
        time_limit=config.max_steps * world.dt,
        wall_contact=[bool(w[0, 0]) for w, _ in flags],
        human_contact=[bool(h[0, 0].any()) for _, h in flags],
    )
    path = write_episode_log(tmp_path / f"{kind}.json", log)
    logged = log_metrics(read_episode_log(path))
    assert list(live) == list(GUIDELINE_KEYS) == list(logged)
    for key in GUIDELINE_KEYS:
        assert live[key] == pytest.approx(logged[key], rel=1e-9, abs=1e-9, nan_ok=True), key
    if kind == "into":
        assert live["gl_human_collisions"] >= 1 and live["gl_min_distance_to_human"] < 0
    if kind == "stop_and_go":
        assert live["gl_stalled_time"] == pytest.approx(1.5, abs=2 * DT)


def test_the_runner_adds_table_one_to_every_episode_whatever_the_batch():
    def go_alone(obs, task):
        return np.zeros(len(obs), dtype=np.int64)

    kwargs = {"map": "hallway", "family": "hallway_head_on", "max_steps": 2400, "guideline_metrics": True}
    three = play_cases("action_selection", go_alone, "val", range(4), batch_size=2, **kwargs)
    four = play_cases("action_selection", go_alone, "val", range(4), batch_size=4, **kwargs)
    for a, b in zip(three, four, strict=True):
        assert set(GUIDELINE_KEYS) <= set(a)
        for key in GUIDELINE_KEYS:
            assert a[key] == pytest.approx(b[key], nan_ok=True), key
        # Table I's success agrees with the task's own when nothing collided.
        if a["gl_collisions"] == 0 and not a["gl_timeout"]:
            assert bool(a["gl_success"]) == bool(a["success"])


def test_table_one_times_out_where_the_task_s_own_time_limit_ended_the_episode():
    # CrowdNav ends an episode at the step starting 1 s before its time limit (4.25 s of a 5 s limit
    # here): Table I's timeout is the task's, not "the episode lasted 5 s", which it never does.
    from socialzoo.env.crowd_config import CrowdNavConfig

    def stand_still(obs, task):
        return np.zeros((len(obs), 2), dtype=np.float32)

    config = CrowdNavConfig.variant("").replace(observation="flat", time_limit=5.0)
    (episode,) = play_cases(
        "crowdnav", stand_still, "val", [0], batch_size=1, config=config, guideline_metrics=True
    )
    assert episode["timeout"] == 1.0 and episode["steps"] == 17
    assert episode["gl_timeout"] and not episode["gl_success"] and episode["gl_collisions"] == 0


def test_table_one_counts_a_collision_the_crowdnav_task_judged_in_the_middle_of_a_step(monkeypatch):
    # The robot drives +y at 1 m/s (0.25 m a step) past a person standing 0.59 m off its line (radii
    # 0.3 + 0.3): the step from y = -0.125 to 0.125 comes within 0.59 m half-way (the task's
    # collision) and ends 0.603 m apart, where the world's contact flags see nothing.
    from socialzoo.env.crowd_config import CrowdNavConfig
    from socialzoo.env.crowd_source import CrowdCaseSource
    from socialzoo.scenarios.crowd_cases import CrowdCase

    config = CrowdNavConfig.variant("").replace(observation="flat")
    people = np.array([[0.59, 0.0]] + [[-5.0 - k, 5.0] for k in range(config.cases.num_humans - 1)])
    case = CrowdCase(
        seed=0,
        robot_starts=np.array([[0.0, -1.125, math.pi / 2]]),
        robot_goals=np.array([[0.0, 4.0, math.pi / 2]]),
        human_starts=people,
        human_goals=people.copy(),  # standing still
    )
    monkeypatch.setattr(CrowdCaseSource, "fixed", lambda self, split, indices: [case for _ in indices])

    def ahead(obs, task):
        return np.tile(np.array([1.0, 0.0], dtype=np.float32), (len(obs), 1))

    (episode,) = play_cases(
        "crowdnav", ahead, "val", [0], batch_size=1, config=config, guideline_metrics=True
    )
    assert episode["collision"] == 1.0 and episode["steps"] == 5
    assert 0 < episode["gl_min_distance_to_human"] < 0.01  # apart at every sample
    assert episode["gl_human_collisions"] == episode["gl_collisions"] == 1 and not episode["gl_success"]


def test_a_closed_door_is_a_wall_for_the_clearing_distance_as_for_the_contacts():
    """GoAlone drives into the closed elevator door of exiting an elevator (suite o, test case 0): the
    live path counted the contact as a wall collision but measured the clearing distance to the map's
    walls only, 0.30 m, as if nothing had been near."""
    from socialzoo.agents import make_policy
    from socialzoo.bench.episodes import play_cases
    from socialzoo.bench.suite import SuiteScenario, suite_task

    scenario = SuiteScenario("exiting_elevator", "o", "Exiting an elevator", "elevator", "")
    task = suite_task("action_selection", scenario)
    probe = task.make(1)
    (episode,) = play_cases(
        task.task,
        make_policy("goalone", task=probe).act,
        "test",
        [0],
        config=probe.config,
        guideline_metrics=True,
    )
    assert episode["gl_wall_collisions"] >= 1
    assert episode["gl_clearing_distance_min"] < 0
