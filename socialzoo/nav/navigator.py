"""Global-plan tracking for a batch of robots: distance to the plan, replanning, the carrot (SPEC section 6)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.core.validation import check_fields, check_int, check_number
from socialzoo.nav.distance_field import DistanceField, field_distance
from socialzoo.nav.recovery import RecoveryConfig, RecoveryState

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
        tolerance: how much closer than that a sight line may pass, m. 0 by default: the local
            planner drives only arcs that keep its wall distance (less an escape slack only for a
            robot already inside it), so a carrot "in sight" along a line closer than that drew
            the robot across a door jamb it could not pass, and it wedged beside a 0.8 m door
            turning to and fro (0.02, the field's lookup error, until env v2).
        step: spacing of the carrot candidates along the path, m.
        spacing: spacing of the field samples along a sight line, m.
        min_ahead: the carrot is never pulled back closer than this along the path to the
            robot's closest path point, m: where the path itself grazes a corner, the robot
            still has a target ahead and keeps its own wall distance as it goes round.
    """

    field: DistanceField
    clearance: float
    tolerance: float = 0.0
    step: float = 0.1
    spacing: float = 0.05
    min_ahead: float = 0.5

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("tolerance", "min_ahead"))


def track(
    pos: np.ndarray,
    paths: np.ndarray,
    lengths: np.ndarray,
    radius: float = CARROT_RADIUS,
    max_skip: int | None = None,
    tolerance: float = 0.0,
    sight: Sight | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The local target (the carrot), each point's distance to its path and the route length left,
    from one pass over the path segments.

    The carrot is where a circle around the robot leaves its path, going forward, as the reference
    navigation does: the goal itself when it lies inside the circle; else, from the path segment
    closest to the robot, walk forward to the first waypoint outside the circle and take the
    circle's crossing of the segment that reaches it (the crossing nearer that waypoint). A robot
    farther than `radius` from its whole path gets its closest path point.

    With `sight`, a carrot the robot cannot drive to in a straight line (see Sight) is pulled back
    along the path to the last point before the first one out of sight, going forward from the
    robot's closest path point: the carrot waits at a corner or before a doorway until the robot
    has come round, instead of pulling it into the wall corner that hides the path.

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
        sight: keeps the carrot in sight; None: the plain carrot.

    Returns:
        (carrot (..., 2) world frame m, distance (...,) m, route left (...,) m: from the robot to
        its closest path point, then along the path to its end).
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
    left = np.empty(len(pos))
    _route_left(pos, paths, lengths, where, left)
    return out.reshape(*shape, 2), dist.reshape(shape), left.reshape(shape)


@kernel
def _route_left(pos, paths, lengths, where, out):  # type: ignore[no-untyped-def]
    """Route length left of each row (M,): robot to its closest path point (where[:, :2]), then
    along the rest of the path, m."""
    for m in range(pos.shape[0]):
        seg, t = int(where[m, 0]), where[m, 1]
        ax, ay = paths[m, seg, 0], paths[m, seg, 1]
        bx, by = paths[m, seg + 1, 0], paths[m, seg + 1, 1]
        cx, cy = ax + t * (bx - ax), ay + t * (by - ay)
        total = math.sqrt((pos[m, 0] - cx) ** 2 + (pos[m, 1] - cy) ** 2)
        total += (1.0 - t) * math.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
        for s in range(seg + 1, lengths[m] - 1):
            total += math.sqrt(
                (paths[m, s + 1, 0] - paths[m, s, 0]) ** 2 + (paths[m, s + 1, 1] - paths[m, s, 1]) ** 2
            )
        out[m] = total


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
    """`track`'s carrot and distance for rows of pos (M, 2), paths (M, L >= 2, 2), lengths (M,); max_skip -1 is None.

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

    Recovery: a robot that drives its plan (the caller says which robots do, `update`'s
    `moving`) without progress for `recovery.after` seconds backs off for
    `recovery.backoff_time` (the caller drives it: socialzoo.nav.recovery.backoff_commands while
    `backing_off`), then replans; unless people stood around it, over another edge (the edge where it stopped is
    avoided for the rest of the episode: `socialzoo.nav.graph.NavGraph.plan_avoiding`). A robot
    wedged beside a door, in a crack of the plan, or pressed against a person gets out; the
    episode metric `stuck` counts the time it lost.

    SPEC section 6: replan when a robot is more than 0.5 m from its plan; the local target ("carrot")
    is the point where a 1.5 m circle around the robot leaves the path. With a Sight (as the envs
    use it) the carrot stays where the robot can drive to it in a straight line, and plans avoid
    straight joins that graze walls: on real floor plans the plain carrot, placed behind a door frame
    or corner, pinned the robot against it for the whole episode.

    Args:
        graph: plans paths (a socialzoo.nav.graph.NavGraph).
        batch_size: B.
        num_robots: R robots per batch row.
        carrot_radius: local-target circle radius, m.
        replan_distance: a robot farther than this from its plan gets a new one, m.
        max_skip: passed to `track`. The defaults (the carrot stops at the end of
            the closest segment, or at the first later waypoint at least radius / 2 away;
            near-equal closest segments resolve to the one furthest along) depart from the plain
            SPEC carrot (None and 0.0) for robustness: with them GoAlone (no humans) reaches the
            goal from all 650 ordered pairs of GDC1's legal poses; the plain carrot cuts through
            the wall between two doors of a U-turn and oscillates on paths that double back.
        tolerance: as `max_skip`.
        sight: keeps the carrot in sight (see `Sight`); None: the plain carrot.
        recovery: the recovery behaviour (socialzoo.nav.recovery); None: none.
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
        recovery: RecoveryConfig | None = None,
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
        # (B, R) route length left after the latest update, m (see `update`).
        self.route_left = np.zeros((batch_size, num_robots))
        self.recovery = recovery
        # The per-robot recovery bookkeeping (progress, back-offs, avoided edges), which a compacted
        # core carries over (socialzoo.env.compaction). Without a recovery config it stays idle:
        # nothing ever backs off or avoids an edge.
        self.recovery_state = RecoveryState(recovery or RecoveryConfig(), batch_size, num_robots)
        # (B, R) robots given a new route by a recovery in the latest update.
        self.rerouted = np.zeros((batch_size, num_robots), dtype=bool)

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
        self.recovery_state.reset(rows)
        if num == 0:
            return
        paths, lengths = self._plan(starts, goals)
        self.plans.assign((rows,), paths, lengths)

    def _plan(self, starts: np.ndarray, goals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """graph.plan_batch, keeping straight joins `plan_clearance` off the walls when set."""
        if self.plan_clearance > 0:
            return self.graph.plan_batch(starts, goals, clearance=self.plan_clearance)
        return self.graph.plan_batch(starts, goals)

    @property
    def backing_off(self) -> np.ndarray:
        """(B, R) bool: robots backing off (their commands: socialzoo.nav.recovery.backoff_commands)."""
        return self.recovery_state.backing_off

    def update(
        self,
        robot_pos: np.ndarray,
        moving: np.ndarray | None = None,
        dt: float = 0.0,
        human_pos: np.ndarray | None = None,
        human_mask: np.ndarray | None = None,
    ) -> np.ndarray:
        """Replan robots that strayed, recover robots that make no progress, return every carrot.

        Also sets `route_left` (B, R): each robot's distance to its plan plus the plan's length
        from the closest point on to the goal, m (what the episode metrics count progress on).

        Args:
            robot_pos: (B, R, 2) robot positions, world frame, m.
            moving: (B, R) bool, robots that drove their plan this step (GoAlone, not halted);
                None: no recovery bookkeeping this call (a reset).
            dt: the step, s.
            human_pos: (B, H, 2) human positions, world frame, m (who blocks a recovering robot).
            human_mask: (B, H) present humans.

        Returns:
            (B, R, 2) carrot, world frame, m.
        """
        self.rerouted = np.zeros(self.plans.lengths.shape, dtype=bool)
        if moving is not None and self.recovery is not None:
            self._recover(robot_pos, np.asarray(moving, dtype=bool), dt, human_pos, human_mask)
        plans = self.plans
        options = (self.carrot_radius, self.max_skip, self.tolerance)
        target, dist, left = track(robot_pos, plans.paths, plans.lengths, *options, self.sight)
        stray = dist > self.replan_distance
        if stray.any():
            rows, robots = np.nonzero(stray)
            pos = robot_pos[rows, robots]
            if self._replan(rows, robots, pos):
                new, _, new_left = track(
                    pos, plans.paths[rows, robots], plans.lengths[rows, robots], *options, self.sight
                )
                target[rows, robots] = new
                left[rows, robots] = new_left
        self.route_left = left
        return target

    def _recover(
        self,
        robot_pos: np.ndarray,
        moving: np.ndarray,
        dt: float,
        human_pos: np.ndarray | None,
        human_mask: np.ndarray | None,
    ) -> None:
        """Recovery bookkeeping on the route left of the last update: a robot starting to back off
        away from people avoids the edge where it stopped; one whose back-off ended is replanned."""
        state = self.recovery_state
        started, ended = state.step(self.route_left, moving, dt)
        if started.any():
            rows, robots = np.nonzero(started)
            pos = robot_pos[rows, robots]
            crowd = state.in_crowd(
                pos,
                None if human_pos is None else human_pos[rows],
                None if human_mask is None else human_mask[rows],
            )
            nodes, edges = getattr(self.graph, "nodes", None), getattr(self.graph, "edges", None)
            if nodes is not None and edges is not None:
                for k in np.flatnonzero(~crowd).tolist():
                    state.avoid_edge_at(nodes, edges, int(rows[k]), int(robots[k]), pos[k])
        if ended.any():
            rows, robots = np.nonzero(ended)
            self._replan(rows, robots, robot_pos[rows, robots])
            self.rerouted[rows, robots] = True

    def _replan(self, rows: np.ndarray, robots: np.ndarray, pos: np.ndarray) -> bool:
        """New plans for robots at pos (M, 2) (avoiding their avoided edges, if any); False where
        none is found (NoPathError: the old plans are kept, tried again next step)."""
        try:
            paths, lengths = self._plan(pos, self.goals[rows, robots])
            paths, lengths = self._keep_avoiding(rows, robots, pos, paths, lengths)
        except ValueError as err:
            logger.debug("replanning %d robots failed: %s", len(rows), err)
            return False
        self.plans.assign((rows, robots), paths, lengths)
        return True

    def _keep_avoiding(
        self, rows: np.ndarray, robots: np.ndarray, pos: np.ndarray, paths: np.ndarray, lengths: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Plans (paths (M, L, 2), lengths (M,)) with those of robots that avoid edges replaced by
        plans around them (where the graph has one; else the avoided edges are forgotten)."""
        avoid = self.recovery_state.avoid
        avoiding = np.flatnonzero((avoid[rows, robots] >= 0).any(axis=1))
        plan_avoiding = getattr(self.graph, "plan_avoiding", None)
        if len(avoiding) == 0 or plan_avoiding is None:
            return paths, lengths
        found: dict[int, np.ndarray] = {}
        for k in avoiding.tolist():
            row, robot = int(rows[k]), int(robots[k])
            path = plan_avoiding(
                pos[k], self.goals[row, robot], avoid[row, robot], clearance=self.plan_clearance
            )
            if path is None:
                avoid[row, robot] = -1  # no way round: take the usual route again
            else:
                found[k] = path
        if not found:
            return paths, lengths
        width = max(paths.shape[1], *(len(p) for p in found.values()))
        paths = _pad_paths(paths, width).copy()
        lengths = np.array(lengths, copy=True)
        for k, path in found.items():
            paths[k] = _pad_paths(path[None], width)[0]
            lengths[k] = len(path)
        return paths, lengths
