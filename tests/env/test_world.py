"""The world step on the shipped building maps: invariants, determinism, batch independence."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from socialzoo.core.config import WorldConfig
from socialzoo.core.geometry import segments_intersect
from socialzoo.env.world import step_world
from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.start_state import scenarios_to_state

FULL = ScenarioConfig(min_humans=25, max_humans=25)
WORLD = WorldConfig()


def crowd(map_name, seeds, cfg=FULL):
    m = load_map(map_name)
    return m, scenarios_to_state([generate_scenario(m, s, cfg) for s in seeds])


def random_commands(rng, batch, steps):
    v = rng.uniform(-0.5, 2.5, (steps, batch, 1, 1))
    w = rng.uniform(-4, 4, (steps, batch, 1, 1))
    return np.concatenate((v, w), axis=-1), rng.random((steps, batch, 1)) < 0.05


@pytest.mark.parametrize("map_name", ["gdc1", "ghc3"])
def test_no_human_ever_crosses_a_wall(map_name):
    m, state = crowd(map_name, range(6))
    walls = m.walls
    commands = np.zeros((state.batch_size, 1, 2))
    blocked_total = 0
    for _ in range(600):
        before = state.human_pos
        state, events = step_world(state, m.wall_index, WORLD, commands)
        moved = np.linalg.norm(state.human_pos - before, axis=-1) > 0
        p0, p1 = before[moved], state.human_pos[moved]
        # Brute force over every wall of the map, independent of the grid index.
        hits = segments_intersect(p0[:, None], p1[:, None], walls[None, :, :2], walls[None, :, 2:])
        assert not hits.any(), f"{hits.any(axis=1).sum()} human moves crossed a wall"
        blocked_total += int(events.human_blocked.sum())
    assert np.isfinite(state.human_pos).all()


def test_state_stays_finite_and_within_limits_for_thousands_of_steps():
    m, state = crowd("gdc1", range(4), ScenarioConfig(min_humans=5, max_humans=25))
    rng = np.random.default_rng(0)
    commands, halts = random_commands(rng, state.batch_size, 3000)
    robot = WORLD.robot
    for command, halt in zip(commands, halts, strict=True):
        state, _ = step_world(state, m.wall_index, WORLD, command, halt)
        speed = np.linalg.norm(state.human_vel, axis=-1)
        assert np.all(speed <= state.human_pref_speed + 1e-9)
        assert np.all(np.abs(state.robot_vel[..., 0]) <= robot.max_speed + 1e-12)
        assert np.all(np.abs(state.robot_vel[..., 1]) <= robot.max_angular_speed + 1e-12)
    for field in ("robot_pose", "robot_vel", "human_pos", "human_vel"):
        assert np.isfinite(getattr(state, field)).all(), field
    assert np.all(state.human_vel[~state.human_mask] == 0.0)
    assert np.all(state.step_count == 3000)


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_speed_limits_hold_for_any_commands(seed):
    m, state = crowd("open_room", [seed % 1000], ScenarioConfig(min_humans=5, max_humans=10))
    rng = np.random.default_rng(seed)
    commands, halts = random_commands(rng, 1, 200)
    for command, halt in zip(commands, halts, strict=True):
        previous = state.robot_vel
        state, _ = step_world(state, m.wall_index, WORLD, command, halt)
        dv = np.abs(state.robot_vel - previous)
        limit = np.array([WORLD.robot.max_linear_accel, WORLD.robot.max_angular_accel]) * WORLD.dt
        assert np.all((dv <= limit + 1e-12) | halt[..., None])
        assert np.all(np.linalg.norm(state.human_vel, axis=-1) <= state.human_pref_speed + 1e-9)


def run(m, state, commands):
    trace = []
    for command in commands:
        state, events = step_world(state, m.wall_index, WORLD, command)
        trace.append((state.copy(), events))
    return trace


def test_same_seed_same_trajectory_and_batch_equals_single_runs():
    m = load_map("gdc1")
    seeds = [3, 17, 42]
    scenarios = [generate_scenario(m, s, FULL) for s in seeds]
    rng = np.random.default_rng(1)
    commands, _ = random_commands(rng, len(seeds), 150)
    batched = run(m, scenarios_to_state(scenarios), commands)
    again = run(m, scenarios_to_state(scenarios), commands)
    for (a, _), (b, _) in zip(batched, again, strict=True):
        np.testing.assert_array_equal(a.human_pos, b.human_pos)
    for i, scenario in enumerate(scenarios):
        single = run(m, scenarios_to_state([scenario]), commands[:, i : i + 1])
        for (whole, whole_events), (alone, alone_events) in zip(batched, single, strict=True):
            np.testing.assert_array_equal(whole.human_pos[i], alone.human_pos[0])
            np.testing.assert_array_equal(whole.human_vel[i], alone.human_vel[0])
            np.testing.assert_array_equal(whole.robot_pose[i], alone.robot_pose[0])
            np.testing.assert_array_equal(whole_events.robot_human[i], alone_events.robot_human[0])
    different = run(m, scenarios_to_state([generate_scenario(m, 4, FULL)]), commands[:, :1])
    assert not np.array_equal(different[-1][0].human_pos[0], batched[-1][0].human_pos[0])


def test_collision_events():
    m, state = crowd("open_room", [0], ScenarioConfig(min_humans=5, max_humans=5))
    state.human_pos[0, 0] = state.robot_pose[0, 0, :2] + [0.3, 0.0]
    _, events = step_world(state, m.wall_index, WORLD, np.zeros((1, 1, 2)))
    assert events.robot_human[0, 0, 0]
    # Put the robot on a wall.
    x1, y1, x2, y2 = m.walls[0]
    state.robot_pose[0, 0] = [(x1 + x2) / 2, (y1 + y2) / 2, 0.0]
    _, events = step_world(state, m.wall_index, WORLD, np.zeros((1, 1, 2)))
    assert events.robot_wall[0, 0]


def test_step_without_human_contacts_is_the_same_step_with_none_counted():
    m, state = crowd("open_room", [0], ScenarioConfig(min_humans=5, max_humans=5))
    state.human_pos[0, 0] = state.robot_pose[0, 0, :2] + [0.3, 0.0]
    after, events = step_world(state, m.wall_index, WORLD, np.zeros((1, 1, 2)))
    bare, left = step_world(state, m.wall_index, WORLD, np.zeros((1, 1, 2)), human_contacts=False)
    assert events.robot_human.any() and not left.robot_human.any()
    assert left.robot_human.shape == events.robot_human.shape and left.robot_human.dtype == bool
    assert np.array_equal(left.robot_wall, events.robot_wall)
    assert np.array_equal(bare.human_pos, after.human_pos) and np.array_equal(
        bare.robot_pose, after.robot_pose
    )
