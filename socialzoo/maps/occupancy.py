"""Walls from an occupancy grid (a floor-plan image: dark pixels are walls), as wall segments."""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

# Unit steps of the outline along pixel edges: +x, +y, -x, -y.
_STEPS = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]], dtype=np.int64)


def wall_pixels(image: np.ndarray, threshold: float = 0.5) -> np.ndarray:
    """Wall mask (rows, cols) of an image: pixels darker than `threshold` (0 black, 1 white).

    Args:
        image: (rows, cols) grey, or (rows, cols, 3 or 4) RGB(A), integer (0..max of the dtype) or
            float in [0, 1]; fully transparent pixels count as free.
        threshold: in (0, 1).

    Raises:
        ValueError: an image of another shape, or a threshold outside (0, 1).
    """
    if not 0.0 < threshold < 1.0:
        raise ValueError(f"threshold must be in (0, 1), got {threshold!r}")
    a = np.asarray(image)
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (1, 2, 3, 4)) or a.size == 0:
        raise ValueError(f"expected a grey or RGB(A) image (rows, cols[, channels]), got shape {a.shape}")
    scale = float(np.iinfo(a.dtype).max) if np.issubdtype(a.dtype, np.integer) else 1.0
    v = a.astype(np.float64) / scale
    alpha = None
    if v.ndim == 3:
        if v.shape[2] in (2, 4):
            alpha = v[..., -1]
            v = v[..., :-1]
        v = v.mean(axis=2) if v.shape[2] == 1 else v @ np.array([0.299, 0.587, 0.114])[: v.shape[2]]
    wall = v < threshold
    if alpha is not None:
        wall &= alpha > 0.0
    return wall


def _outline_edges(wall: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Directed unit edges around wall cells, wall on the left: (start corners (K, 2), step (K,)).

    wall is indexed [i, j] with i along x and j along y; corner (i, j) is the cell's lower-left.
    """
    padded = np.pad(wall, 1)
    core = padded[1:-1, 1:-1]
    starts, steps = [], []
    # (neighbour offset, start corner offset, step) of each side of a cell, counter-clockwise.
    for (di, dj), (ci, cj), step in (
        ((0, -1), (0, 0), 0),  # bottom side, left to right
        ((1, 0), (1, 0), 1),  # right side, upwards
        ((0, 1), (1, 1), 2),  # top side, right to left
        ((-1, 0), (0, 1), 3),  # left side, downwards
    ):
        free = ~padded[1 + di : padded.shape[0] - 1 + di, 1 + dj : padded.shape[1] - 1 + dj]
        cells = np.argwhere(core & free)
        starts.append(cells + np.array([ci, cj]))
        steps.append(np.full(len(cells), step, dtype=np.int64))
    return np.concatenate(starts), np.concatenate(steps)


def _loops(starts: np.ndarray, steps: np.ndarray, width: int) -> list[np.ndarray]:
    """Closed corner loops (L, 2) chaining the directed edges; at a corner with two ways out (two
    wall cells touching diagonally) the outline turns left, staying round the cell it follows."""
    ends = starts + _STEPS[steps]
    key = starts[:, 0] * (width + 2) + starts[:, 1]
    end_key = ends[:, 0] * (width + 2) + ends[:, 1]
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    first = np.searchsorted(sorted_key, end_key, side="left")
    last = np.searchsorted(sorted_key, end_key, side="right")
    nxt = order[np.minimum(first, len(order) - 1)]
    two = np.flatnonzero(last - first == 2)
    if len(two):
        a, b = order[first[two]], order[first[two] + 1]
        # The left turn: step (s + 1) % 4 after step s.
        left = (steps[two] + 1) % 4
        nxt[two] = np.where(steps[a] == left, a, b)
    seen = np.zeros(len(starts), dtype=bool)
    loops = []
    for k0 in range(len(starts)):
        if seen[k0]:
            continue
        chain = []
        k = k0
        while not seen[k]:
            seen[k] = True
            chain.append(k)
            k = int(nxt[k])
        loops.append(starts[np.array(chain)])
    return loops


def _corners(loop: np.ndarray) -> np.ndarray:
    """The loop's points where its direction changes (a closed polygon, first point not repeated)."""
    prev = np.roll(loop, 1, axis=0)
    nxt = np.roll(loop, -1, axis=0)
    d0, d1 = loop - prev, nxt - loop
    turn = (d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0]) != 0
    return loop[turn]


def _douglas_peucker(points: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices of the points of an open polyline (L, 2) kept within `tolerance` of it."""
    keep = np.zeros(len(points), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(points) - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        a, b = points[i], points[j]
        d = b - a
        norm = math.hypot(d[0], d[1])
        rel = points[i + 1 : j] - a
        if norm > 0:
            dist = np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0]) / norm
        else:
            dist = np.hypot(rel[:, 0], rel[:, 1])
        k = int(np.argmax(dist))
        if dist[k] > tolerance:
            keep[i + 1 + k] = True
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return np.flatnonzero(keep)


def _simplify_loop(corners: np.ndarray, tolerance: float) -> np.ndarray:
    """A closed polygon (L, 2) simplified by Douglas-Peucker, split at its two farthest points."""
    if len(corners) <= 4:
        return corners
    far = int(np.argmax(((corners - corners[0]) ** 2).sum(-1)))
    first = corners[: far + 1]
    second = np.concatenate((corners[far:], corners[:1]))
    a = first[_douglas_peucker(first, tolerance)]
    b = second[_douglas_peucker(second, tolerance)]
    return np.concatenate((a, b[1:-1]))


def walls_from_occupancy(
    wall: np.ndarray,
    scale: float,
    origin: tuple[float, float] = (0.0, 0.0),
    tolerance: float = 0.75,
    min_area: float = 0.0,
) -> np.ndarray:
    """Wall segments tracing the outlines of the wall pixels of a floor-plan image.

    The outline of every wall region is traced along the pixel edges (wall on the left, so each
    region's outline is a closed loop), straight runs are merged and staircases are simplified by
    Douglas-Peucker within `tolerance` pixels; each simplified loop becomes wall segments. Pixels are
    `scale` metres square; image row 0 is the top, so y grows upwards from the bottom row.

    Args:
        wall: (rows, cols) bool, True for wall pixels; row 0 is the top of the image.
        scale: metres per pixel.
        origin: world position of the image's lower-left corner, m.
        tolerance: simplification tolerance, pixels (staircases within it become one line).
        min_area: wall regions smaller than this are dropped (specks, text), m^2.

    Returns:
        (W, 4) segments x1, y1, x2, y2, m.

    Raises:
        ValueError: a scale that is not a positive number, or a mask that is not 2-D.
    """
    if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be a positive number of metres per pixel, got {scale!r}")
    mask = np.asarray(wall, dtype=bool)
    if mask.ndim != 2:
        raise ValueError(f"wall mask must be 2-D (rows, cols), got shape {mask.shape}")
    grid = mask[::-1].T  # [i along x, j along y]
    if min_area > 0 and grid.any():
        labels, count = ndimage.label(grid)
        sizes = np.bincount(labels.ravel(), minlength=count + 1) * scale * scale
        grid = grid & (sizes[labels] >= min_area) & (labels > 0)
    if not grid.any():
        return np.zeros((0, 4))
    starts, steps = _outline_edges(grid)
    segments = []
    for loop in _loops(starts, steps, grid.shape[1]):
        poly = _simplify_loop(_corners(loop).astype(np.float64), tolerance)
        if len(poly) < 2:
            continue
        ends = np.roll(poly, -1, axis=0)
        segments.append(np.concatenate((poly, ends), axis=1))
    out = np.concatenate(segments) * scale
    out += np.array([origin[0], origin[1], origin[0], origin[1]], dtype=np.float64)
    return out[(out[:, 0] != out[:, 2]) | (out[:, 1] != out[:, 3])]
