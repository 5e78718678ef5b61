"""Wall tests of straight segments: whether lines between points touch a wall, or keep a clearance from every wall."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from socialzoo.core.walls import WallIndex


def _length_groups(walls: WallIndex, p0: np.ndarray, p1: np.ndarray) -> Iterator[np.ndarray]:
    """Row indices of the segments grouped by length (powers of two of the index's reach).

    `WallIndex.crosses` and `segment_clearance` sample every segment of a call as finely as its
    longest one needs, so grouping keeps the short segments cheap.
    """
    length = np.sqrt(((p1 - p0) ** 2).sum(-1))
    group = np.ceil(np.log2(np.maximum(length / walls.fine.reach, 1.0))).astype(np.intp)
    for g in np.unique(group):
        yield np.flatnonzero(group == g)


def _points(p: np.ndarray) -> np.ndarray:
    return np.asarray(p, dtype=np.float64).reshape(-1, 2)


def segments_free(walls: WallIndex | None, p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """Whether straight segments [p0, p1] (N, 2) touch no wall; bool (N,)."""
    p0, p1 = _points(p0), _points(p1)
    free = np.ones(len(p0), dtype=bool)
    if walls is None or walls.num_walls == 0 or len(p0) == 0:
        return free
    for rows in _length_groups(walls, p0, p1):
        free[rows] = ~walls.crosses(p0[rows], p1[rows])
    return free


def segments_clear_of(walls: WallIndex, p0: np.ndarray, p1: np.ndarray, need: np.ndarray) -> np.ndarray:
    """Whether straight segments [p0, p1] (N, 2) keep need (N,) (m, at most 0.5) from every wall;
    bool (N,)."""
    from socialzoo.maps.map_file import segment_clearance

    p0, p1 = _points(p0), _points(p1)
    ok = np.ones(len(p0), dtype=bool)
    if len(p0) == 0:
        return ok
    for rows in _length_groups(walls, p0, p1):
        ok[rows] = segment_clearance(walls, p0[rows], p1[rows])[0] >= need[rows]
    return ok


def segments_clear(walls: WallIndex | None, p0: np.ndarray, p1: np.ndarray, clearance: float) -> np.ndarray:
    """Whether straight segments [p0, p1] (N, 2) keep `clearance` (m, at most 0.5) from every wall;
    bool (N,)."""
    from socialzoo.maps.map_file import segment_clearance

    p0 = _points(p0)
    if walls is None or walls.num_walls == 0 or len(p0) == 0:
        return np.ones(len(p0), dtype=bool)
    return np.asarray(segment_clearance(walls, p0, p1)[0] >= clearance)
