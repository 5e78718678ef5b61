"""The episode recorder: a trace holds every state and step of the episode the runner plays, the
same for the same seed, with the laser scanned where asked."""

import math

import numpy as np
import pytest

from socialzoo.agents import make_policy
from socialzoo.bench.replay import (
    PolicySpec,
    benchmark_scenario,
    record_episode,
    record_policies,
    replay_scene,
)
from socialzoo.bench.runner import BatchedRunner, Trial, make_spec
from socialzoo.core.config import LaserConfig
from socialzoo.env.config import EnvConfig
from socialzoo.env.metrics import SUMMARY_KEYS
from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet

MAX_STEPS = 160


@pytest.fixture(scope="module")
def rooms(rooms_map_path):
    config = EnvConfig(
        map=str(rooms_map_path),
        max_steps=MAX_STEPS,
        scenario=ScenarioConfig(min_humans=3, max_humans=6),
    )
    return config, load_map(config.map)


@pytest.fixture(scope="module")
def ref_trace(rooms):
    config, m = rooms
    scenario = benchmark_scenario(config, 4, m)
    return record_episode(config, scenario, make_policy("ref"), laser_rays=30, laser_stride=3, world_map=m)


def test_trace_shapes_and_consistency(rooms, ref_trace):
    config, m = rooms
    trace = ref_trace
    t, h = trace.num_steps, trace.num_humans
    assert 0 < t <= MAX_STEPS
    assert trace.metrics["steps"] == t
    assert trace.robot_pose.shape == (t + 1, 3) and trace.robot_vel.shape == (t + 1, 2)
    assert trace.human_pos.shape == trace.human_vel.shape == (t + 1, h, 2) and 3 <= h <= 6
    assert trace.carrot.shape == (t + 1, 2) and trace.plan_index.shape == (t + 1,)
    for name in ("action", "target_human", "reward", "force", "blame", "human_collisions", "wall_collision"):
        assert getattr(trace, name).shape == (t,), name
    # The per-step series add up to the episode's metrics.
    assert math.isclose(trace.reward.sum(), trace.metrics["total_reward"], rel_tol=1e-12)
    assert math.isclose(trace.force.mean(), trace.metrics["mean_force"], rel_tol=1e-12)
    assert trace.blame.max() == trace.metrics["max_blame"]
    assert int((trace.human_collisions > 0).sum()) == trace.metrics["human_collisions"]
    # The start state is the scenario's, the trace ends where the metrics say.
    scenario = benchmark_scenario(config, 4, m)
    np.testing.assert_array_equal(trace.robot_pose[0], scenario.robot_starts[0])
    np.testing.assert_array_equal(trace.goal, scenario.robot_goals[0])
    final = np.hypot(*(trace.robot_pose[-1, :2] - trace.goal[:2]))
    assert math.isclose(final, trace.metrics["distance_from_goal"], rel_tol=1e-12)
    assert set(np.unique(trace.action)) <= {0, 1, 2}  # Ref never passes
    assert trace.target_human.min() >= -1 and trace.target_human.max() < h
    assert len(trace.plans) >= 1 and all(p.shape[1] == 2 for p in trace.plans)


def test_laser_is_scanned_every_stride_and_at_the_end(rooms, ref_trace):
    config, _ = rooms
    trace = ref_trace
    expected = list(range(0, trace.num_steps + 1, 3))
    if expected[-1] != trace.num_steps:
        expected.append(trace.num_steps)
    assert trace.laser_steps.tolist() == expected
    assert trace.laser_ranges.shape == (len(expected), 30) and trace.laser_angles.shape == (30,)
    assert np.all((trace.laser_ranges > 0) & (trace.laser_ranges <= trace.laser_max_range))
    # Inside the closed rooms map every ray hits a wall or a human well within range.
    assert trace.laser_ranges.max() < 15.0
    # The scan is the laser's own: a robot's first scan ends on the walls around it.
    from socialzoo.core.laser import laser_scan
    from socialzoo.env.tasks.action_selection import ActionSelectionTask

    task = ActionSelectionTask(config, 1)
    task.reset_rows([0], [benchmark_scenario(config, 4)])
    ranges = laser_scan(
        task.core.state, task.core.walls, LaserConfig(num_rays=30), config.world.human.radius
    )[0, 0]
    np.testing.assert_array_equal(trace.laser_ranges[0], ranges)


def test_no_laser(rooms):
    config, m = rooms
    trace = record_episode(config, benchmark_scenario(config, 1, m), make_policy("goalone"), laser_rays=0)
    assert trace.laser_angles.shape == (0,) and trace.laser_steps.tolist() == [0]
    assert trace.laser_ranges.shape == (1, 0)


def test_same_seed_same_trace(rooms, ref_trace):
    config, m = rooms
    again = record_episode(
        config, benchmark_scenario(config, 4, m), make_policy("ref"), laser_rays=30, laser_stride=3
    )
    for name in (
        "robot_pose",
        "human_pos",
        "human_vel",
        "carrot",
        "laser_ranges",
        "action",
        "reward",
        "blame",
    ):
        np.testing.assert_array_equal(getattr(again, name), getattr(ref_trace, name), err_msg=name)
    assert again.metrics == pytest.approx(ref_trace.metrics, nan_ok=True)
    other = record_episode(config, benchmark_scenario(config, 5, m), make_policy("ref"), laser_rays=30)
    assert not np.array_equal(other.robot_pose[0], ref_trace.robot_pose[0])


def test_recording_is_the_runners_episode(rooms_map_path):
    """The recorder's metrics equal the benchmark runner's for the same trial (batched there)."""
    test_set = TestSet(str(rooms_map_path), 5, 4, ScenarioConfig(min_humans=3, max_humans=6), name="rooms")
    spec = make_spec(["ref"], [test_set], batch_size=3, env_overrides={"max_steps": MAX_STEPS})
    results = BatchedRunner(spec).run([Trial("ref", "rooms", k) for k in range(4)])
    config = spec.env_configs["rooms"]
    m = load_map(config.map)
    for k in (0, 3):
        scenario = test_set.scenario(k)
        trace = record_episode(config, scenario, make_policy("ref"), laser_rays=0, world_map=m)
        for key in SUMMARY_KEYS:
            assert trace.metrics[key] == pytest.approx(results[k].metrics[key], nan_ok=True, rel=0, abs=0), (
                key
            )


def test_record_policies_side_by_side(rooms):
    config, m = rooms
    scenario = benchmark_scenario(config, 2, m)
    specs = [PolicySpec.parse("goalone"), PolicySpec.parse("REF")]
    traces = record_policies(config, scenario, specs, laser_rays=10, laser_stride=5, world_map=m)
    assert [t.label for t in traces] == ["goalone", "ref"]
    assert (traces[0].action == 0).all()
    np.testing.assert_array_equal(traces[0].robot_pose[0], traces[1].robot_pose[0])
    np.testing.assert_array_equal(traces[0].human_pos[0], traces[1].human_pos[0])
    scene = replay_scene(config, m, "title")
    assert scene.map_name == "rooms" and scene.walls.shape == (len(m.walls), 4)
    assert (scene.robot_length, scene.robot_width) == (0.5, 0.43)
    with pytest.raises(ValueError, match="unknown policy 'robocop'"):
        record_policies(config, scenario, [PolicySpec.parse("robocop")])
    with pytest.raises(ValueError, match="at least one policy"):
        record_policies(config, scenario, [])


def test_policy_spec_parse():
    assert PolicySpec.parse("ref") == PolicySpec("ref", {}, "ref")
    spec = PolicySpec.parse("PPO=runs/a/model.zip")
    assert (spec.name, spec.kwargs, spec.label) == ("ppo", {"path": "runs/a/model.zip"}, "ppo (model.zip)")
    with pytest.raises(ValueError, match="NAME or NAME=PATH"):
        PolicySpec.parse("=x")
    with pytest.raises(ValueError, match="policy 'goalone' is not loaded from a file"):
        PolicySpec.parse("goalone=x.zip").build()


def test_bad_recorder_arguments(rooms):
    config, m = rooms
    scenario = benchmark_scenario(config, 1, m)
    with pytest.raises(ValueError, match="laser_stride must be an int >= 1, got 0"):
        record_episode(config, scenario, make_policy("ref"), laser_stride=0)
    with pytest.raises(ValueError, match="laser_rays must be an int >= 0 or None, got -1"):
        record_episode(config, scenario, make_policy("ref"), laser_rays=-1)


def test_a_policy_of_observations_alone_is_recorded_with_its_flat_batch():
    """The learned CrowdNav policies take (N, D) observations: the recorder gives them that, as the
    runner does (the suite's replay pages of suite_crowdnav)."""
    import numpy as np

    from socialzoo.agents import make_policy
    from socialzoo.bench.replay import record_task_episode
    from socialzoo.bench.task_benchmark import TaskId

    task_id = TaskId.of("socialzoo/CrowdNavSuite-v2")
    probe = task_id.make(1, family="frontal_approach")
    policy = make_policy("suite_crowdnav", task=probe.name, observation_space=probe.observation_space)
    assert not policy.reads_core
    task = task_id.make(1, family="frontal_approach", **policy.task_overrides)
    task.reset(np.array([0]), {"split": "test", "cases": [0]})
    trace = record_task_episode(task, policy, label="suite_crowdnav")
    assert trace.outcome in ("success", "collision", "timeout") and len(trace.robot_pose) > 1


def test_people_who_enter_and_leave_a_recorded_scene_are_kept_with_their_presence(tmp_path, monkeypatch):
    """The recorder kept only the people present in the first state: in a recorded scene those who
    entered later were never drawn, and those who left stayed drawn where they left."""
    from socialzoo.data.tracks import Recording, Track
    from socialzoo.scenarios.catalogue import FAMILIES, register_family
    from socialzoo.scenarios.recorded import RecordedScene

    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))
    name = "recorded_come_and_go"
    if name not in FAMILIES:
        # Whichever track the robot takes, someone enters (at frame 8) or leaves (at frame 25)
        # while it drives.
        walkers = tuple(
            Track(p, first, np.linspace([-6.0 + 3 * p, -6.0], [-6.0 + 3 * p, 6.0], last - first))
            for p, (first, last) in enumerate([(0, 40), (0, 25), (0, 25), (8, 40), (8, 40)])
        )
        recording = Recording(name="come_and_go", dt=0.4, num_frames=40, tracks=walkers, source="test")
        register_family(RecordedScene(recording))
    config = EnvConfig(family=name, max_steps=400)
    m = load_map(config.map)
    trace = record_episode(config, benchmark_scenario(config, 100, m), make_policy("goalone"), world_map=m)
    present = trace.human_present
    assert present.shape == (trace.num_steps + 1, trace.num_humans) == (trace.num_steps + 1, 4)
    assert not present[0].all() or not present[-1].all()  # kept though absent at the start or end
    assert np.isfinite(trace.human_pos[present]).all()


@pytest.mark.parametrize(
    ("env_id", "policy"), [("socialzoo/ActionSelection-v2", "ref"), ("socialzoo/CrowdNav-v1", "orca")]
)
def test_a_task_of_two_robots_is_recorded_with_the_other_robot(env_id, policy):
    """`socialzoo replay --env ID --task-config num_robots=2` failed with numpy's 'cannot reshape
    array of size 2 into shape (1,1)': the recorder gave the task one robot's action. Every robot
    acts; robot 0 is the panel's, the others are kept to be drawn."""
    from socialzoo.bench.replay import record_case
    from socialzoo.bench.task_benchmark import TaskId

    limit = {"max_steps": 30} if "ActionSelection" in env_id else {"time_limit": 3.0}
    probe = TaskId.of(env_id).make(1, num_robots=2, **limit)
    acting = make_policy(policy, task=probe.name, observation_space=probe.observation_space)
    trace, _ = record_case(env_id, acting, "test", 0, num_robots=2, **limit)
    assert trace.other_robots.shape == (trace.num_steps + 1, 1, 3) and 0 < trace.num_steps <= 40
    assert np.ptp(trace.other_robots[:, 0, :2], axis=0).max() > 0.05  # it drives too
