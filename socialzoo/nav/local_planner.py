"""Trajectory-rollout local planner (SPEC section 6), vectorised over batch rows and arcs.

Each row samples constant-curvature arcs, trims them at the first collision and at the closest
approach to its local target, scores them, and drives along the best one with 1-D time-optimal
speed control; a target far off the heading makes the robot stop and turn in place instead.

Collision model. The planning footprint is a disc of `robot_radius` around the robot centre; it
must stay `obstacle_margin` away from walls and from human discs of `human_radius`.
- Walls: a precomputed distance field of the map (the distance to the nearest wall at the centres
  of a 2.5 cm grid, one byte per cell) is read at sample points along every arc, so a call costs
  one gather per sample point whatever the wall density. The sample points come from one
  (A * S, 2) x (2, 2N) product of arc offsets precomputed in the robot frame.
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

Speed: v = min(max_speed, v_prev + a dt, the speed that still stops within L at deceleration a),
and no faster than lets omega = v c be reached under the robot's angular acceleration limit, so
that the robot really follows the arc it checked.

Turning and recovery (refinements of the SPEC's rule, needed in GDC1's 0.9 m doorways):
- the 30 degree turn-in-place test uses the target's bearing slid along the nearest wall when
  the robot is within `slide_band` of its margin (so it lines up with a doorway instead of
  facing the door frame that hides its target), tilted away from the wall inside the margin;
- a robot whose every arc is blocked by walls turns in place to the heading, on a 15 degree
  fan, whose straight line makes the most progress towards its target.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, fields
from functools import lru_cache

import numpy as np

from socialzoo.core.config import RobotConfig
from socialzoo.core.jit import kernel
from socialzoo.core.walls import WallIndex
from socialzoo.nav.distance_field import DistanceField, distance_field

# Curvatures below this are straight lines; the closed forms below use it in place of zero.
_STRAIGHT = 1e-9
# Free lengths at or below this do not count as a move (m).
_MIN_FREE = 1e-3
_TWO_PI = 2.0 * math.pi
# Batches of at least this many rows evaluate rows whose trimmed arcs all end within
# _SHORT_ARC (m) apart, with fewer wall samples (see evaluate_arcs).
_SPLIT_ROWS = 32
_SHORT_ARC = 1.6
# Guards float32 divisions by quantities that vanish only in degenerate geometry.
_TINY32 = np.float32(1e-30)


@dataclass(frozen=True, kw_only=True)
class LocalPlannerConfig:
    """Trajectory-rollout parameters (SPEC section 6).

    Attributes:
        curvature_min, curvature_max, curvature_step: the sampled arcs, 1/m (41 by default).
        turn_in_place_angle_deg: a target farther off the heading than this makes the robot
            stop and turn in place, degrees.
        turn_in_place_max_speed: the robot starts turning only once slower than this, m/s
            (it brakes first, as the reference does).
        obstacle_margin: required gap between the planning disc and any obstacle, m.
        max_arc_length: longest arc considered, m.
        target_clip: local targets farther than this are pulled in along their bearing, m (the
            reference clips its local target to the carrot distance, 1.5 m).
        clearance_cap: clearance counts up to this, m.
        planner_accel: linear acceleration and deceleration limit of the speed control, m/s^2.
        progress_weight: score per metre of progress towards the target.
        free_path_weight: score per metre of free path length.
        robot_radius: planning disc radius, m: smaller than the collision footprint (a
            0.5 x 0.43 m box, half-diagonal 0.332 m), as the SPEC allows; with the margin the
            disc still covers it, and GDC1's 0.87 m doors stay passable.
        human_radius: radius of a human disc, m.
        human_lookahead: a walking human is also an obstacle where it will be this many seconds
            later at its present velocity (0: present positions only, as the SPEC's rollout).
            The rollout itself sees a frozen scene; without this, people who walk into a
            slowing or waiting robot make up most collisions (GoAlone among 5-25 humans on GDC1:
            68% of episodes collision-free with 0, 82% with 0.5 s).
        min_wall_distance: hard floor of the escape rule on the centre's wall distance, m: with
            the distance field's lookup error (under 0.02 m) it keeps the footprint's corners
            off the walls even while the robot turns in place.
        min_human_distance: hard floor of the escape rule on robot-human centre distance, m.
        escape_slack: how much closer than now an escaping arc may pass, m.
        slide_band: a robot closer than wall_distance + slide_band to a wall turns towards its
            target slid along that wall (see ArcEvaluation.bearing), m.
        stuck_length: a robot whose every arc is blocked by walls within this is stuck, m.
        recovery_length: how far a stuck robot looks along candidate headings, m.
        recovery_angle_deg: a stuck robot turns in place until its heading is within this of
            the recovery direction, degrees.
        sample_spacing: spacing of wall-check samples along an arc, m.
        near_sample_spacing: finer spacing used up to `near_range`, m.
        near_range: extent of the finely sampled start of each arc, m.
        field_resolution: cell size of the wall distance field, m.
    """

    curvature_min: float = -2.0
    curvature_max: float = 2.0
    curvature_step: float = 0.1
    turn_in_place_angle_deg: float = 30.0
    turn_in_place_max_speed: float = 0.1
    obstacle_margin: float = 0.1
    max_arc_length: float = 5.0
    target_clip: float = 1.5
    clearance_cap: float = 1.0
    planner_accel: float = 5.0
    progress_weight: float = 1.0
    free_path_weight: float = 0.1
    robot_radius: float = 0.27
    human_radius: float = 0.2
    human_lookahead: float = 0.5
    min_wall_distance: float = 0.355
    min_human_distance: float = 0.45
    escape_slack: float = 0.04
    slide_band: float = 0.1
    stuck_length: float = 0.05
    recovery_length: float = 0.6
    recovery_angle_deg: float = 2.0
    sample_spacing: float = 0.1
    near_sample_spacing: float = 0.05
    near_range: float = 0.3
    field_resolution: float = 0.025

    def __post_init__(self) -> None:
        signed = {"curvature_min", "curvature_max"}
        nonnegative = {"obstacle_margin", "progress_weight", "free_path_weight", "escape_slack", "near_range"}
        nonnegative |= {"human_lookahead"}
        nonnegative |= {"turn_in_place_max_speed", "turn_in_place_angle_deg"}
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
                raise ValueError(f"LocalPlannerConfig.{f.name} must be a finite number, got {value!r}")
            if f.name in signed:
                continue
            if value < 0 or (value == 0 and f.name not in nonnegative):
                limit = ">= 0" if f.name in nonnegative else "> 0"
                raise ValueError(f"LocalPlannerConfig.{f.name} must be {limit}, got {value!r}")
        if self.curvature_min >= self.curvature_max:
            raise ValueError(
                f"LocalPlannerConfig.curvature_min ({self.curvature_min!r}) must be below "
                f"curvature_max ({self.curvature_max!r})"
            )
        steps = (self.curvature_max - self.curvature_min) / self.curvature_step
        if abs(steps - round(steps)) > 1e-6:
            raise ValueError(
                f"LocalPlannerConfig.curvature_step ({self.curvature_step!r}) must divide "
                f"curvature_max - curvature_min ({self.curvature_max - self.curvature_min!r})"
            )
        if self.turn_in_place_angle_deg > 180.0:
            raise ValueError(
                "LocalPlannerConfig.turn_in_place_angle_deg must be <= 180, "
                f"got {self.turn_in_place_angle_deg!r}"
            )
        if self.min_wall_distance > self.wall_distance:
            raise ValueError(
                f"LocalPlannerConfig.min_wall_distance ({self.min_wall_distance!r}) exceeds "
                f"robot_radius + obstacle_margin ({self.wall_distance!r})"
            )
        if self.min_human_distance > self.human_distance:
            raise ValueError(
                f"LocalPlannerConfig.min_human_distance ({self.min_human_distance!r}) exceeds "
                f"robot_radius + obstacle_margin + human_radius ({self.human_distance!r})"
            )
        if self.near_sample_spacing > self.sample_spacing:
            raise ValueError(
                f"LocalPlannerConfig.near_sample_spacing ({self.near_sample_spacing!r}) exceeds "
                f"sample_spacing ({self.sample_spacing!r})"
            )

    @property
    def curvatures(self) -> np.ndarray:
        """(A,) sampled curvatures, 1/m, increasing (A = 41 by default)."""
        count = round((self.curvature_max - self.curvature_min) / self.curvature_step) + 1
        return np.round(np.linspace(self.curvature_min, self.curvature_max, count), 12)

    @property
    def num_arcs(self) -> int:
        return len(self.curvatures)

    @property
    def wall_distance(self) -> float:
        """Required distance from the robot centre to walls, m."""
        return self.robot_radius + self.obstacle_margin

    @property
    def human_distance(self) -> float:
        """Required robot-human centre distance, m."""
        return self.robot_radius + self.obstacle_margin + self.human_radius

    @property
    def field_pad(self) -> float:
        """The distance field extends this far past the walls, m: arcs (at most about 1.1 times
        the clipped target distance) of robots inside the walls' bounding box stay on the grid
        (a sample off the grid would read its border cell)."""
        return min(self.max_arc_length, 2.0 * self.target_clip)

    @property
    def field_range(self) -> float:
        """Distances are resolved up to this in the wall distance field, m."""
        return max(self.wall_distance, self.robot_radius + self.clearance_cap) + 0.1


# ---------------------------------------------------------------------------------------------
# Arc tables


@dataclass(frozen=True)
class ArcTable:
    """Arc geometry shared by every call with one config.

    Attributes:
        curvature: (A,) signed curvature, 1/m.
        abs_curvature: (A,) |curvature|, with straight arcs at a tiny positive value.
        side: (A,) +1 for left turns (and straight), -1 for right turns.
        lengths: (K,) arc length of the wall-check samples, m, increasing from 0.
        free_at: (K + 1,) free length when the first blocked sample is k (k = K: none blocked):
            the length of the sample before it, 0 for k = 0, inf for k = K, m.
        offsets: (A, K, 2) sample positions in the robot frame (x ahead, y left), m.
        cell_offsets: (K, A, 2) float32 offsets in distance-field cells (cfg.field_resolution),
            sample-major so that a prefix of samples is one contiguous block.
        abs_curvature32, side32, half_k2, two_over_k2: float32 (A,) copies for the human terms:
            |c|, side, c^2 / 2 and 2 / c^2.
    """

    curvature: np.ndarray
    abs_curvature: np.ndarray
    side: np.ndarray
    lengths: np.ndarray
    free_at: np.ndarray
    offsets: np.ndarray
    cell_offsets: np.ndarray
    abs_curvature32: np.ndarray
    side32: np.ndarray
    half_k2: np.ndarray
    two_over_k2: np.ndarray


def arc_points(
    abs_curvature: np.ndarray, side: np.ndarray, length: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Robot-frame point reached after `length` metres along arcs; broadcasts, returns (x, y)."""
    turn = abs_curvature * length
    x = np.sin(turn) / abs_curvature
    # 1 - cos(u) written as 2 sin^2(u / 2): exact for the tiny curvature of straight arcs.
    y = side * 2.0 * np.sin(0.5 * turn) ** 2 / abs_curvature
    return x, y


@lru_cache(maxsize=16)
def arc_table(cfg: LocalPlannerConfig) -> ArcTable:
    """Precomputed arcs and sample offsets for a config."""
    curvature = cfg.curvatures
    side = np.where(curvature < 0.0, -1.0, 1.0)
    abs_curvature = np.maximum(np.abs(curvature), _STRAIGHT)
    near = np.arange(0.0, cfg.near_range - 1e-9, cfg.near_sample_spacing)
    far = np.arange(cfg.near_range, cfg.max_arc_length + 0.5 * cfg.sample_spacing, cfg.sample_spacing)
    lengths = np.unique(np.round(np.concatenate((near, np.minimum(far, cfg.max_arc_length))), 9))
    free_at = np.concatenate(([0.0], lengths[:-1], [np.inf]))
    x, y = arc_points(abs_curvature[:, None], side[:, None], lengths[None, :])
    offsets = np.stack((x, y), axis=-1)
    k32 = abs_curvature.astype(np.float32)
    return ArcTable(
        curvature=curvature,
        abs_curvature=abs_curvature,
        side=side,
        lengths=lengths,
        free_at=free_at,
        offsets=offsets,
        cell_offsets=np.ascontiguousarray(
            (offsets / cfg.field_resolution).astype(np.float32).transpose(1, 0, 2)
        ),
        abs_curvature32=k32,
        side32=side.astype(np.float32),
        half_k2=(0.5 * abs_curvature**2).astype(np.float32),
        two_over_k2=(2.0 / abs_curvature**2).astype(np.float32),
    )


# ---------------------------------------------------------------------------------------------
# The planner


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


@kernel
def _arc_wall_codes(x, y, cos, sin, offsets, field_shape, field_codes, here, codes):  # type: ignore[no-untyped-def]
    """Distance-field codes along every arc of every row, as running minima.

    codes (S, A, N) gets, for sample j of arc a of row i, the smallest field code over samples
    0..j; sample 0 (the robot's own position) reads 255, because it never blocks an arc: the
    robot is where it is, and an arc leading away from a wall it is too close to must stay open.
    here (N,) gets the code at the robot. offsets (K >= S, A, 2) are the arc samples in field
    cells (ArcTable.cell_offsets), rotated by each row's heading in float32.
    """
    ox, oy, res, num_x, num_y, _ = field_shape
    num_samples, num_arcs, n = codes.shape
    c = cos.astype(np.float32)
    s = sin.astype(np.float32)
    sx = ((x - ox) / res).astype(np.float32)
    sy = ((y - oy) / res).astype(np.float32)
    for i in range(n):
        ix = min(max(int(sx[i]), 0), num_x - 1)
        iy = min(max(int(sy[i]), 0), num_y - 1)
        here[i] = field_codes[ix * num_y + iy]
        for a in range(num_arcs):
            codes[0, a, i] = 255
    for j in range(1, num_samples):
        for a in range(num_arcs):
            off_x, off_y = offsets[j, a, 0], offsets[j, a, 1]
            for i in range(n):
                # Truncation is the floor on the grid, then rows near its border are clamped.
                ix = min(max(int(off_x * c[i] - off_y * s[i] + sx[i]), 0), num_x - 1)
                iy = min(max(int(off_x * s[i] + off_y * c[i] + sy[i]), 0), num_y - 1)
                codes[j, a, i] = min(field_codes[ix * num_y + iy], codes[j - 1, a, i])


def _segment_min_rows(values: np.ndarray, rows: np.ndarray, num_rows: int) -> np.ndarray:
    """Row-wise minimum of values (P, A) whose rows (P,) are sorted: (num_rows, A), inf if none."""
    if num_rows == 1:
        return values.min(axis=0, keepdims=True)
    out = np.full((num_rows, values.shape[1]), np.inf)
    starts = np.flatnonzero(np.concatenate(([True], rows[1:] != rows[:-1])))
    out[rows[starts]] = np.minimum.reduceat(values, starts, axis=0)
    return out


@dataclass(frozen=True)
class _HumanArcs:
    """Circle-disc terms of pair humans against every arc (float32, (P, A) unless noted)."""

    yp: np.ndarray  # human's lateral offset towards the arc's turning side, m
    r: np.ndarray  # k * (distance from the turning centre to the human)
    r_minus_a: np.ndarray  # r - (1 - k yp), free of cancellation
    psi: np.ndarray  # turning angle at the human's closest approach, in [0, 2 pi)
    dist2: np.ndarray  # (P, 1) squared robot-human distance, m^2
    hit: np.ndarray  # free length before the inflated disc, m (inf on a miss)


def _human_arcs(hx: np.ndarray, hy: np.ndarray, radius: np.ndarray, table: ArcTable) -> _HumanArcs:
    """Where every arc enters the discs of radius `radius` around humans (hx, hy) (P,), robot frame.

    Along an arc of curvature k, the squared distance to h after turning u = k s is
    (2 / k^2) (a - r cos(u - psi) + k^2 |h|^2 / 2) with a = 1 - k yp, b = k hx, r = |(a, b)|,
    psi = atan2(b, a). Every term is written so that it stays accurate in float32 down to the
    tiny curvature of the straight arc.
    """
    k = table.abs_curvature32
    hx32 = hx.astype(np.float32)[:, None]
    yp = table.side32 * hy.astype(np.float32)[:, None]
    dist2 = hx32 * hx32 + (hy * hy).astype(np.float32)[:, None]
    a = 1.0 - k * yp
    b = k * hx32
    b2 = b * b
    r = np.sqrt(a * a + b2)
    psi = np.arctan2(b, a)
    # r - a = b^2 / (r + a) when a > 0 (no cancellation); r + |a| never vanishes unless r does.
    abs_a = np.abs(a)
    r_minus_a = np.where(a > 0.0, b2 / np.maximum(r + abs_a, _TINY32), r + abs_a)
    r = np.maximum(r, _TINY32)
    e = table.half_k2 * (dist2 - (radius * radius).astype(np.float32)[:, None])
    # 1 - cos(delta), delta the half-angle of the arc inside the disc.
    one_minus = (r_minus_a - e) / r
    meets = (one_minus >= 0.0) & (one_minus <= 2.0)
    delta = 2.0 * np.arcsin(np.sqrt(np.clip(0.5 * one_minus, 0.0, 1.0)))
    enter = psi - delta
    enter += np.float32(_TWO_PI) * (enter < 0.0)
    hit = np.where(meets, enter / k, np.float32(np.inf))
    psi += np.float32(_TWO_PI) * (psi < 0.0)
    return _HumanArcs(yp=yp, r=r, r_minus_a=r_minus_a, psi=psi, dist2=dist2, hit=hit)


def _human_gaps(h: _HumanArcs, length: np.ndarray, table: ArcTable) -> np.ndarray:
    """(P, A) smallest robot-human centre distance along the arcs' first `length` (P, A) metres."""
    k = table.abs_curvature32
    turn = length.astype(np.float32) * k
    half = 0.5 * (turn - h.psi)
    end2 = table.two_over_k2 * (table.half_k2 * h.dist2 - h.r_minus_a + 2.0 * h.r * np.sin(half) ** 2)
    # Distance from the turning circle to the human, (r - 1) / k = (k |h|^2 - 2 yp) / (r + 1).
    ring = (k * h.dist2 - 2.0 * h.yp) / (h.r + 1.0)
    near2 = np.where(h.psi <= turn, ring * ring, np.minimum(end2, h.dist2))
    return np.sqrt(np.maximum(near2, 0.0))


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
    """Roll out, trim and score every arc of every row (see the module docstring).

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
    _arc_wall_codes(x, y, cos, sin, table.cell_offsets, field.shape_args, field.codes, here_code, codes)
    here = here_code * field.quantum
    limit = _escape_limit(here, cfg.wall_distance, cfg.min_wall_distance, cfg.escape_slack)
    limit_code = np.ceil(limit / field.quantum - 1e-9).astype(np.uint8)
    num_free = (codes >= limit_code).sum(axis=0, dtype=np.uint8)  # (A, n) unblocked samples
    free = np.minimum(table.free_at[np.minimum(num_free, num_samples)].T, trim)
    free = np.where(num_free.T >= num_samples, trim, free)

    # The heading to turn to: towards the target, or, for a robot close to a wall, towards the
    # target with its into-the-wall part removed (so that it lines up with a doorway or corridor
    # instead of facing a wall corner that hides its target).
    bearing = np.arctan2(ty, tx)
    near = here < cfg.wall_distance + cfg.slide_band
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
        humans = _human_arcs(hx, hy, radius, table)
        # Inside the hard floor and not moving away: blocked at once.
        hit = np.where(((hd < radius) & (hx > 0.0))[:, None], np.float32(0.0), humans.hit)
        free = np.minimum(free, _segment_min_rows(hit, pair_row, n))

    # Clearance along each trimmed arc: walls from the running minimum, humans in closed form.
    last = np.searchsorted(table.lengths[:num_samples], free, side="right") - 1  # (n, A)
    wall_code = codes[last, np.arange(len(k)), np.arange(n)[:, None]]  # (n, A)
    clearance = wall_code * field.quantum - cfg.robot_radius
    if humans is not None:
        gap = _human_gaps(humans, free[pair_row], table) - (cfg.robot_radius + cfg.human_radius)
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
    turn = ev.turn
    if turn.any():
        v_cmd, w_cmd = _turn_in_place(ev.bearing, vel, cfg, robot_cfg, dt)
        command[:, 0] = np.where(turn, v_cmd, command[:, 0])
        command[:, 1] = np.where(turn, w_cmd, command[:, 1])
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
