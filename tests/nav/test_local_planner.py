"""Trajectory rollout: free lengths, arc choice, turning in place, speed control, batching."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from socialzoo.core.config import RobotConfig
from socialzoo.core.geometry import closest_point_on_segment
from socialzoo.core.walls import WallIndex
from socialzoo.nav.distance_field import build_distance_field
from socialzoo.nav.local_planner import (
    LocalPlannerConfig,
    arc_points,
    arc_table,
    evaluate_arcs,
    plan_commands,
)

CFG = LocalPlannerConfig()
ROBOT = RobotConfig()
DT = 0.025
NO_HUMANS = (np.zeros((1, 0, 2)), np.zeros((1, 0), dtype=bool))


def true_wall_distance(points: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Brute-force distance from points (..., 2) to the nearest of walls (W, 4)."""
    _, dist = closest_point_on_segment(points[..., None, :], walls[:, :2], walls[:, 2:])
    return dist.min(axis=-1)


def arc_samples(pose: np.ndarray, curvature: float, length: float, step: float = 0.005) -> np.ndarray:
    """World points every `step` metres along an arc from pose, (M, 2)."""
    s = np.arange(0.0, length + step / 2, step)
    k = max(abs(curvature), 1e-9)
    x, y = arc_points(np.array(k), np.array(1.0 if curvature >= 0 else -1.0), s)
    c, sn = math.cos(pose[2]), math.sin(pose[2])
    return np.stack((pose[0] + c * x - sn * y, pose[1] + sn * x + c * y), axis=-1)


def plan1(pose, target, walls, vel=(0.0, 0.0), humans=None, max_speed=1.5, weight=-0.5, cfg=CFG):
    human_pos, human_mask = (
        NO_HUMANS if humans is None else (np.array([humans]), np.ones((1, len(humans)), bool))
    )
    return plan_commands(
        np.array([pose], float),
        np.array([vel], float),
        np.array([target], float),
        np.array([max_speed]),
        np.array([weight]),
        walls,
        human_pos,
        human_mask,
        cfg,
        ROBOT,
        DT,
    )[0]


def test_config_validation_names_the_field():
    with pytest.raises(ValueError, match="obstacle_margin"):
        LocalPlannerConfig(obstacle_margin=-0.1)
    with pytest.raises(ValueError, match="curvature_min"):
        LocalPlannerConfig(curvature_min=2.0, curvature_max=-2.0)
    with pytest.raises(ValueError, match="curvature_step"):
        LocalPlannerConfig(curvature_step=0.3)
    with pytest.raises(ValueError, match="min_wall_distance"):
        LocalPlannerConfig(min_wall_distance=0.5)
    with pytest.raises(ValueError, match="planner_accel"):
        LocalPlannerConfig(planner_accel=float("nan"))
    with pytest.raises(TypeError):
        LocalPlannerConfig(0.1)  # type: ignore[misc]


def test_forty_one_arcs():
    assert len(CFG.curvatures) == 41
    np.testing.assert_allclose(CFG.curvatures[[0, 20, 40]], [-2.0, 0.0, 2.0])
    table = arc_table(CFG)
    assert table.lengths[0] == 0.0 and table.lengths[-1] == pytest.approx(CFG.max_arc_length)
    # Sample offsets lie on their arcs: distance to the turning centre is the radius.
    k = table.curvature[-1]
    off = table.offsets[-1]
    np.testing.assert_allclose(np.hypot(off[:, 0], off[:, 1] - 1 / k), 1 / k, atol=1e-9)


def test_distance_field_is_within_half_a_cell_diagonal():
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 10, (30, 2))
    walls = np.hstack((a, a + rng.uniform(-2, 2, (30, 2))))
    field = build_distance_field(walls, 0.05, 1.5)
    points = rng.uniform(-3, 13, (5000, 2))
    truth = np.minimum(true_wall_distance(points, walls), 1.5)
    got = field.lookup(points)
    half_diagonal = 0.05 * math.sqrt(0.5)
    assert np.all(got <= np.minimum(truth + half_diagonal, 1.5) + 1e-9)
    assert np.all(got >= truth - half_diagonal - field.quantum - 1e-9)


def test_straight_corridor_drives_straight_and_accelerates():
    walls = WallIndex(np.array([[-5, -1, 20, -1], [-5, 1, 20, 1]], float))
    cmd = plan1((0, 0, 0), (1.5, 0), walls)
    assert cmd[0] == pytest.approx(CFG.planner_accel * DT)
    assert cmd[1] == pytest.approx(0.0)
    cmd = plan1((0, 0, 0), (1.5, 0), walls, vel=(1.5, 0))
    assert cmd[0] == pytest.approx(1.5)  # capped at max_speed


def test_turns_in_place_when_the_target_is_behind():
    walls = WallIndex(np.array([[-5, -3, 5, -3]], float))
    for target, sign in (((-1.0, 0.3), 1), ((-1.0, -0.3), -1), ((0.2, 1.0), 1)):
        cmd = plan1((0, 0, 0), target, walls)
        assert cmd[0] == 0.0
        assert np.sign(cmd[1]) == sign
        assert abs(cmd[1]) == pytest.approx(ROBOT.max_angular_accel * DT)
    # Still moving fast: brake first, no rotation yet.
    cmd = plan1((0, 0, 0), (-1.0, 0.3), walls, vel=(1.0, 0.0))
    assert cmd[0] == pytest.approx(1.0 - CFG.planner_accel * DT) and cmd[1] == 0.0
    # Within 30 degrees: drive.
    cmd = plan1((0, 0, 0), (1.5, 0.7), walls)
    assert cmd[0] > 0.0 and cmd[1] > 0.0


def test_stops_in_a_dead_end_and_at_the_target():
    # Walls 0.4 m ahead and on both sides: no arc is free, so the robot does not drive (it may
    # turn in place looking for a way out).
    pocket = WallIndex(np.array([[0.4, -1, 0.4, 1], [-1, 0.4, 1, 0.4], [-1, -0.4, 1, -0.4]], float))
    assert plan1((0, 0, 0), (2.0, 0.0), pocket)[0] == 0.0
    braking = plan1((0, 0, 0), (2.0, 0.0), pocket, vel=(1.0, 0.0))
    assert braking[0] <= 1.0 - CFG.planner_accel * DT + 1e-12 and braking[1] == 0.0
    open_walls = WallIndex(np.array([[-5, -3, 5, -3]], float))
    # At the target: nothing left to drive.
    assert plan1((0, 0, 0), (0.0, 0.0), open_walls, vel=(0.5, 0.0))[0] == 0.0
    # Speed control: a target 0.1 m ahead allows no more than the stopping speed.
    v = plan1((0, 0, 0), (0.1, 0.0), open_walls, vel=(1.5, 0.0))[0]
    assert v <= math.sqrt(2 * CFG.planner_accel * 0.1) + 1e-9


def test_free_length_stops_short_of_a_human():
    walls = WallIndex(np.array([[-5, -3, 20, -3]], float))
    ev = evaluate_arcs(
        np.array([[0.0, 0.0, 0.0]]),
        np.array([[1.5, 0.0]]),
        np.array([0.0]),
        walls,
        np.array([[[1.2, 0.1]]]),
        np.ones((1, 1), bool),
        CFG,
    )
    straight = 20
    expected = 1.2 - math.sqrt(CFG.human_distance**2 - 0.1**2)
    assert ev.free[0, straight] == pytest.approx(expected, abs=1e-4)
    # Clearance is the gap between the robot and human discs along the trimmed arc.
    assert ev.clearance[0, straight] == pytest.approx(
        min(1.0, math.hypot(1.2 - expected, 0.1) - CFG.robot_radius - CFG.human_radius), abs=1e-3
    )


coords = st.floats(-3.0, 3.0, allow_nan=False)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(
    st.lists(st.tuples(coords, coords, coords, coords), min_size=1, max_size=8),
    st.floats(-0.5, 0.5),
)
def test_never_picks_a_colliding_arc_when_a_free_one_exists(segments, bearing):
    walls = np.array(segments, float)
    start_dist = float(true_wall_distance(np.zeros(2), walls))
    if start_dist < CFG.wall_distance + 0.02:
        return  # the robot must start clear of the margin
    index = WallIndex(walls)
    pose = np.array([0.0, 0.0, 0.0])
    target = 1.5 * np.array([math.cos(bearing), math.sin(bearing)])
    ev = evaluate_arcs(pose[None], target[None], np.array([-0.5]), index, *NO_HUMANS, CFG)
    best = int(ev.best[0])
    table = arc_table(CFG)
    # The chosen arc is free over its first 0.5 m (or its free length if shorter): the planning
    # disc keeps its margin up to half a sample spacing, and the collision box never touches.
    check = min(0.5, float(ev.best_free[0]))
    pts = arc_samples(pose, float(table.curvature[best]), check)
    dist = true_wall_distance(pts, walls)
    field_error = CFG.field_resolution * math.sqrt(0.5) + CFG.field_range / 250
    assert dist.min() >= CFG.wall_distance - field_error - CFG.near_sample_spacing / 2 - 1e-9
    assert dist.min() > math.hypot(ROBOT.half_length, ROBOT.half_width)
    # If some arc is clearly free for its first 0.3 m, the robot does move.
    for j, c in enumerate(table.curvature):
        length = min(0.3, float(ev.trim[0, j]))
        if length < 0.1:
            continue
        d = true_wall_distance(arc_samples(pose, float(c), length), walls)
        if d.min() >= CFG.wall_distance + 0.1:
            assert ev.best_free[0] > 0.0
            break


@settings(max_examples=80, deadline=None)
@given(
    st.lists(st.tuples(st.floats(-0.5, 3.0), st.floats(-2.0, 2.0)), min_size=1, max_size=6),
    st.floats(-0.5, 0.5),
)
def test_never_drives_into_a_human(humans, bearing):
    humans_arr = np.array(humans, float)
    if np.hypot(humans_arr[:, 0], humans_arr[:, 1]).min() < CFG.human_distance + 0.02:
        return
    walls = WallIndex(np.array([[-10, -10, -10, 10]], float))
    target = 1.5 * np.array([math.cos(bearing), math.sin(bearing)])
    ev = evaluate_arcs(
        np.zeros((1, 3)),
        target[None],
        np.array([0.5]),
        walls,
        humans_arr[None],
        np.ones((1, len(humans)), bool),
        CFG,
    )
    table = arc_table(CFG)
    # The escape rule: a human already within escape_slack of the required distance may be
    # passed at escape_slack less than its present distance (never below the hard floor).
    present = np.hypot(humans_arr[:, 0], humans_arr[:, 1])
    keep = np.clip(present - CFG.escape_slack, CFG.min_human_distance, CFG.human_distance)
    for j, c in enumerate(table.curvature):
        pts = arc_samples(np.zeros(3), float(c), float(ev.free[0, j]), step=0.002)
        gap = np.hypot(pts[:, None, 0] - humans_arr[:, 0], pts[:, None, 1] - humans_arr[:, 1])
        assert np.all(gap >= keep - 2e-3)
    # The reported clearance matches brute force along the chosen arc.
    best = int(ev.best[0])
    pts = arc_samples(np.zeros(3), float(table.curvature[best]), float(ev.free[0, best]), step=0.002)
    gap = np.hypot(pts[:, None, 0] - humans_arr[:, 0], pts[:, None, 1] - humans_arr[:, 1]).min()
    expect = np.clip(gap - CFG.robot_radius - CFG.human_radius, 0, CFG.clearance_cap)
    wall_gap = true_wall_distance(pts, np.array([[-10, -10, -10, 10]], float)).min() - CFG.robot_radius
    assert ev.clearance[0, best] == pytest.approx(min(expect, max(0.0, min(wall_gap, 1.0))), abs=2e-3)


def test_escape_rule_lets_a_robot_inside_the_margin_move_away():
    # 0.38 m from a wall (inside the 0.4 m planning distance), heading along it.
    walls = WallIndex(np.array([[-5, -0.38, 20, -0.38]], float))
    cmd = plan1((0, 0, 0), (1.5, 0.2), walls)
    assert cmd[0] > 0.0
    # But never below the hard floor.
    tight = WallIndex(np.array([[-5, -0.34, 20, -0.34]], float))
    ev = evaluate_arcs(np.zeros((1, 3)), np.array([[1.5, -0.3]]), np.array([0.0]), tight, *NO_HUMANS, CFG)
    table = arc_table(CFG)
    for j, c in enumerate(table.curvature):
        if ev.free[0, j] > 0.06 and c < 0:
            pytest.fail(f"arc {c} drives towards a wall already inside the hard floor")


def test_batch_equals_rows_one_by_one():
    rng = np.random.default_rng(7)
    walls_arr = np.array(
        [[-5, -1.2, 20, -1.2], [-5, 1.2, 20, 1.2], [4, -1.2, 4, 0.0], [7, 1.2, 7, 0.2]], float
    )
    walls = WallIndex(walls_arr)
    n = 48  # large enough for rows with short and long trimmed arcs to be evaluated apart
    pose = np.column_stack((rng.uniform(0, 10, n), rng.uniform(-0.5, 0.5, n), rng.uniform(-1, 1, n)))
    vel = np.column_stack((rng.uniform(0, 1.5, n), rng.uniform(-1, 1, n)))
    target = pose[:, :2] + rng.uniform(-2, 2, (n, 2))
    humans = pose[:, None, :2] + rng.uniform(-3, 3, (n, 5, 2))
    mask = rng.random((n, 5)) < 0.7
    speed = rng.choice([1.5, 2.25], n)
    weight = rng.choice([-0.5, 0.0, 0.5], n)
    batch = plan_commands(pose, vel, target, speed, weight, walls, humans, mask, CFG, ROBOT, DT)
    ev = evaluate_arcs(pose, target, weight, walls, humans, mask, CFG)
    longest = ev.trim.max(axis=1)
    assert (longest <= 1.6).any() and (longest > 1.6).any()
    for i in range(n):
        one = plan_commands(
            pose[i : i + 1],
            vel[i : i + 1],
            target[i : i + 1],
            speed[i : i + 1],
            weight[i : i + 1],
            walls,
            humans[i : i + 1],
            mask[i : i + 1],
            CFG,
            ROBOT,
            DT,
        )
        np.testing.assert_allclose(batch[i], one[0], atol=1e-12)
        alone = evaluate_arcs(
            pose[i : i + 1],
            target[i : i + 1],
            weight[i : i + 1],
            walls,
            humans[i : i + 1],
            mask[i : i + 1],
            CFG,
        )
        for f in dataclasses.fields(alone):
            np.testing.assert_array_equal(getattr(ev, f.name)[i], getattr(alone, f.name)[0], err_msg=f.name)
    active = rng.random(n) < 0.5
    part = plan_commands(pose, vel, target, speed, weight, walls, humans, mask, CFG, ROBOT, DT, active=active)
    np.testing.assert_allclose(part[active], batch[active], atol=1e-12)
    assert np.all(part[~active] == 0.0)


def test_clearance_weight_sign():
    # The clearance weight has the reference's cost sign: a negative weight adds clearance to the
    # score, a positive one subtracts it.
    walls = WallIndex(np.array([[1.5, -0.55, 1.5, 1.2], [-3, -3, 6, -3], [-3, 3, 6, 3]], float))
    cfg = dataclasses.replace(CFG, free_path_weight=0.0)
    ev_reward = evaluate_arcs(
        np.zeros((1, 3)), np.array([[1.5, 0.0]]), np.array([-0.5]), walls, *NO_HUMANS, cfg
    )
    ev_penal = evaluate_arcs(
        np.zeros((1, 3)), np.array([[1.5, 0.0]]), np.array([0.5]), walls, *NO_HUMANS, cfg
    )
    diff = ev_reward.score - ev_penal.score
    np.testing.assert_allclose(diff[np.isfinite(diff)], ev_reward.clearance[np.isfinite(diff)], atol=1e-9)


def test_lines_up_with_a_doorway_instead_of_facing_the_frame():
    # A 0.9 m channel going up (y); the target is up and to the right, hidden behind the right
    # door frame. Turning towards it (38 degrees off) would face the frame: the robot keeps
    # driving up the channel instead.
    walls = WallIndex(np.array([[-0.45, -3, -0.45, 0.5], [0.45, -3, 0.45, 0.5], [0.45, 0.5, 3, 0.5]], float))
    pose = (0.05, 0.0, math.pi / 2)
    target = (1.0, 1.2)
    ev = evaluate_arcs(np.array([pose]), np.array([target]), np.array([-0.5]), walls, *NO_HUMANS, CFG)
    raw = math.atan2(target[1] - pose[1], target[0] - pose[0]) - pose[2]
    assert abs(raw) > math.radians(CFG.turn_in_place_angle_deg)
    assert not ev.turn[0]
    cmd = plan1(pose, target, walls)
    assert cmd[0] > 0.0


def test_wall_sampling_stops_only_where_nothing_reads_it():
    # arc_wall_codes stops sampling an arc at its first blocked sample and at its trimmed length;
    # the free length and the running minima up to it are those of a full sampling.
    from socialzoo.maps.map_file import load_map
    from socialzoo.nav.arcs import arc_wall_codes
    from socialzoo.nav.distance_field import distance_field
    from socialzoo.nav.local_planner import _limit_codes

    walls = load_map("gdc1").wall_index
    field = distance_field(walls, CFG.field_resolution, CFG.field_range, CFG.field_pad)
    table = arc_table(CFG)
    rng = np.random.default_rng(0)
    n, num_arcs, num_samples = 400, len(table.curvature), len(table.lengths)
    lo, hi = walls.wall_a.min(axis=0), walls.wall_a.max(axis=0)
    x, y = rng.uniform(lo[0], hi[0], n), rng.uniform(lo[1], hi[1], n)
    heading = rng.uniform(-math.pi, math.pi, n)
    trim = rng.uniform(0.0, CFG.max_arc_length, (n, num_arcs))
    trim[:, ::7] = 0.0
    stop = _limit_codes(field.quantum, CFG.wall_distance, CFG.min_wall_distance, CFG.escape_slack)

    def sample(stop_code, trim):
        here, num_free = np.empty(n, np.uint8), np.empty((num_arcs, n), np.uint8)
        codes = np.empty((num_samples, num_arcs, n), np.uint8)
        arc_wall_codes(
            x, y, np.cos(heading), np.sin(heading), table.cell_offsets, field.shape_args, field.codes,
            stop_code, table.lengths, trim, here, codes, num_free,
        )  # fmt: skip
        return here, codes, num_free

    here, codes, num_free = sample(stop, trim)
    full_here, full, _ = sample(np.zeros(256, np.uint8), np.full((n, num_arcs), np.inf))
    np.testing.assert_array_equal(here, full_here)
    limit = stop[full_here]
    full_free = (full >= limit).sum(axis=0)
    free = np.minimum(table.free_at[num_free].T, trim)
    want = np.minimum(table.free_at[full_free].T, trim)
    np.testing.assert_array_equal(free, want)
    last = np.searchsorted(table.lengths, free, side="right") - 1
    rows = np.arange(n)[:, None]
    arcs = np.arange(num_arcs)
    np.testing.assert_array_equal(codes[last, arcs, rows], full[last, arcs, rows])
    assert (codes != full).any()  # something was skipped
