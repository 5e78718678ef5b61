"""ORCA people: the reference library's answers, circle swaps, head-on pairs, walls and doors, and
results that do not depend on the batch row."""

import dataclasses

import numpy as np
import pytest

from socialzoo.core.config import OrcaConfig, WorldConfig
from socialzoo.core.walls import WallIndex
from socialzoo.humans.orca import orca_velocities
from socialzoo.humans.people import step_people

# One step of six agents (radius 0.25, max speed 1.2; neighbor_dist 4, max_neighbors 10,
# time_horizon 2, time_horizon_obst 1, dt 0.025) among walls given as two-vertex obstacles, as
# the reference library RVO2 (snape/RVO2, float32) answered them: walls, positions, velocities,
# preferred velocities, new velocities. A box, a corridor with a door (agents touching its walls),
# and no walls.
REFERENCE = [
    (
        [[0.0, 0.0, 8.0, 0.0], [8.0, 0.0, 8.0, 6.0], [8.0, 6.0, 0.0, 6.0], [0.0, 6.0, 0.0, 0.0]],
        [[4.6, 4.91], [5.32, 1.68], [3.04, 4.79], [1.63, 4.54], [5.43, 2.85], [3.05, 1.94]],
        [[0.08, -0.74], [-0.02, 0.56], [-1.08, -0.37], [-1.52, -1.03], [-1.47, -0.19], [-1.01, 0.22]],
        [[0.16, -0.19], [-2.52, -0.54], [-0.05, 0.11], [-1.53, -0.48], [-0.98, -0.81], [1.06, -0.81]],
        [
            [0.16, -0.19],
            [-0.8746305, -0.3773988],
            [-0.1329974, 0.1232626],
            [-0.9897322, -0.67855],
            [-1.115416, -0.4425468],
            [-0.6986744, -0.9184112],
        ],
    ),
    (
        [[0.0, 3.0, 3.5, 3.0], [4.5, 3.0, 8.0, 3.0], [0.0, 6.0, 8.0, 6.0], [0.0, 0.0, 8.0, 0.0]],
        [[1.62, 4.58], [2.34, 1.88], [5.83, 3.05], [5.67, 3.67], [5.16, 1.04], [4.2, 3.04]],
        [[-0.51, 1.6], [0.61, -0.96], [0.06, 0.46], [-0.15, 0.55], [-0.05, 0.53], [1.15, -0.54]],
        [[0.2, -0.46], [0.13, -1.19], [-0.58, -0.2], [0.9, 1.15], [-1.32, -0.79], [0.65, -1.99]],
        [
            [0.1247454, -0.2611855],
            [0.13, -1.19],
            [-0.400127, 0.2771378],
            [0.6712653, 0.9946874],
            [-0.5844368, 0.2594037],
            [-0.1534849, 0.3049975],
        ],
    ),
    (
        [],
        [[4.78, 1.23], [5.66, 5.14], [5.94, 3.33], [2.3, 1.52], [6.05, 3.25], [2.47, 4.84]],
        [[-0.16, -0.89], [-0.01, -0.35], [0.93, 0.52], [-0.02, 0.53], [-0.27, 0.84], [-0.0, 0.47]],
        [[-1.29, 0.35], [-1.69, -2.04], [-0.3, -0.9], [0.16, 2.24], [-0.83, -0.62], [0.21, 0.49]],
        [
            [-0.8110976, -0.3313473],
            [0.3573734, -0.7449723],
            [-0.8919541, 0.8027566],
            [0.08549646, 1.19695],
            [0.8919541, -0.8027566],
            [0.21, 0.49],
        ],
    ),
]
FAR_WALL = np.array([[100.0, 100.0, 101.0, 100.0]])


def orca(pos, vel, pref, walls, cfg, dt, radius=None, speed=None, seen=None):
    """ORCA velocities of agents given as (N, 2) arrays of one row."""
    n = len(pos)
    ones = np.ones((1, n), bool)
    radius = np.full((1, n), cfg.radius) if radius is None else np.asarray(radius, float)[None]
    speed = np.full((1, n), cfg.max_speed or 1.0) if speed is None else np.asarray(speed, float)[None]
    seen = ones if seen is None else np.asarray(seen, bool)[None]
    return orca_velocities(pos[None], vel[None], pref[None], radius, speed, ones, ones, seen, walls, cfg, dt)[
        0
    ]


@pytest.mark.parametrize("case", range(len(REFERENCE)))
def test_one_step_matches_the_reference_library(case):
    walls, pos, vel, pref, expected = (np.array(a, float) for a in REFERENCE[case])
    index = WallIndex(walls.reshape(-1, 4) if len(walls) else FAR_WALL)
    cfg = OrcaConfig(
        neighbor_dist=4.0, max_neighbors=10, time_horizon=2.0, time_horizon_obst=1.0, radius=0.25
    )
    got = orca(pos, vel, pref, index, cfg, 0.025, speed=np.full(6, 1.2))
    np.testing.assert_allclose(got, expected, atol=1e-4)


def walk(pos, goal, walls, cfg, dt, seconds, via=None, **kw):
    """Agents walking to their goals (through the points `via` first, if given: the next target
    once within 0.5 m); returns the trajectory (steps, N, 2)."""
    vel = np.zeros_like(pos)
    trace = [pos]
    passed = np.zeros(len(pos), bool)
    for _ in range(int(seconds / dt)):
        if via is not None:
            passed |= np.linalg.norm(via - pos, axis=-1) < 0.5
        target = goal if via is None else np.where(passed[:, None], goal, via)
        to_goal = target - pos
        dist = np.linalg.norm(to_goal, axis=-1, keepdims=True)
        pref = np.where(dist > 1.0, to_goal / np.maximum(dist, 1e-9), to_goal)
        vel = orca(pos, vel, pref, walls, cfg, dt, **kw)
        pos = pos + dt * vel
        trace.append(pos)
    return np.array(trace)


def min_gap(trace):
    diff = np.linalg.norm(trace[:, :, None] - trace[:, None], axis=-1)
    n = trace.shape[1]
    return diff[:, ~np.eye(n, dtype=bool)].min()


@pytest.mark.parametrize("preset", ["crowdnav", "socialzoo"])
def test_agents_on_a_circle_swap_to_the_antipodes_without_overlap(preset):
    cfg = OrcaConfig.preset(preset)
    n = 10
    angle = np.arange(n) * 2 * np.pi / n
    # A little noise on the circle, as CrowdNav's circle crossing has: a perfectly symmetric
    # circle jams ORCA (in the reference library too), each agent waiting for the others.
    pos = 4.0 * np.stack((np.cos(angle), np.sin(angle)), -1) + np.random.default_rng(0).uniform(
        -0.3, 0.3, (n, 2)
    )
    trace = walk(pos, -pos, WallIndex(FAR_WALL), cfg, 0.025, 30.0)
    assert np.abs(trace[-1] + pos).max() < 0.05, "everyone arrives"
    assert min_gap(trace) > 2 * cfg.radius - 1e-3


def test_head_on_pair_passes_without_contact():
    cfg = OrcaConfig.preset("crowdnav")
    # Head on, 10 cm apart sideways. (Exactly in line, both slow down facing each other and
    # never pass: the reference library does the same.)
    pos = np.array([[0.0, 0.0], [8.0, 0.1]])
    trace = walk(pos, pos[::-1].copy(), WallIndex(FAR_WALL), cfg, 0.025, 16.0)
    assert min_gap(trace) > 2 * cfg.radius - 1e-6
    assert np.abs(trace[-1] - pos[::-1]).max() < 0.05
    # Each steps aside to its right: the one walking +x to -y, the other to +y.
    assert trace[:, 0, 1].min() < -0.1 and trace[:, 1, 1].max() > 0.2


def wall_distance(points, walls):
    a, b = walls[:, :2], walls[:, 2:]
    ab = b - a
    t = np.clip(((points[:, None] - a) * ab).sum(-1) / (ab**2).sum(-1), 0, 1)
    return np.linalg.norm(points[:, None] - (a + t[..., None] * ab), axis=-1).min(-1)


def test_agent_along_a_wall_keeps_its_radius_off_it():
    cfg = OrcaConfig(time_horizon_obst=1.0)
    walls = np.array([[0.0, 0.0, 10.0, 0.0]])
    # Walking parallel to the wall, then asked to walk into it at an angle.
    pos = np.array([[0.5, 0.6]])
    trace = walk(pos, np.array([[9.0, -3.0]]), WallIndex(walls), cfg, 0.025, 12.0, speed=[1.0])
    distance = wall_distance(trace[:, 0], walls)
    assert distance.min() > cfg.radius - 1e-6
    assert trace[-1, 0, 0] > 7.5, "it slides along the wall towards its goal"


def test_agents_through_a_door_never_cut_its_walls():
    cfg = OrcaConfig(time_horizon_obst=1.0)
    # A wall at x = 5 with a 1.2 m door between y = 2.4 and 3.6; four agents go through it.
    walls = np.array([[5.0, 0.0, 5.0, 2.4], [5.0, 3.6, 5.0, 6.0], [0, 0, 10, 0], [0, 6, 10, 6]], float)
    pos = np.array([[1.0, 1.0], [1.0, 2.5], [1.5, 4.0], [1.0, 5.0]])
    goal = np.array([[9.0, 3.0], [9.0, 1.0], [9.0, 5.0], [9.0, 4.0]])
    # Through the door's middle, as a route's waypoint leads them (ORCA itself is local: walking
    # straight at a goal behind the wall, one slides along the wall and stays there).
    door = np.tile([[5.0, 3.0]], (4, 1))
    trace = walk(pos, goal, WallIndex(walls), cfg, 0.025, 30.0, via=door)
    assert np.abs(trace[-1] - goal).max() < 0.1, "everyone gets through the door"
    assert wall_distance(trace.reshape(-1, 2), walls).min() > cfg.radius - 1e-3
    assert min_gap(trace) > 2 * cfg.radius - 1e-3


def test_an_invisible_agent_is_not_avoided_but_sees_the_others():
    cfg = OrcaConfig()
    pos = np.array([[0.0, 0.0], [1.0, 0.0]])
    vel = np.array([[1.0, 0.0], [-1.0, 0.0]])
    seen = [True, False]
    got = orca(pos, vel, vel.copy(), WallIndex(FAR_WALL), cfg, 0.025, seen=seen)
    np.testing.assert_array_equal(got[0], vel[0])  # agent 1 is invisible: 0 walks straight on
    assert got[1, 1] != 0.0  # agent 1 still avoids agent 0


def test_rows_step_the_same_alone_or_in_any_batch():
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
    from socialzoo.scenarios.start_state import scenarios_to_state

    m = load_map("gdc1")
    scenarios = [generate_scenario(m, s, ScenarioConfig(min_humans=20, max_humans=25)) for s in (3, 8, 11)]
    world = WorldConfig()
    robot = np.array([[[1.0, 0.5]]])

    def run(state):
        state.human_model[:] = 1
        states = []
        for _ in range(60):
            target = state.human_target
            robot_pos = state.robot_pose[..., :2]
            pos, vel, _ = step_people(
                state.human_pos, state.human_vel, target, state.human_pref_speed, state.human_mask,
                state.human_model, state.human_group, robot_pos, np.repeat(robot, len(robot_pos), 0),
                m.wall_index, world,
            )  # fmt: skip
            state.human_pos, state.human_vel = pos, vel
            states.append(pos.copy())
        return np.array(states)

    batched = run(scenarios_to_state(scenarios, max_humans=25))
    for i, scenario in enumerate(scenarios):
        alone = run(scenarios_to_state([scenario], max_humans=25))
        np.testing.assert_array_equal(batched[:, i], alone[:, 0])


def test_bad_parameters_are_refused_naming_them():
    with pytest.raises(ValueError, match=r"OrcaConfig.radius must be > 0"):
        OrcaConfig(radius=-0.3)
    with pytest.raises(ValueError, match=r"OrcaConfig.max_neighbors must be an int >= 0"):
        OrcaConfig(max_neighbors=2.5)
    with pytest.raises(ValueError, match=r"OrcaConfig.max_speed must be > 0"):
        OrcaConfig(max_speed=0.0)
    with pytest.raises(ValueError, match="unknown ORCA parameter set 'rvo'"):
        OrcaConfig.preset("rvo")
    crowdnav = OrcaConfig.preset("crowdnav")
    assert (crowdnav.neighbor_dist, crowdnav.max_neighbors, crowdnav.time_horizon) == (10.0, 10, 5.0)
    assert (crowdnav.time_horizon_obst, crowdnav.radius, crowdnav.max_speed) == (5.0, 0.3, 1.0)
    invisible = dataclasses.replace(crowdnav, robot_visible=False)
    assert not invisible.robot_visible


def test_a_wall_seen_exactly_end_on_is_avoided_as_one_seen_slightly_askew():
    # Walking along the line of a wall at its end: the wall has no side, yet its near end is in the
    # way. Dropping it (as RVO2 does) walked the agent into the wall; now the answer is the limit of
    # the answers slightly off the line.
    cfg = OrcaConfig()
    walls = WallIndex(np.array([[0.0, 0.0, 5.0, 0.0]]))
    vel = pref = np.array([[1.0, 0.0]])
    on_line = orca(np.array([[-0.5, 0.0]]), vel, pref, walls, cfg, 0.1)
    askew = orca(np.array([[-0.5, 1e-12]]), vel, pref, walls, cfg, 0.1)
    assert on_line[0, 0] < 0.5, "it slows down for the wall's end"
    np.testing.assert_allclose(on_line, askew, atol=1e-9)


def test_a_post_is_avoided_as_the_end_of_a_wall_seen_end_on():
    # A zero-length wall acts as a point (socialzoo.maps.map_file); ORCA used to drop it, so its
    # people walked through posts. Its velocity obstacle is the point's alone: that of a wall
    # starting at the post and pointing straight away from the agent.
    cfg = OrcaConfig(time_horizon_obst=1.0)
    pos, vel, pref = np.array([[-0.5, 0.2]]), np.array([[1.0, -0.1]]), np.array([[1.0, 0.0]])
    post = orca(pos, vel, pref, WallIndex(np.array([[0.0, 0.0, 0.0, 0.0]])), cfg, 0.025)
    end_on = orca(pos, vel, pref, WallIndex(np.array([[0.0, 0.0, 1.0, -0.4]])), cfg, 0.025)
    assert np.abs(post - pref).max() > 0.1
    np.testing.assert_allclose(post, end_on, atol=1e-9)
    trace = walk(np.array([[-3.0, 0.0]]), np.array([[3.0, 0.0]]), WallIndex(np.array([[0.0, 0.05, 0.0, 0.05]])),
                 cfg, 0.025, 10.0, speed=[1.0])  # fmt: skip
    assert np.linalg.norm(trace[:, 0] - [0.0, 0.05], axis=-1).min() > cfg.radius - 1e-3
    assert np.abs(trace[-1, 0] - [3.0, 0.0]).max() < 0.1, "it goes round the post"
