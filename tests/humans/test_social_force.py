"""The batched social force equals a literal scalar transcription of PedSim's model."""

import math

import numpy as np
import pytest

from socialzoo.core.config import HumanConfig
from socialzoo.core.walls import WallIndex
from socialzoo.humans.routes import advance_waypoints
from socialzoo.humans.social_force import human_acceleration

CFG = HumanConfig()


def _moussaid(p, v, q, w, cfg):
    """PedSim's Agent::socialForce for one other agent, written out with scalars."""
    dx, dy = q[0] - p[0], q[1] - p[1]
    dist = math.hypot(dx, dy)
    ex, ey = dx / dist, dy / dist
    ix, iy = cfg.social_lambda * (v[0] - w[0]) + ex, cfg.social_lambda * (v[1] - w[1]) + ey
    ilen = math.hypot(ix, iy)
    ix, iy = ix / ilen, iy / ilen
    theta = math.atan2(ey, ex) - math.atan2(iy, ix)
    theta = (theta + math.pi) % (2 * math.pi) - math.pi
    b = cfg.social_gamma * ilen
    speed = -math.exp(-dist / b - (cfg.social_n_prime * b * theta) ** 2)
    angle = -math.copysign(1.0, theta) * math.exp(-dist / b - (cfg.social_n * b * theta) ** 2)
    return speed * ix + angle * -iy, speed * iy + angle * ix


def _reference(pos, vel, target, speed, robot_pos, robot_vel, walls, cfg):
    out = np.zeros_like(pos)
    for i in range(len(pos)):
        d = target[i] - pos[i]
        e = d / np.linalg.norm(d)
        fx, fy = (e * speed[i] - vel[i]) / cfg.relaxation_time * cfg.desired_factor
        for j in range(len(pos)):
            if j != i:
                sx, sy = _moussaid(pos[i], vel[i], pos[j], vel[j], cfg)
                fx, fy = fx + cfg.social_strength * sx, fy + cfg.social_strength * sy
        for r in range(len(robot_pos)):
            scaled = pos[i] + (robot_pos[r] - pos[i]) / cfg.robot_scale
            sx, sy = _moussaid(pos[i], vel[i], scaled, robot_vel[r], cfg)
            fx, fy = fx + cfg.social_strength * sx, fy + cfg.social_strength * sy
        best, point = math.inf, None
        for x1, y1, x2, y2 in walls:
            a, b = np.array([x1, y1]), np.array([x2, y2])
            t = np.clip(np.dot(pos[i] - a, b - a) / np.dot(b - a, b - a), 0, 1)
            c = a + t * (b - a)
            if np.linalg.norm(pos[i] - c) < best:
                best, point = np.linalg.norm(pos[i] - c), c
        if best <= 1.0:
            away = (pos[i] - point) / best
            amount = math.exp(-(best - cfg.force_radius) / cfg.obstacle_sigma)
            fx, fy = (
                fx + cfg.obstacle_strength * amount * away[0],
                fy + cfg.obstacle_strength * amount * away[1],
            )
        out[i] = fx, fy
    return out


@pytest.mark.parametrize("seed", range(5))
def test_matches_scalar_reference(seed):
    rng = np.random.default_rng(seed)
    n = 8
    walls = np.array([[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0], [4, 2, 6, 3.0]])
    pos = rng.uniform([0.5, 0.5], [9.5, 5.5], (n, 2))
    vel = rng.normal(0, 0.7, (n, 2))
    target = rng.uniform([0.5, 0.5], [9.5, 5.5], (n, 2))
    speed = rng.uniform(0.8, 1.2, n)
    robot_pos = rng.uniform([0.5, 0.5], [9.5, 5.5], (2, 2))
    robot_vel = rng.normal(0, 1.0, (2, 2))
    got, wall_dist = human_acceleration(
        pos[None],
        vel[None],
        target[None],
        speed[None],
        np.ones((1, n), bool),
        robot_pos[None],
        robot_vel[None],
        WallIndex(walls),
        CFG,
    )
    want = _reference(pos, vel, target, speed, robot_pos, robot_vel, walls, CFG)
    # The pair terms are evaluated in float32: agreement to about 1e-5 relative.
    np.testing.assert_allclose(got[0], want, rtol=1e-9, atol=1e-9)
    assert wall_dist.shape == (1, n)


def test_absent_humans_exert_and_feel_nothing():
    rng = np.random.default_rng(3)
    walls = np.array([[0.0, 0.0, 10.0, 0.0]])
    pos = rng.uniform(1, 5, (1, 6, 2))
    vel = rng.normal(0, 1, (1, 6, 2))
    target = rng.uniform(1, 5, (1, 6, 2))
    speed = np.ones((1, 6))
    mask = np.array([[True, True, True, False, False, False]])
    args = (np.zeros((1, 1, 2)) + 20.0, np.zeros((1, 1, 2)), WallIndex(walls), CFG)
    full, _ = human_acceleration(pos, vel, target, speed, mask, *args)
    only, _ = human_acceleration(pos[:, :3], vel[:, :3], target[:, :3], speed[:, :3], mask[:, :3], *args)
    np.testing.assert_allclose(full[:, :3], only, rtol=1e-6, atol=1e-7)
    assert np.all(full[:, 3:] == 0.0)


def test_pair_force_is_antisymmetric_between_two_humans():
    walls = np.array([[100.0, 100.0, 101.0, 100.0]])
    pos = np.array([[[0.0, 0.0], [0.7, 0.2]]])
    vel = np.array([[[1.0, 0.0], [-0.8, 0.1]]])
    acc, _ = human_acceleration(
        pos,
        vel,
        pos,
        np.zeros((1, 2)),
        np.ones((1, 2), bool),
        np.full((1, 1, 2), 50.0),
        np.zeros((1, 1, 2)),
        WallIndex(walls),
        HumanConfig(desired_factor=1e-9),
    )
    np.testing.assert_allclose(acc[0, 0], -acc[0, 1], atol=1e-5)


def test_waypoints_shuttle_between_ends():
    route_len = np.array([[3]])
    pos = np.zeros((1, 1, 2))
    # The person stands on the route's ends; its middle waypoint lies far off.
    route = np.array([[[[0.0, 0.0], [5.0, 5.0], [0.0, 0.0]]]])
    waypoint, direction = np.array([[2]]), np.array([[1]])
    waypoint, direction = advance_waypoints(pos, route, route_len, waypoint, direction, 1.0)
    assert (waypoint[0, 0], direction[0, 0]) == (1, -1)
    waypoint, direction = advance_waypoints(pos, route, route_len, np.array([[0]]), np.array([[-1]]), 1.0)
    assert (waypoint[0, 0], direction[0, 0]) == (1, 1)
    waypoint, direction = advance_waypoints(pos, route, route_len, np.array([[1]]), np.array([[1]]), 1.0)
    assert (waypoint[0, 0], direction[0, 0]) == (1, 1)
    # A one-waypoint route stays put.
    one_point = np.array([[1]])
    waypoint, direction = advance_waypoints(pos, route, one_point, np.array([[0]]), np.array([[1]]), 1.0)
    assert waypoint[0, 0] == 0


def _random_routes(rng: np.random.Generator, h: int):
    """(route, route_len, waypoint, direction) of 3 worlds of h people on random routes of up to 4 points."""
    route = rng.uniform(-2.0, 2.0, (3, h, 4, 2))
    route_len = rng.integers(1, 5, (3, h))
    return route, route_len, rng.integers(0, route_len), rng.choice([-1, 1], (3, h))


def test_waypoints_advance_alike_from_the_route_or_the_gathered_targets():
    rng = np.random.default_rng(0)
    route, route_len, waypoint, direction = _random_routes(rng, 5)
    # Half the people stand on their waypoint, so some advance and some turn back.
    target = np.take_along_axis(route, waypoint[:, :, None, None], axis=2)[:, :, 0]
    pos = np.where(rng.random((3, 5, 1)) < 0.5, target, target + 3.0)
    from_route = advance_waypoints(pos, route, route_len, waypoint, direction, 0.5)
    from_target = advance_waypoints(pos, route, route_len, waypoint, direction, 0.5, target)
    for got, want in zip(from_target, from_route, strict=True):
        np.testing.assert_array_equal(got, want)
    assert (from_route[0] != waypoint).any() and (from_route[1] != direction).any()


def test_kept_people_keep_their_waypoint_and_the_others_advance_as_before():
    rng = np.random.default_rng(1)
    route, route_len, waypoint, direction = _random_routes(rng, 6)
    pos = np.take_along_axis(route, waypoint[:, :, None, None], axis=2)[:, :, 0]  # all on their waypoint
    keep = rng.random((3, 6)) < 0.5
    # A kept person's route is never read: NaN there changes nothing.
    route_read = np.where(keep[:, :, None, None], np.nan, route)
    moved = advance_waypoints(pos, route, route_len, waypoint, direction, 0.5)
    kept = advance_waypoints(pos, route_read, route_len, waypoint, direction, 0.5, moving=~keep)
    for got, all_moved, before in zip(kept, moved, (waypoint, direction), strict=True):
        np.testing.assert_array_equal(got[keep], before[keep])
        np.testing.assert_array_equal(got[~keep], all_moved[~keep])
    assert (moved[0][keep] != waypoint[keep]).any()  # those kept would have moved on


def _learned_beside_a_person_and_a_wall():
    """(human_acceleration's first arguments, desired velocities, learned mask): a learned person
    (slot 0) beside a scripted one and a wall."""
    pos = np.array([[[0.0, 0.15], [0.5, 0.2]]])
    vel = np.array([[[1.0, 0.0], [-1.0, 0.0]]])
    target = np.array([[[5.0, 0.0], [-5.0, 0.0]]])
    speed, mask = np.array([[1.2, 1.2]]), np.ones((1, 2), dtype=bool)
    walls = WallIndex(np.array([[-5.0, 0.0, 5.0, 0.0]]))
    none = np.zeros((1, 0, 2))
    args = (pos, vel, target, speed, mask, none, none, walls)
    return args, np.array([[[0.4, 0.9], [0.0, 0.0]]]), np.array([[True, False]])


def test_learned_people_without_forces_relax_towards_their_desired_velocity_alone():
    """HumanConfig.learned_forces off: a learned person beside another person and a wall feels only
    the relaxation towards its desired velocity; the scripted person still feels every force, and
    with the switch on the learned person does too."""
    args, desired, learned = _learned_beside_a_person_and_a_wall()
    vel = args[1]
    off = HumanConfig(learned_forces=False)
    accel_off, _ = human_acceleration(*args, off, desired, learned)
    accel_on, _ = human_acceleration(*args, CFG, desired, learned)
    relax = off.desired_factor * (desired[0, 0] - vel[0, 0]) / off.relaxation_time
    np.testing.assert_array_equal(accel_off[0, 0], relax)
    assert np.abs(accel_on[0, 0] - relax).max() > 1.0  # the person and the wall push it
    np.testing.assert_array_equal(accel_off[0, 1], accel_on[0, 1])


def test_learned_people_relax_at_their_own_relaxation_time():
    """HumanConfig.learned_relaxation_time sets the learned people's tau, with or without forces;
    the scripted person's acceleration is bit for bit the same as without it, and None is the
    people's own."""
    args, desired, learned = _learned_beside_a_person_and_a_wall()
    vel = args[1]
    for forces in (False, True):
        base = HumanConfig(learned_forces=forces)
        slow = HumanConfig(learned_forces=forces, learned_relaxation_time=2.0)
        accel_base, _ = human_acceleration(*args, base, desired, learned)
        accel_slow, _ = human_acceleration(*args, slow, desired, learned)
        explicit = HumanConfig(learned_forces=forces, learned_relaxation_time=0.5)
        same, _ = human_acceleration(*args, explicit, desired, learned)
        np.testing.assert_array_equal(same, accel_base)
        np.testing.assert_array_equal(accel_slow[0, 1], accel_base[0, 1])
        # Only the relaxation term changes: from (v_d - v) / 0.5 to (v_d - v) / 2.0.
        change = (desired[0, 0] - vel[0, 0]) * (1.0 / 2.0 - 1.0 / 0.5)
        np.testing.assert_allclose(accel_slow[0, 0] - accel_base[0, 0], change, atol=1e-12)
    with pytest.raises(ValueError, match="learned_relaxation_time"):
        HumanConfig(learned_relaxation_time=0.0)
