"""The feasibility rule of scenario generation: which legal-pose pairs are a fair start and goal, and how many
people a map's floor holds."""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from socialzoo.maps.map_file import Map
from socialzoo.nav.graph import graph_of

# Share of the episode's time limit that a feasible route may take at cruise speed.
ROUTE_TIME_SHARE = 0.75
# The benchmark's time limit (SPEC section 2: 3200 steps of 25 ms) and GoAlone's cruise speed.
BENCHMARK_TIME_LIMIT = 80.0
CRUISE_SPEED = 1.5


# The longest feasible route, m: the share of the time limit at the cruise speed, 0.75 x 80 s x 1.5 m/s.
MAX_ROUTE_LENGTH = ROUTE_TIME_SHARE * BENCHMARK_TIME_LIMIT * CRUISE_SPEED
# GDC1's walkable floor (cells at least 0.39 m from walls, 5 cm grid, socialzoo.maps.roadmap) and
# the benchmark's largest crowd on it: the density the crowd keeps on other maps.
GDC1_WALKABLE_AREA = 1352.0
CROWD_DENSITY = 25 / GDC1_WALKABLE_AREA


def max_humans_for(m: Map, min_humans: int, max_humans: int) -> int:
    """The largest head count of a scenario on map m: max_humans, lowered on a map with a
    walkable_area to the benchmark's crowd density (rounded, at least min_humans).

    The SPEC's 5 to 25 humans walk GDC1's 1352 m^2 of floor, so a map with less floor gets at most
    proportionally fewer (never fewer than min_humans): 25 people in a 340 m^2 office floor would be
    another, much harder, task. The shipped maps carry no area and keep the SPEC's head count.
    """
    if m.walkable_area is None:
        return max_humans
    return int(min(max_humans, max(min_humans, round(m.walkable_area * CROWD_DENSITY))))


_LENGTHS: weakref.WeakKeyDictionary[Map, np.ndarray] = weakref.WeakKeyDictionary()


def route_lengths(m: Map) -> np.ndarray:
    """Planned route length between every two legal poses of a map, m (built once per map object).

    Returns:
        (P, P) float, read-only: entry (i, j) is the length of the route from pose i to pose j;
        0 on the diagonal, inf where no route exists (a pose that reaches no graph edge, or poses
        on parts of the graph that are not connected).
    """
    cached = _LENGTHS.get(m)
    if cached is not None:
        return cached
    poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)[:, :2]
    n = len(poses)
    lengths = np.zeros((n, n))
    if n > 1:
        first, second = np.nonzero(~np.eye(n, dtype=bool))
        paths, _, ok = graph_of(m).plan_batch_status(poses[first], poses[second])
        length = np.sqrt((np.diff(paths, axis=1) ** 2).sum(-1)).sum(-1)
        lengths[first, second] = np.where(ok, length, np.inf)
    lengths.setflags(write=False)
    _LENGTHS[m] = lengths
    return lengths


def feasible_pairs(m: Map, max_route_length: float = MAX_ROUTE_LENGTH) -> np.ndarray:
    """(P, P) bool: pose i to pose j (i != j) is a feasible route (at most max_route_length, m).

    A route's length is measured along the navigation graph as `NavGraph.plan_batch` plans it (a
    straight line where wall-free). By default max_route_length is 75% of the distance the robot
    covers in the episode's time limit at its cruise speed, 0.75 x 80 s x 1.5 m/s = 90 m; the other
    quarter of the time is left for turns, doorways and people. GDC1's and GHC3's longest
    pose-to-pose routes are 86.6 m, so on the paper's maps every pair is feasible.
    """
    lengths = route_lengths(m)
    ok = lengths <= max_route_length
    np.fill_diagonal(ok, False)
    return ok


@dataclass(frozen=True)
class RouteStats:
    """Route statistics over the ordered pairs of distinct legal poses of a map.

    Attributes:
        num_pairs: ordered pairs of distinct poses.
        num_feasible: pairs whose route is at most max_route_length.
        num_unreachable: pairs with no route at all.
        max_route_length: the rule's limit, m.
        shortest, median, longest: route lengths over the reachable pairs, m (nan if none).
        stranded: indices of poses with no feasible route to any other pose.
    """

    num_pairs: int
    num_feasible: int
    num_unreachable: int
    max_route_length: float
    shortest: float
    median: float
    longest: float
    stranded: tuple[int, ...]

    @property
    def feasible_share(self) -> float:
        """Share of pairs that are feasible (0 for a map with fewer than two poses)."""
        return self.num_feasible / self.num_pairs if self.num_pairs else 0.0


def route_stats(m: Map, max_route_length: float = MAX_ROUTE_LENGTH) -> RouteStats:
    """Feasible-route statistics of a map's legal poses (see RouteStats)."""
    lengths = route_lengths(m)
    n = len(lengths)
    off = ~np.eye(n, dtype=bool)
    values = lengths[off]
    reachable = values[np.isfinite(values)]
    ok = feasible_pairs(m, max_route_length)
    stranded = tuple(int(i) for i in np.flatnonzero(~(ok.any(axis=1) | ok.any(axis=0))))
    return RouteStats(
        num_pairs=int(off.sum()),
        num_feasible=int(ok.sum()),
        num_unreachable=int((~np.isfinite(values)).sum()),
        max_route_length=float(max_route_length),
        shortest=float(reachable.min()) if len(reachable) else math.nan,
        median=float(np.median(reachable)) if len(reachable) else math.nan,
        longest=float(reachable.max()) if len(reachable) else math.nan,
        stranded=stranded,
    )


# Rejection rounds before an infeasible pair is replaced by a uniform pick among the feasible ones.
_REDRAWS = 256


def redraw_robot_pair(
    rng: np.random.Generator, feasible: np.ndarray, start: int, goal: int
) -> tuple[int, int]:
    """The robot's (start, goal) pose indices, drawn again (both) until the pair is feasible.

    Draws nothing when the first pair is feasible, so on maps where every pair is (GDC1, GHC3)
    the generator's stream is the same as without the rule.
    """
    num_poses = len(feasible)
    for _ in range(_REDRAWS):
        if feasible[start, goal]:
            return start, goal
        start = int(rng.integers(num_poses))
        goal = int(rng.integers(num_poses - 1))
        goal += goal >= start
    pairs = np.argwhere(feasible)
    start, goal = (int(v) for v in pairs[int(rng.integers(len(pairs)))])
    return start, goal


def redraw_human_pairs(
    rng: np.random.Generator,
    feasible: np.ndarray,
    robot_start: int,
    start: np.ndarray,
    goal: np.ndarray,
    where: str,
) -> None:
    """Draw the infeasible human (start, goal) pairs again, in place, as they were drawn.

    Re-draws consume the generator in row order and only for infeasible rows (none on GDC1 and
    GHC3). Starts stay off the robot's start and goals off their own start.

    Raises:
        ValueError: no feasible pair starts anywhere but at the robot's start.
    """
    num_poses = len(feasible)
    bad = ~feasible[start, goal]
    for _ in range(_REDRAWS):
        rows = np.flatnonzero(bad)
        if len(rows) == 0:
            return
        s = rng.integers(num_poses - 1, size=len(rows))
        s += s >= robot_start
        g = rng.integers(num_poses - 1, size=len(rows))
        g += g >= s
        start[rows], goal[rows] = s, g
        bad[rows] = ~feasible[s, g]
    pairs = np.argwhere(feasible)
    pairs = pairs[pairs[:, 0] != robot_start]
    if len(pairs) == 0:
        raise ValueError(f"{where}: no feasible human route starts away from the robot's start pose")
    rows = np.flatnonzero(bad)
    pick = pairs[rng.integers(len(pairs), size=len(rows))]
    start[rows], goal[rows] = pick[:, 0], pick[:, 1]
