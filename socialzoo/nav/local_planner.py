"""Trajectory-rollout local planner (SPEC section 6), vectorised over batch rows and arcs: `evaluate_arcs` scores
constant-curvature arcs, `plan_commands` drives along the best one or turns in place."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, fields
from functools import lru_cache

import numpy as np

from socialzoo.core.config import RobotConfig
from socialzoo.core.walls import WallIndex
from socialzoo.nav.arcs import ArcTable, arc_points, arc_table, arc_wall_codes, human_arcs, human_gaps
from socialzoo.nav.distance_field import DistanceField, distance_field
from socialzoo.nav.planner_config import LocalPlannerConfig

# The config and the arc geometry live in their own modules; they are part of this API too.
__all__ = ["ArcEvaluation", "LocalPlannerConfig", "arc_points", "arc_table", "evaluate_arcs", "plan_commands"]

# Free lengths at or below this do not count as a move (m).
_MIN_FREE = 1e-3
# Batches of at least this many rows evaluate rows whose trimmed arcs all end within
# _SHORT_ARC (m) apart, with fewer wall samples (see evaluate_arcs).
_SPLIT_ROWS = 32
_SHORT_ARC = 1.6


def _stopping_speed(distance: np.ndarray, accel: float, dt: float) -> np.ndarray:
    """Largest speed from which a robot moving one more step at it can still stop within distance.

    Solves v * dt + v^2 / (2 a) = distance for v >= 0.
    """
    adt = accel * dt
    return np.sqrt(adt * adt + 2.0 * accel * np.maximum(distance, 0.0)) - adt


def _escape_limit(here: np.ndarray, required: float, floor: float, slack: float) -> np.ndarray:
    """Distance an arc must keep from an obstacle now `here` away (the escape rule).

    The required distance, or, for a robot less than `slack` beyond it (or already inside it),
    `slack` less than its present distance, so that it can move along or away even though the
    distance field's lookups scatter by a centimetre or two; never less than `floor`.
    """
    return np.minimum(np.maximum(here - slack, floor), required)


@lru_cache(maxsize=16)
def _limit_codes(quantum: float, required: float, floor: float, slack: float) -> np.ndarray:
    """(256,) uint8: for each distance-field code at the robot, the smallest code an arc sample
    may read without blocking (the escape limit, `_escape_limit`, rounded up to codes). Read-only."""
    here = np.arange(256, dtype=np.uint8) * quantum
    codes = np.ceil(_escape_limit(here, required, floor, slack) / quantum - 1e-9).astype(np.uint8)
    codes.flags.writeable = False
    return codes


_SCRATCH = threading.local()


def _scratch(name: str, shape: tuple[int, ...], dtype: type) -> np.ndarray:
    """A reusable contiguous work array (per thread, grow-only): large fresh temporaries cost
    page faults on every call."""
    store: dict[str, np.ndarray] = _SCRATCH.__dict__.setdefault("arrays", {})
    size = math.prod(shape)
    array = store.get(name)
    if array is None or array.size < size or array.dtype != dtype:
        array = store[name] = np.empty(max(size, 2 * (0 if array is None else array.size)), dtype=dtype)
    return array[:size].reshape(shape)


def _segment_min_rows(values: np.ndarray, rows: np.ndarray, num_rows: int) -> np.ndarray:
    """Row-wise minimum of values (P, A) whose rows (P,) are sorted: (num_rows, A), inf if none."""
    if num_rows == 1:
        return values.min(axis=0, keepdims=True)
    out = np.full((num_rows, values.shape[1]), np.inf)
    starts = np.flatnonzero(np.concatenate(([True], rows[1:] != rows[:-1])))
    out[rows[starts]] = np.minimum.reduceat(values, starts, axis=0)
    return out


@dataclass(frozen=True)
class ArcEvaluation:
    """Every arc of every row, as scored by the rollout.

    Attributes:
        target: (N, 2) local target in the robot frame, pulled in to `target_clip`, m.
        bearing: (N,) heading change the robot would turn in place by, rad: the target's
            bearing, slid along the nearest wall for a robot close to one; for a robot stuck
            against a wall, the recovery heading.
        turn: (N,) bool, turn in place (the bearing is too large, or recovery).
        trim: (N, A) arc length to the closest approach to the target (capped), m.
        free: (N, A) free path length: trim, cut at the first collision, m.
        clearance: (N, A) clearance along the trimmed arc, in [0, clearance_cap], m.
        score: (N, A) score; -inf for arcs with no free length.
        best: (N,) index of the chosen arc.
        best_free: (N,) free length of the chosen arc (0 when no arc can move), m.
        wall_blocked: (N,) bool, walls alone leave no arc `stuck_length` of free path although
            the target is farther than twice that: the robot is stuck against a wall.
    """

    target: np.ndarray
    bearing: np.ndarray
    turn: np.ndarray
    trim: np.ndarray
    free: np.ndarray
    clearance: np.ndarray
    score: np.ndarray
    best: np.ndarray
    best_free: np.ndarray
    wall_blocked: np.ndarray


def evaluate_arcs(
    pose: np.ndarray,
    target: np.ndarray,
    clearance_weight: np.ndarray,
    walls: WallIndex,
    human_pos: np.ndarray,
    human_mask: np.ndarray,
    cfg: LocalPlannerConfig,
    human_vel: np.ndarray | None = None,
) -> ArcEvaluation:
    """Roll out, trim and score every arc of every row (below).

    Collision model. The planning footprint is a disc of `robot_radius` around the robot centre; it
    must stay `obstacle_margin` away from walls and from human discs of `human_radius`.
    - Walls: a precomputed distance field of the map (the distance to the nearest wall at the centres
      of a 2.5 cm grid, one byte per cell) is read at sample points along every arc, so a call costs
      one lookup per sample point whatever the wall density. The sample points are arc offsets
      precomputed in the robot frame, rotated and looked up in one compiled pass that also keeps
      the running minimum along each arc (socialzoo.nav.arcs.arc_wall_codes).
    - Humans: exact circle-disc intersection of every arc with every human near the row (pairs
      gathered once), in closed form (float32, written to stay accurate for the straight arc). A
      walking human is also an obstacle where it will be `human_lookahead` seconds later.
    - Escape rule: a robot already inside a margin (after a tracking error, or a human walking up to
      it) may still take arcs that come no closer than `escape_slack` less than it is now, down to
      hard floors (`min_wall_distance`, `min_human_distance`); its own position never blocks an arc.

    Scoring (maximised, over arcs with a free length > 0; a row with none stops):

        score = progress_weight * (|t| - |e - t|) + free_path_weight * L - clearance_weight * clr

    where t is the local target (robot frame, pulled in to `target_clip`), L the arc's free length
    (trimmed at the first collision, at the closest approach to t and at `max_arc_length`), e the
    arc's point at L, and clr the clearance along the trimmed arc: the smallest gap between the
    planning disc and any wall or human disc, clipped to [0, clearance_cap]. clearance_weight keeps
    the reference planner's cost sign: a negative weight (GoAlone, -0.5) rewards clearance, a positive
    one (Pass, +0.5) lets the robot squeeze past. Defaults: progress_weight 1 (one metre of progress
    is worth one point), free_path_weight 0.1 (a tie-breaker towards arcs with room ahead, small
    enough never to trade progress for length), |clearance_weight| <= 0.5 (a full metre of clearance
    is worth half a metre of progress, as in the reference).

    Args:
        pose: (N, 3) robot pose x, y (m), theta (rad), world frame.
        target: (N, 2) local target, world frame, m.
        clearance_weight: (N,) clearance weight (cost sign: negative rewards clearance).
        walls: the map's wall index (its distance field is built on first use and cached).
        human_pos: (N, H, 2) human positions, world frame, m.
        human_mask: (N, H) present humans; every present human is an obstacle.
        cfg: planner parameters.
        human_vel: (N, H, 2) human velocities, world frame, m/s; with them (and a positive
            `human_lookahead`) each walking human is also an obstacle where it will be then.

    Returns:
        The per-arc evaluation.
    """
    table = arc_table(cfg)
    aim = _aim(pose, target, table, cfg)
    n = len(pose)
    if n >= _SPLIT_ROWS:
        # Walls are sampled up to the longest trimmed arc of the batch; rows whose arcs all end
        # early (most: the carrot is 1.5 m away) are evaluated apart with fewer samples. Every
        # row's answer is the same either way.
        short = aim.trim.max(axis=1) <= _SHORT_ARC
        num_short = int(np.count_nonzero(short))
        if 0 < num_short < n:
            groups = (np.flatnonzero(short), np.flatnonzero(~short))
            parts = [
                _evaluate(
                    pose[rows],
                    aim.rows(rows),
                    clearance_weight[rows],
                    walls,
                    human_pos[rows],
                    human_mask[rows],
                    cfg,
                    None if human_vel is None else human_vel[rows],
                )
                for rows in groups
            ]
            return _merge_rows(parts, groups, n)
    return _evaluate(pose, aim, clearance_weight, walls, human_pos, human_mask, cfg, human_vel)


@dataclass(frozen=True)
class _Aim:
    """Each row's local target in its robot frame and the arcs trimmed at their closest approach."""

    cos: np.ndarray  # (N,) cos and sin of the robot heading
    sin: np.ndarray
    tx: np.ndarray  # (N,) target in the robot frame, pulled in to target_clip, m
    ty: np.ndarray
    tdist: np.ndarray  # (N,) its distance, m
    trim: np.ndarray  # (N, A) arc length to the closest approach (capped), m

    def rows(self, index: np.ndarray) -> _Aim:
        return _Aim(*(getattr(self, f.name)[index] for f in fields(self)))


def _aim(pose: np.ndarray, target: np.ndarray, table: ArcTable, cfg: LocalPlannerConfig) -> _Aim:
    """The local target in each robot's frame (pulled in to target_clip) and the trimmed arcs."""
    cos, sin = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    dx, dy = target[:, 0] - pose[:, 0], target[:, 1] - pose[:, 1]
    tx, ty = cos * dx + sin * dy, cos * dy - sin * dx
    tdist = np.sqrt(tx * tx + ty * ty)
    scale = np.minimum(1.0, cfg.target_clip / np.maximum(tdist, 1e-12))
    tx, ty, tdist = tx * scale, ty * scale, tdist * scale
    # Arc length to the closest approach to the target: the turning angle at which the target
    # sits, atan2(|c| tx, 1 - c ty), over |c|; zero for targets behind.
    k = table.abs_curvature
    trim = np.arctan2(k * tx[:, None], 1.0 - table.curvature * ty[:, None]) / k
    trim = np.minimum(np.maximum(trim, 0.0), cfg.max_arc_length)  # (n, A)
    return _Aim(cos=cos, sin=sin, tx=tx, ty=ty, tdist=tdist, trim=trim)


def _merge_rows(parts: list[ArcEvaluation], groups: tuple[np.ndarray, ...], n: int) -> ArcEvaluation:
    """One ArcEvaluation of n rows from evaluations of the row groups `groups`."""
    merged = {}
    for f in fields(ArcEvaluation):
        first = getattr(parts[0], f.name)
        out = np.empty((n, *first.shape[1:]), dtype=first.dtype)
        for part, rows in zip(parts, groups, strict=True):
            out[rows] = getattr(part, f.name)
        merged[f.name] = out
    return ArcEvaluation(**merged)


def _evaluate(
    pose: np.ndarray,
    aim: _Aim,
    clearance_weight: np.ndarray,
    walls: WallIndex,
    human_pos: np.ndarray,
    human_mask: np.ndarray,
    cfg: LocalPlannerConfig,
    human_vel: np.ndarray | None,
) -> ArcEvaluation:
    """`evaluate_arcs` for rows whose target and trimmed arcs are known."""
    table = arc_table(cfg)
    field = distance_field(walls, cfg.field_resolution, cfg.field_range, cfg.field_pad)
    n = len(pose)
    x, y = pose[:, 0], pose[:, 1]
    cos, sin = aim.cos, aim.sin
    tx, ty, tdist, trim = aim.tx, aim.ty, aim.tdist, aim.trim
    k = table.abs_curvature
    longest = float(trim.max())

    # Walls: distance-field codes at the arc samples up to the longest trimmed arc, as running
    # minima along each arc: a blocked sample blocks the rest, and the clearance of a trimmed arc
    # is one read.
    num_samples = min(int(np.searchsorted(table.lengths, longest)) + 1, len(table.lengths))
    codes = _scratch("codes", (num_samples, len(k), n), np.uint8)
    here_code = np.empty(n, dtype=np.uint8)
    num_free = np.empty((len(k), n), dtype=np.uint8)  # (A, n) unblocked samples
    stop_code = _limit_codes(field.quantum, cfg.wall_distance, cfg.min_wall_distance, cfg.escape_slack)
    arc_wall_codes(
        x, y, cos, sin, table.cell_offsets, field.shape_args, field.codes, stop_code, table.lengths, trim,
        here_code, codes, num_free,
    )  # fmt: skip
    here = here_code * field.quantum
    limit = _escape_limit(here, cfg.wall_distance, cfg.min_wall_distance, cfg.escape_slack)
    free = np.minimum(table.free_at[np.minimum(num_free, num_samples)].T, trim)
    free = np.where(num_free.T >= num_samples, trim, free)

    # The heading to turn to: towards the target, or, for a robot close to a wall, towards the
    # target with its into-the-wall part removed (so that it lines up with a doorway or corridor
    # instead of facing a wall corner that hides its target).
    bearing = np.arctan2(ty, tx)
    near = here < cfg.wall_distance + cfg.slide_band
    if near.any():
        # Only where the straight line to the target is blocked: in a doorway the wall distance's
        # gradient points back out of the door, and sliding would turn the robot away from a
        # target it can drive to.
        rows = np.flatnonzero(near)
        near[rows] = ~_line_clear(field, pose[rows], tx[rows], ty[rows], limit[rows], cfg.near_sample_spacing)
    if near.any():
        rows = np.flatnonzero(near)
        # Inside the margin, also head away from the wall (up to 45 degrees).
        tilt = np.clip((cfg.wall_distance - here[rows]) / cfg.escape_slack, 0.0, 1.0)
        bearing[rows] = _slide_bearing(field, pose[rows], tx[rows], ty[rows], tilt)
    turn = np.abs(bearing) > math.radians(cfg.turn_in_place_angle_deg)
    wall_blocked = (free.max(axis=1) < cfg.stuck_length) & (tdist > 2.0 * cfg.stuck_length)
    if wall_blocked.any():
        # Stuck against a wall: turn in place towards the heading whose straight line makes
        # the most progress (searched on a 15 degree fan), rather than towards the target.
        rows = np.flatnonzero(wall_blocked)
        bearing[rows] = _recovery_bearing(
            field, pose[rows], tx[rows], ty[rows], limit[rows], bearing[rows], cfg
        )
        turn[rows] = np.abs(bearing[rows]) > math.radians(cfg.recovery_angle_deg)

    # Humans near each row: exact entry into discs inflated to the required distance. A walking
    # human is also an obstacle where it will be `human_lookahead` seconds later.
    if human_vel is not None and cfg.human_lookahead > 0.0:
        moving = human_mask & (np.abs(human_vel).sum(-1) > 0.0)
        human_pos = np.concatenate((human_pos, human_pos + cfg.human_lookahead * human_vel), axis=1)
        human_mask = np.concatenate((human_mask, moving), axis=1)
    hx_all = cos[:, None] * (human_pos[..., 0] - x[:, None]) + sin[:, None] * (human_pos[..., 1] - y[:, None])
    hy_all = cos[:, None] * (human_pos[..., 1] - y[:, None]) - sin[:, None] * (human_pos[..., 0] - x[:, None])
    hdist = np.sqrt(hx_all * hx_all + hy_all * hy_all)
    reach = longest + max(cfg.human_distance, cfg.robot_radius + cfg.human_radius + cfg.clearance_cap)
    pair_row, pair_h = np.nonzero(human_mask & (hdist < reach))
    humans = None
    if len(pair_row):
        hx, hy, hd = hx_all[pair_row, pair_h], hy_all[pair_row, pair_h], hdist[pair_row, pair_h]
        radius = _escape_limit(hd, cfg.human_distance, cfg.min_human_distance, cfg.escape_slack)
        humans = human_arcs(hx, hy, radius, table)
        # Inside the hard floor and not moving away: blocked at once.
        hit = np.where(((hd < radius) & (hx > 0.0))[:, None], np.float32(0.0), humans.hit)
        free = np.minimum(free, _segment_min_rows(hit, pair_row, n))

    # Clearance along each trimmed arc: walls from the running minimum, humans in closed form.
    last = np.searchsorted(table.lengths[:num_samples], free, side="right") - 1  # (n, A)
    wall_code = codes[last, np.arange(len(k)), np.arange(n)[:, None]]  # (n, A)
    clearance = wall_code * field.quantum - cfg.robot_radius
    if humans is not None:
        gap = human_gaps(humans, free[pair_row], table) - (cfg.robot_radius + cfg.human_radius)
        clearance = np.minimum(clearance, _segment_min_rows(gap, pair_row, n))
    clearance = np.minimum(np.maximum(clearance, 0.0), cfg.clearance_cap)

    # Score and choose.
    ex, ey = arc_points(k, table.side, free)
    remaining = np.sqrt((ex - tx[:, None]) ** 2 + (ey - ty[:, None]) ** 2)
    score = cfg.progress_weight * (tdist[:, None] - remaining) + cfg.free_path_weight * free
    score -= clearance_weight[:, None] * clearance
    movable = free > _MIN_FREE
    score[~movable] = -np.inf
    best = score.argmax(axis=1)
    rows = np.arange(n)
    best_free = np.where(movable[rows, best], free[rows, best], 0.0)
    return ArcEvaluation(
        target=np.column_stack((tx, ty)),
        bearing=bearing,
        turn=turn,
        trim=trim,
        free=free,
        clearance=clearance,
        score=score,
        best=best,
        best_free=best_free,
        wall_blocked=wall_blocked,
    )


def plan_commands(
    pose: np.ndarray,
    vel: np.ndarray,
    target: np.ndarray,
    max_speed: np.ndarray,
    clearance_weight: np.ndarray,
    walls: WallIndex,
    human_pos: np.ndarray,
    human_mask: np.ndarray,
    cfg: LocalPlannerConfig,
    robot_cfg: RobotConfig,
    dt: float,
    active: np.ndarray | None = None,
    human_vel: np.ndarray | None = None,
) -> np.ndarray:
    """Velocity commands that drive each robot towards its local target without collisions.

    Each row samples constant-curvature arcs, trims them at the first collision and at the closest
    approach to its local target, scores them, and drives along the best one with 1-D time-optimal
    speed control; a target far off the heading makes the robot stop and turn in place instead.

    Speed: v = min(max_speed, v_prev + a dt, the speed that still stops within L at deceleration a),
    and no faster than lets omega = v c be reached under the robot's angular acceleration limit, so
    that the robot really follows the arc it checked.

    Turning and recovery (refinements of the SPEC's rule, needed in GDC1's 0.9 m doorways):
    - the 30 degree turn-in-place test uses the target's bearing slid along the nearest wall when
      the robot is within `slide_band` of its margin and the straight line to its target is blocked
      (so it lines up with a doorway instead of facing the door frame that hides its target), tilted
      away from the wall inside the margin; with the line clear, the target's own bearing (in a
      doorway the wall gradient points back out of the door);
    - a robot whose every arc is blocked by walls turns in place to the heading, on a 15 degree
      fan, whose straight line makes the most progress towards its target.

    Args:
        pose: (N, 3) robot pose x, y (m), theta (rad), world frame.
        vel: (N, 2) current (v, omega), m/s and rad/s.
        target: (N, 2) local target, world frame, m.
        max_speed: (N,) speed limit of each row, m/s.
        clearance_weight: (N,) clearance weight of each row (cost sign: negative rewards
            clearance).
        walls: the map's wall index (its distance field is built on first use and cached).
        human_pos: (N, H, 2) human positions, world frame, m.
        human_mask: (N, H) present humans; every present human is an obstacle.
        cfg: planner parameters.
        robot_cfg: robot limits (angular speed and acceleration for turning in place).
        dt: control period, s.
        active: (N,) bool rows to plan for; the others get a zero command. None: all rows.
        human_vel: (N, H, 2) human velocities, world frame, m/s (see `evaluate_arcs`).

    Returns:
        (N, 2) command (v, omega), m/s and rad/s: omega = v * curvature along the chosen arc, or
        (braking, rotation) when turning in place. A row with no free arc stops.
    """
    num_rows = len(pose)
    command = np.zeros((num_rows, 2))
    if active is not None and not active.all():
        rows = np.flatnonzero(active)
        if len(rows):
            command[rows] = plan_commands(
                pose[rows],
                vel[rows],
                target[rows],
                max_speed[rows],
                clearance_weight[rows],
                walls,
                human_pos[rows],
                human_mask[rows],
                cfg,
                robot_cfg,
                dt,
                human_vel=None if human_vel is None else human_vel[rows],
            )
        return command
    if num_rows == 0:
        return command
    ev = evaluate_arcs(pose, target, clearance_weight, walls, human_pos, human_mask, cfg, human_vel)
    curvature = arc_table(cfg).curvature

    # 1-D time-optimal speed along the chosen arc: accelerate while a stop within the free
    # length stays possible at the planner's deceleration. The speed is also held to what the
    # robot's angular acceleration can follow, so that omega = v * c is reached this step and the
    # robot stays on the arc that was checked (rather than swinging wide of it).
    v_prev, w_prev = vel[:, 0], vel[:, 1]
    accel = cfg.planner_accel
    c = curvature[ev.best]
    speed = np.minimum(np.minimum(max_speed, v_prev + accel * dt), _stopping_speed(ev.best_free, accel, dt))
    reachable = np.minimum(
        np.maximum(w_prev * np.sign(c), 0.0) + robot_cfg.max_angular_accel * dt, robot_cfg.max_angular_speed
    )
    speed = np.minimum(speed, reachable / np.maximum(np.abs(c), 1e-9))
    speed = np.maximum(speed, 0.0)
    command[:, 0] = speed
    command[:, 1] = speed * c

    # Turning in place: when the bearing is large, or to the recovery heading of a stuck robot.
    if ev.turn.any():
        turning = np.stack(_turn_in_place(ev.bearing, vel, cfg, robot_cfg, dt), axis=-1)
        command = np.where(ev.turn[:, None], turning, command)
    return command


def _turn_in_place(
    bearing: np.ndarray, vel: np.ndarray, cfg: LocalPlannerConfig, robot_cfg: RobotConfig, dt: float
) -> tuple[np.ndarray, np.ndarray]:
    """(v, omega) commands (N,) that brake, then rotate by `bearing` (N,) rad time-optimally."""
    v_prev, w_prev = vel[:, 0], vel[:, 1]
    a_ang = robot_cfg.max_angular_accel
    direction = np.sign(bearing)
    along = w_prev * direction  # angular speed towards the target
    w_mag = np.minimum(
        np.minimum(robot_cfg.max_angular_speed, np.maximum(along, 0.0) + a_ang * dt),
        _stopping_speed(np.abs(bearing), a_ang, dt),
    )
    slow_down = w_prev - np.sign(w_prev) * np.minimum(np.abs(w_prev), a_ang * dt)
    omega = np.where(along < 0.0, slow_down, direction * w_mag)
    omega = np.where(v_prev > cfg.turn_in_place_max_speed, 0.0, omega)
    return np.maximum(v_prev - cfg.planner_accel * dt, 0.0), omega


def _recovery_bearing(
    field: DistanceField,
    pose: np.ndarray,
    tx: np.ndarray,
    ty: np.ndarray,
    limit: np.ndarray,
    fallback: np.ndarray,
    cfg: LocalPlannerConfig,
) -> np.ndarray:
    """Heading change (N,) rad for robots whose every arc is blocked by walls.

    Straight lines from the robot every 15 degrees are checked against the wall distance field
    (at `limit` (N,), m) up to `recovery_length`; the heading whose free line gets closest to
    the target (tx, ty) (robot frame) wins, smaller turns breaking near ties. Rows where no line
    is free keep `fallback` (N,).
    """
    headings = np.radians(np.arange(-165.0, 181.0, 15.0))  # (K,) relative to the robot
    step = cfg.near_sample_spacing
    dist = np.arange(step, cfg.recovery_length + step / 2, step)  # (M,)
    world = pose[:, 2:3] + headings  # (N, K)
    ux, uy = np.cos(world), np.sin(world)
    points = pose[:, None, None, :2] + dist[None, None, :, None] * np.stack((ux, uy), axis=-1)[:, :, None, :]
    blocked = np.logical_or.accumulate(field.lookup(points) < limit[:, None, None], axis=-1)
    num_free = (~blocked).sum(axis=-1)  # (N, K) leading free samples
    free = np.concatenate(([0.0], dist))[num_free]
    ex, ey = free * np.cos(headings), free * np.sin(headings)
    progress = np.sqrt(tx * tx + ty * ty)[:, None] - np.sqrt(
        (tx[:, None] - ex) ** 2 + (ty[:, None] - ey) ** 2
    )
    score = np.where(free >= 2.0 * cfg.stuck_length, progress - 0.05 * np.abs(headings), -np.inf)
    best = score.argmax(axis=1)
    found = np.isfinite(score[np.arange(len(pose)), best])
    return np.where(found, headings[best], fallback)


def _line_clear(
    field: DistanceField, pose: np.ndarray, tx: np.ndarray, ty: np.ndarray, limit: np.ndarray, spacing: float
) -> np.ndarray:
    """(N,) bool: the straight line from each robot to its target (tx, ty) (robot frame) keeps
    `limit` (N,) from walls at every sample `spacing` apart past the robot itself."""
    dist = np.sqrt(tx * tx + ty * ty)
    steps = np.arange(1, max(1, math.ceil(float(dist.max(initial=0.0)) / spacing)) + 1) * spacing  # (M,)
    frac = np.minimum(steps[None, :] / np.maximum(dist, 1e-9)[:, None], 1.0)  # (N, M)
    cos, sin = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    wx, wy = cos * tx - sin * ty, sin * tx + cos * ty
    points = pose[:, None, :2] + frac[..., None] * np.stack((wx, wy), axis=-1)[:, None, :]
    return np.asarray((field.lookup(points) >= limit[:, None]).all(axis=1))


def _slide_bearing(
    field: DistanceField, pose: np.ndarray, tx: np.ndarray, ty: np.ndarray, tilt: np.ndarray
) -> np.ndarray:
    """Bearing (N,) rad of the target direction (tx, ty) (robot frame) slid along the nearest wall.

    The component of the target direction into the nearest wall (against the distance field's
    gradient) is removed; a target straight into the wall gives the wall direction nearer the
    heading. Then `tilt` (N,) times the unit gradient is added, turning the direction away from
    the wall (tilt 1: by 45 degrees from the wall's direction).
    """
    step = 2.0 * field.resolution
    probes = pose[:, None, :2] + np.array([[step, 0.0], [-step, 0.0], [0.0, step], [0.0, -step]])
    d = field.lookup(probes)
    gx, gy = d[:, 0] - d[:, 1], d[:, 2] - d[:, 3]
    cos, sin = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    grad = np.stack((cos * gx + sin * gy, cos * gy - sin * gx), axis=-1)  # robot frame
    grad /= np.maximum(np.sqrt((grad**2).sum(-1)), 1e-9)[:, None]
    to_target = np.stack((tx, ty), axis=-1)
    to_target /= np.maximum(np.sqrt((to_target**2).sum(-1)), 1e-9)[:, None]
    into = np.minimum((to_target * grad).sum(-1), 0.0)
    desired = to_target - into[:, None] * grad
    tangent = np.stack((-grad[:, 1], grad[:, 0]), axis=-1)
    tangent *= np.where(tangent[:, 0] < 0.0, -1.0, 1.0)[:, None]
    desired = np.where(((desired**2).sum(-1) < 1e-2)[:, None], tangent, desired)
    desired /= np.sqrt((desired**2).sum(-1))[:, None]
    desired += tilt[:, None] * grad
    return np.arctan2(desired[:, 1], desired[:, 0])
