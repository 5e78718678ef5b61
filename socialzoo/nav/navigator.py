"""Global-plan tracking for a batch of robots: distance to the plan, replanning, the carrot.

SPEC section 6: replan when a robot is more than 0.5 m from its plan; the local target ("carrot")
is the point where a 1.5 m circle around the robot leaves the path. With a Sight (as the envs
use it) the carrot stays where the robot can drive to it in a straight line, and plans avoid
straight joins that graze walls: on real floor plans the plain carrot, placed behind a door frame
or corner, pinned the robot against it for the whole episode.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.core.validation import check_int, check_number
from socialzoo.nav.distance_field import DistanceField, field_distance

logger = logging.getLogger(__name__)

# Default carrot circle radius (m) and allowed deviation from the plan (m), SPEC section 6.
CARROT_RADIUS = 1.5
REPLAN_DISTANCE = 0.5


class PathPlanner(Protocol):
    """What the navigator needs from a navigation graph (socialzoo.nav.graph.NavGraph)."""

    def plan_batch(
        self, starts: np.ndarray, goals: np.ndarray, *, clearance: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """(paths (N, L, 2), lengths (N,)) for starts and goals (N, 2), padded with the last point;
        straight joins keep `clearance` (m) from walls where they can."""
        ...


@dataclass
class GlobalPlans:
    """The global plan of every robot of a batch.

    Attributes:
        paths: (B, R, L, 2) waypoints from (about) the robot to its goal, world frame, m; each
            path is padded to L by repeating its last waypoint.
        lengths: (B, R) int number of valid waypoints (>= 1).
    """

    paths: np.ndarray
    lengths: np.ndarray

    @staticmethod
    def empty(batch_size: int, num_robots: int = 1) -> GlobalPlans:
        """Plans of one waypoint at the origin (to be overwritten by a reset)."""
        return GlobalPlans(
            paths=np.zeros((batch_size, num_robots, 1, 2)),
            lengths=np.ones((batch_size, num_robots), dtype=np.intp),
        )

    def assign(self, index: tuple[np.ndarray, ...], paths: np.ndarray, lengths: np.ndarray) -> None:
        """Overwrite the plans at `index` (any numpy index of the (B, R) axes).

        Args:
            index: selects M plans of the (B, R) grid, e.g. (rows,) or (rows, robots).
            paths: (M, L', 2) new waypoints padded with their last one.
            lengths: (M,) valid waypoints per new path.
        """
        width = max(self.paths.shape[2], paths.shape[1])
        self.paths = _pad_paths(self.paths, width)
        self.paths[index] = _pad_paths(paths, width).reshape(self.paths[index].shape)
        self.lengths[index] = np.asarray(lengths).reshape(self.lengths[index].shape)


def _pad_paths(paths: np.ndarray, width: int) -> np.ndarray:
    """Pad the waypoint axis (-2) of paths to `width` by repeating the last waypoint."""
    have = paths.shape[-2]
    if have >= width:
        return paths
    last = np.repeat(paths[..., -1:, :], width - have, axis=-2)
    return np.concatenate((paths, last), axis=-2)


def distance_to_path(pos: np.ndarray, paths: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Distance from points to their polyline paths.

    Args:
        pos: (..., 2) points, world frame, m.
        paths: (..., L, 2) waypoints, padded by repeating the last one.
        lengths: (...,) int number of valid waypoints (>= 1).

    Returns:
        (...,) distance to the nearest point of the path, m.
    """
    return track(pos, paths, lengths)[1]


def needs_replan(
    pos: np.ndarray, paths: np.ndarray, lengths: np.ndarray, max_distance: float = REPLAN_DISTANCE
) -> np.ndarray:
    """(...,) bool: robots more than max_distance (m) from their plan (SPEC: 0.5 m)."""
    return distance_to_path(pos, paths, lengths) > max_distance


def carrot(
    pos: np.ndarray,
    paths: np.ndarray,
    lengths: np.ndarray,
    radius: float = CARROT_RADIUS,
    max_skip: int | None = None,
    tolerance: float = 0.0,
) -> np.ndarray:
    """The local target: where a circle around the robot leaves its path, going forward.

    As the reference navigation does: the goal itself when it lies inside the circle; else,
    from the path segment closest to the robot, walk forward to the first waypoint outside the
    circle and take the circle's crossing of the segment that reaches it (the crossing nearer that
    waypoint). A robot farther than `radius` from its whole path gets its closest path point.

    Args:
        pos: (..., 2) robot positions, world frame, m.
        paths: (..., L, 2) waypoints, padded by repeating the last one.
        lengths: (...,) int number of valid waypoints (>= 1).
        radius: circle radius, m (SPEC: 1.5).
        max_skip: if given, the carrot lies at most this many whole segments past the closest
            segment: it stops at that segment's end even inside the circle (or, where that end
            is nearer than radius / 2, at the first later waypoint that is not). This keeps the
            carrot from cutting through a wall where the path turns back within the circle (a
            U-turn through two doors). None: no limit.
        tolerance: segments within this of the closest distance count as closest too, and the
            one furthest along the path is used, m.

    Returns:
        (..., 2) carrot, world frame, m.
    """
    return track(pos, paths, lengths, radius, max_skip, tolerance)[0]


@dataclass(frozen=True)
class Sight:
    """What keeps the carrot in sight: the map's wall distance field and the clearance wanted.

    A carrot is in sight when the straight line from the robot to it keeps at least
    min(clearance, the robot's own wall distance, the carrot's wall distance) - tolerance from
    every wall, read in the distance field (socialzoo.nav.distance_field): the robot can drive
    straight to it without entering its wall margin.

    Attributes:
        field: the distance field (its `shape_args` and `codes`).
        clearance: wanted distance from the line to walls, m (the local planner's wall distance).
        tolerance: slack for the field's lookup error, m.
        step: spacing of the carrot candidates along the path, m.
        spacing: spacing of the field samples along a sight line, m.
        min_ahead: the carrot is never pulled back closer than this along the path to the
            robot's closest path point, m: where the path itself grazes a corner, the robot
            still has a target ahead and keeps its own wall distance as it goes round.
    """

    field: DistanceField
    clearance: float
    tolerance: float = 0.02
    step: float = 0.1
    spacing: float = 0.05
    min_ahead: float = 0.5

    def __post_init__(self) -> None:
        for name, positive in (
            ("clearance", True),
            ("tolerance", False),
            ("step", True),
            ("spacing", True),
            ("min_ahead", False),
        ):
            value = getattr(self, name)
            ok = isinstance(value, (int, float)) and math.isfinite(value) and (value > 0 or not positive)
            if not ok or value < 0:
                raise ValueError(
                    f"Sight.{name} must be a {'positive' if positive else 'non-negative'} number, got {value!r}"
                )


def track(
    pos: np.ndarray,
    paths: np.ndarray,
    lengths: np.ndarray,
    radius: float = CARROT_RADIUS,
    max_skip: int | None = None,
    tolerance: float = 0.0,
    sight: Sight | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """`carrot` and `distance_to_path` from one pass over the path segments.

    With `sight`, a carrot the robot cannot drive to in a straight line (see Sight) is pulled back
    along the path to the last point before the first one out of sight, going forward from the
    robot's closest path point: the carrot waits at a corner or before a doorway until the robot
    has come round, instead of pulling it into the wall corner that hides the path.

    Returns:
        (carrot (..., 2) world frame m, distance (...,) m).
    """
    shape = np.shape(pos)[:-1]
    pos = np.asarray(pos, dtype=np.float64).reshape(-1, 2)
    lengths = np.asarray(lengths)
    lengths = (lengths if lengths.shape == shape else np.broadcast_to(lengths, shape)).reshape(-1)
    paths = np.asarray(paths, dtype=np.float64)
    paths = paths.reshape(-1, paths.shape[-2], 2)
    if paths.shape[1] == 1:
        paths = np.concatenate((paths, paths), axis=1)
    out = np.empty(pos.shape)
    dist = np.empty(len(pos))
    # Path positions (segment index, fraction) of the closest point and of the carrot.
    where = np.empty((len(pos), 4))
    _track_rows(
        pos, paths, lengths, radius, -1 if max_skip is None else max_skip, tolerance, out, dist, where
    )
    if sight is not None:
        f = sight.field
        _keep_in_sight(
            pos, paths, where, out, sight.clearance, sight.tolerance, sight.step, sight.spacing,
            sight.min_ahead, f.shape_args, f.codes,
        )  # fmt: skip
    return out.reshape(*shape, 2), dist.reshape(shape)


@kernel
def _in_sight(px, py, qx, qy, need, spacing, shape, codes):  # type: ignore[no-untyped-def]
    """Whether the line from (px, py) to (qx, qy) keeps `need` from walls (the start excluded)."""
    dx, dy = qx - px, qy - py
    num = int(math.sqrt(dx * dx + dy * dy) / spacing) + 1
    for i in range(1, num + 1):
        f = i / num
        if field_distance(px + f * dx, py + f * dy, shape, codes) < need:
            return False
    return True


@kernel
def _keep_in_sight(pos, paths, where, out, clearance, tolerance, step, spacing, min_ahead, shape, codes):  # type: ignore[no-untyped-def]
    """Pull each row's carrot `out` (M, 2) back into sight along its path (see `track`), never
    closer than `min_ahead` along the path to the closest point.

    where (M, 4): closest segment, its fraction, carrot segment, its fraction.
    """
    for m in range(pos.shape[0]):
        px, py = pos[m, 0], pos[m, 1]
        here = field_distance(px, py, shape, codes)
        cx, cy = out[m, 0], out[m, 1]
        need = min(clearance, here, field_distance(cx, cy, shape, codes)) - tolerance
        if _in_sight(px, py, cx, cy, need, spacing, shape, codes):
            continue
        seg, frac = int(where[m, 0]), where[m, 1]
        last_seg, last_frac = int(where[m, 2]), where[m, 3]
        ax, ay = paths[m, seg, 0], paths[m, seg, 1]
        bx, by = paths[m, seg + 1, 0], paths[m, seg + 1, 1]
        # Start at the closest point; it stays the carrot if nothing further on is in sight.
        best_x, best_y = ax + frac * (bx - ax), ay + frac * (by - ay)
        blocked = False
        walked = 0.0
        while not blocked:
            ax, ay = paths[m, seg, 0], paths[m, seg, 1]
            bx, by = paths[m, seg + 1, 0], paths[m, seg + 1, 1]
            seg_len = math.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
            end = last_frac if seg == last_seg else 1.0
            inc = step / seg_len if seg_len > 0.0 else 1.0
            while True:
                walked += (min(frac + inc, end) - frac) * seg_len
                frac = min(frac + inc, end)
                qx, qy = ax + frac * (bx - ax), ay + frac * (by - ay)
                need = min(clearance, here, field_distance(qx, qy, shape, codes)) - tolerance
                # The first min_ahead metres are always taken: a carrot that could wait right
                # at the robot (a path grazing a corner) would give it nothing to drive to.
                if walked > min_ahead and not _in_sight(px, py, qx, qy, need, spacing, shape, codes):
                    blocked = True
                    break
                best_x, best_y = qx, qy
                if frac >= end:
                    break
            if seg >= last_seg:
                break
            seg += 1
            frac = 0.0
        out[m, 0], out[m, 1] = best_x, best_y


@kernel
def _track_rows(pos, paths, lengths, radius, max_skip, tolerance, out, dist, where):  # type: ignore[no-untyped-def]
    """`track` for rows of pos (M, 2), paths (M, L >= 2, 2), lengths (M,); max_skip -1 is None.

    where (M, 4) gets each row's closest segment and fraction along it, and the carrot's.
    """
    r2 = radius * radius
    num_points = paths.shape[1]
    seg_dist = np.empty(num_points - 1)
    seg_t = np.empty(num_points - 1)
    for m in range(pos.shape[0]):
        px, py = pos[m, 0], pos[m, 1]
        # Distance to each valid segment (a one-waypoint path is one degenerate segment).
        num_segments = max(lengths[m] - 1, 1)
        best = np.inf
        for s in range(num_segments):
            ax, ay = paths[m, s, 0], paths[m, s, 1]
            abx, aby = paths[m, s + 1, 0] - ax, paths[m, s + 1, 1] - ay
            len2 = abx * abx + aby * aby
            t = ((px - ax) * abx + (py - ay) * aby) / (len2 if len2 > 0.0 else 1.0)
            t = min(max(t, 0.0), 1.0)
            dx, dy = px - ax - t * abx, py - ay - t * aby
            seg_dist[s] = math.sqrt(dx * dx + dy * dy)
            seg_t[s] = t
            best = min(best, seg_dist[s])
        # The closest segment; of segments about as close (within `tolerance`), the one furthest
        # along, so that a path doubling back on itself does not pull the robot back and forth.
        seg = 0
        for s in range(num_segments):
            if (tolerance > 0.0 and seg_dist[s] <= best + tolerance) or seg_dist[s] == best:
                seg = s
                if tolerance <= 0.0:
                    break
        t = seg_t[seg]
        closest_x = paths[m, seg, 0] + t * (paths[m, seg + 1, 0] - paths[m, seg, 0])
        closest_y = paths[m, seg, 1] + t * (paths[m, seg + 1, 1] - paths[m, seg, 1])
        # First waypoint past the closest segment's start that lies outside the circle; the goal
        # is outside whenever it is used, so one always exists there. With max_skip, the waypoint
        # ending the allowed stretch counts as the exit, so the carrot stops there; if it is
        # nearer than half the radius (short segments), the next one that is not.
        exit_at = 1
        for k in range(seg + 1, lengths[m]):
            rel2 = (paths[m, k, 0] - px) ** 2 + (paths[m, k, 1] - py) ** 2
            if rel2 >= r2 or (max_skip >= 0 and k >= seg + 1 + max_skip and rel2 >= 0.25 * r2):
                exit_at = k
                break
        goal = lengths[m] - 1
        where[m, 0], where[m, 1] = seg, t
        if (paths[m, goal, 0] - px) ** 2 + (paths[m, goal, 1] - py) ** 2 < r2:
            out[m, 0], out[m, 1] = paths[m, goal, 0], paths[m, goal, 1]
            where[m, 2], where[m, 3] = max(goal - 1, 0), 1.0 if goal > 0 else 0.0
        elif seg_dist[seg] > radius:
            out[m, 0], out[m, 1] = closest_x, closest_y
            where[m, 2], where[m, 3] = seg, t
        else:
            # Crossing of |p0 + u (p1 - p0) - pos| = radius nearer p1: the larger root.
            x0, y0 = paths[m, exit_at - 1, 0], paths[m, exit_at - 1, 1]
            dx, dy = paths[m, exit_at, 0] - x0, paths[m, exit_at, 1] - y0
            fx, fy = x0 - px, y0 - py
            qa = dx * dx + dy * dy
            qb = fx * dx + fy * dy
            qc = fx * fx + fy * fy - r2
            root = (-qb + math.sqrt(max(qb * qb - qa * qc, 0.0))) / (qa if qa > 0.0 else 1.0)
            root = min(max(root, 0.0), 1.0)
            out[m, 0], out[m, 1] = x0 + root * dx, y0 + root * dy
            where[m, 2], where[m, 3] = exit_at - 1, root
            if exit_at - 1 < seg or (exit_at - 1 == seg and root < t):
                where[m, 2], where[m, 3] = seg, t
        dist[m] = best


class Navigator:
    """Global plans of a batch of robots, replanned when a robot strays from its plan.

    Args:
        graph: plans paths (a socialzoo.nav.graph.NavGraph).
        batch_size: B.
        num_robots: R robots per batch row.
        carrot_radius: local-target circle radius, m.
        replan_distance: a robot farther than this from its plan gets a new one, m.
        max_skip: passed to `carrot`. The defaults (the carrot stops at the end of
            the closest segment, or at the first later waypoint at least radius / 2 away;
            near-equal closest segments resolve to the one furthest along) depart from the plain
            SPEC carrot (None and 0.0) for robustness: with them GoAlone (no humans) reaches the
            goal from all 650 ordered pairs of GDC1's legal poses; the plain carrot cuts through
            the wall between two doors of a U-turn and oscillates on paths that double back.
        tolerance: as `max_skip`.
    """

    def __init__(
        self,
        graph: PathPlanner,
        batch_size: int,
        num_robots: int = 1,
        *,
        carrot_radius: float = CARROT_RADIUS,
        replan_distance: float = REPLAN_DISTANCE,
        max_skip: int | None = 0,
        tolerance: float = 0.3,
        sight: Sight | None = None,
    ) -> None:
        check_number("Navigator", "carrot_radius", carrot_radius, low=0, low_open=True)
        check_number("Navigator", "replan_distance", replan_distance, low=0, low_open=True)
        check_int("Navigator", "max_skip", max_skip, low=0, allow_none=True)
        check_number("Navigator", "tolerance", tolerance, low=0)
        self.graph = graph
        self.carrot_radius = carrot_radius
        self.replan_distance = replan_distance
        self.max_skip = max_skip
        self.tolerance = tolerance
        self.sight = sight
        self.plan_clearance = 0.0 if sight is None else sight.clearance
        self.plans = GlobalPlans.empty(batch_size, num_robots)
        self.goals = np.zeros((batch_size, num_robots, 2))

    @property
    def batch_size(self) -> int:
        """B, the number of worlds."""
        return self.plans.paths.shape[0]

    @property
    def num_robots(self) -> int:
        """R, the robots per world."""
        return self.plans.paths.shape[1]

    def reset(self, rows: np.ndarray, starts: np.ndarray, goals: np.ndarray) -> None:
        """Plan afresh for batch rows.

        Args:
            rows: (M,) int batch rows (or a (B,) bool mask).
            starts: (M, R, 2) robot positions, world frame, m ((M, 2) when R == 1).
            goals: (M, R, 2) goal positions, world frame, m ((M, 2) when R == 1).

        Raises:
            socialzoo.nav.graph.NoPathError: a start or goal cannot be joined to the graph.
        """
        rows = np.asarray(rows)
        if rows.dtype == bool:
            rows = np.flatnonzero(rows)
        num = len(rows)
        r = self.num_robots
        starts = np.asarray(starts, dtype=np.float64).reshape(num * r, 2)
        goals = np.asarray(goals, dtype=np.float64).reshape(num * r, 2)
        self.goals[rows] = goals.reshape(num, r, 2)
        if num == 0:
            return
        paths, lengths = self._plan(starts, goals)
        self.plans.assign((rows,), paths, lengths)

    def _plan(self, starts: np.ndarray, goals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """graph.plan_batch, keeping straight joins `plan_clearance` off the walls when set."""
        if self.plan_clearance > 0:
            return self.graph.plan_batch(starts, goals, clearance=self.plan_clearance)
        return self.graph.plan_batch(starts, goals)

    def update(self, robot_pos: np.ndarray) -> np.ndarray:
        """Replan robots that strayed, then return every robot's carrot.

        Args:
            robot_pos: (B, R, 2) robot positions, world frame, m.

        Returns:
            (B, R, 2) carrot, world frame, m.
        """
        plans = self.plans
        options = (self.carrot_radius, self.max_skip, self.tolerance)
        target, dist = track(robot_pos, plans.paths, plans.lengths, *options, self.sight)
        stray = dist > self.replan_distance
        if stray.any():
            rows, robots = np.nonzero(stray)
            pos = robot_pos[rows, robots]
            try:
                paths, lengths = self._plan(pos, self.goals[rows, robots])
            except ValueError as err:  # NoPathError: keep the old plans, try again next step
                logger.debug("replanning %d robots failed: %s", len(rows), err)
            else:
                plans.assign((rows, robots), paths, lengths)
                new = track(
                    pos, plans.paths[rows, robots], plans.lengths[rows, robots], *options, self.sight
                )[0]
                target[rows, robots] = new
        return target
