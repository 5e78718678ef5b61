"""Where the suite's families place people and the robot: distances and points along a route, spots drawn clear of
the walls and of each other, and how late the robot arrives against its nominal timing."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from socialzoo.maps.map_file import Map

# GoAlone arrives about this much later than route length / cruise speed, s: it accelerates (0.2 s
# on a straight run from rest) and slows in turns.
ROBOT_LAG = 0.4
# Clearance from walls of every spot a family draws, m (a legal pose needs 0.35).
SPOT_CLEARANCE = 0.4


def clear_of_walls(m: Map, points: np.ndarray, clearance: float = SPOT_CLEARANCE) -> np.ndarray:
    """(n,) whether each of the (n, 2) points is at least `clearance` from every wall."""
    if not m.num_walls:
        return np.ones(len(points), dtype=bool)
    _, dist = m.wall_index.nearest(np.asarray(points, dtype=np.float64).reshape(-1, 2))
    return np.asarray(dist >= clearance)


def arc_lengths(path: np.ndarray) -> np.ndarray:
    """(k,) the distance along the (k, 2) path to each of its points, m."""
    return np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))))


def point_at(path: np.ndarray, s: float) -> tuple[np.ndarray, np.ndarray]:
    """(point, unit direction) at distance s along the path (clipped to its ends)."""
    arc = arc_lengths(path)
    if len(path) < 2 or arc[-1] <= 0.0:
        return path[0].copy(), np.array([1.0, 0.0])
    s = float(np.clip(s, 0.0, arc[-1]))
    k = int(np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(path) - 2))
    while arc[k + 1] <= arc[k] and k + 2 < len(path):  # skip repeated points
        k += 1
    leg = path[k + 1] - path[k]
    length = max(float(np.linalg.norm(leg)), 1e-9)
    return path[k] + leg * min((s - arc[k]) / length, 1.0), leg / length


def draw_spots(
    m: Map,
    rng: np.random.Generator,
    n: int,
    draw: Callable[[], np.ndarray],
    avoid: np.ndarray,
    gap: float,
    box: tuple[np.ndarray, np.ndarray] | None = None,
    tries: int = 50,
) -> np.ndarray:
    """Up to n points from draw() (one (2,) point a call), each clear of the walls, inside the box
    (lo, hi) if one is given, and at least `gap` from the `avoid` points and from each other; a
    point whose tries run out is left out, so fewer may come back."""
    spots: list[np.ndarray] = []
    taken = np.asarray(avoid, dtype=np.float64).reshape(-1, 2)
    for _ in range(n):
        for _ in range(tries):
            p = np.asarray(draw(), dtype=np.float64)
            far = not len(taken) or float(np.min(np.linalg.norm(taken - p, axis=1))) >= gap
            inside = box is None or bool(np.all((p >= box[0]) & (p <= box[1])))
            if far and inside and clear_of_walls(m, p[None])[0]:
                spots.append(p)
                taken = np.vstack((taken, p))
                break
    return np.array(spots, dtype=np.float64).reshape(-1, 2)
