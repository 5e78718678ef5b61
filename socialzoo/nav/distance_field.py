"""A map's wall distance field: distance to the nearest wall on a fine grid, one byte per cell."""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.core.walls import WallIndex


@dataclass(frozen=True)
class DistanceField:
    """The distance to the nearest wall, sampled at the centres of a square grid's cells.

    A lookup returns the value of the cell containing the point, so it is within half a cell
    diagonal (plus one quantum, rounding down) of the true distance. Distances are stored as uint8
    codes of `quantum` metres, so a lookup is a one-byte gather and the table stays small in cache.

    Attributes:
        origin: world position of the grid's lower-left corner, (2,), m.
        resolution: cell side, m.
        num_x, num_y: cells along x and y.
        max_range: distances are capped here, m; points off the grid read max_range.
        quantum: metres per code unit.
        codes: (num_x * num_y,) uint8, flat index ix * num_y + iy: the distance from the cell's
            centre to the nearest wall in quanta, rounded down.
    """

    origin: np.ndarray
    resolution: float
    num_x: int
    num_y: int
    max_range: float
    quantum: float
    codes: np.ndarray

    def lookup(self, points: np.ndarray) -> np.ndarray:
        """Wall distance of world points (..., 2) to within half a cell diagonal; (...,) m."""
        flat = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
        out = np.empty(len(flat))
        _lookup_all(flat, self.shape_args, self.codes, out)
        return out.reshape(points.shape[:-1])

    @cached_property
    def shape_args(self) -> tuple[float, float, float, int, int, float]:
        """(origin x, origin y, resolution, num_x, num_y, quantum): the grid for `field_distance`."""
        return (
            float(self.origin[0]), float(self.origin[1]), self.resolution, self.num_x, self.num_y, self.quantum,
        )  # fmt: skip


@kernel
def field_distance(px: float, py: float, shape: tuple[float, float, float, int, int, float], codes) -> float:  # type: ignore[no-untyped-def]
    """DistanceField.lookup for one point, in a kernel; shape is DistanceField.shape_args."""
    ox, oy, resolution, num_x, num_y, quantum = shape
    ix = min(max(math.floor((px - ox) / resolution), 0), num_x - 1)
    iy = min(max(math.floor((py - oy) / resolution), 0), num_y - 1)
    return codes[ix * num_y + iy] * quantum


@kernel
def _lookup_all(points, shape, codes, out):  # type: ignore[no-untyped-def]
    """field_distance of every row of points (N, 2) into out (N,)."""
    for k in range(points.shape[0]):
        out[k] = field_distance(points[k, 0], points[k, 1], shape, codes)


def build_distance_field(
    walls: np.ndarray, resolution: float, max_range: float, pad: float = 0.0
) -> DistanceField:
    """Distance field of wall segments (W, 4), exact at cell centres, capped at max_range.

    The grid covers the walls' bounding box grown by max_range + pad and two cells, so every
    point off the grid is at least max_range from every wall, and points up to `pad` away from a
    point inside the walls' bounding box are on the grid.
    """
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    grow = max_range + pad + 2.0 * resolution
    if len(walls):
        lo = np.minimum(walls[:, 0:2], walls[:, 2:4]).min(axis=0) - grow
        hi = np.maximum(walls[:, 0:2], walls[:, 2:4]).max(axis=0) + grow
    else:
        lo, hi = np.full(2, -grow), np.full(2, grow)
    num_x = max(1, math.ceil((hi[0] - lo[0]) / resolution))
    num_y = max(1, math.ceil((hi[1] - lo[1]) / resolution))
    # Squared distances in float32 (the codes keep 250 levels): a block of cells per wall, its
    # bounding box grown by the range. Build time only, hence the loop over walls.
    grid = np.full((num_x, num_y), np.float32(max_range**2), dtype=np.float32)
    reach = max_range + resolution
    for a, b in zip(walls[:, 0:2], walls[:, 2:4], strict=True):
        i0 = np.maximum(np.floor((np.minimum(a, b) - reach - lo) / resolution).astype(int), 0)
        i1 = np.minimum(np.ceil((np.maximum(a, b) + reach - lo) / resolution).astype(int), (num_x, num_y))
        px = (lo[0] + (np.arange(i0[0], i1[0]) + 0.5) * resolution - a[0]).astype(np.float32)[:, None]
        py = (lo[1] + (np.arange(i0[1], i1[1]) + 0.5) * resolution - a[1]).astype(np.float32)[None, :]
        d = (b - a).astype(np.float32)
        len2 = float(d @ d)
        t = px * (d[0] / len2 if len2 > 0 else 0.0) + py * (d[1] / len2 if len2 > 0 else 0.0)
        np.clip(t, 0.0, 1.0, out=t)
        ex = px - t * d[0]
        ey = py - t * d[1]
        ex *= ex
        ey *= ey
        ex += ey
        block = grid[i0[0] : i1[0], i0[1] : i1[1]]
        np.minimum(block, ex, out=block)
    grid = np.sqrt(grid)
    quantum = max_range / 250.0
    codes = np.floor(np.clip(grid, 0.0, max_range) / quantum).astype(np.uint8)
    return DistanceField(
        origin=lo,
        resolution=resolution,
        num_x=num_x,
        num_y=num_y,
        max_range=max_range,
        quantum=quantum,
        codes=codes.reshape(-1),
    )


_LAST_FIELD: dict[str, tuple[weakref.ref[WallIndex], tuple[float, float, float], DistanceField]] = {}
_FIELDS: weakref.WeakKeyDictionary[WallIndex, dict[tuple[float, float, float], DistanceField]] = (
    weakref.WeakKeyDictionary()
)


def distance_field(walls: WallIndex, resolution: float, max_range: float, pad: float = 0.0) -> DistanceField:
    """The distance field of a wall index, built on first use and cached with the index."""
    last = _LAST_FIELD.get("entry")
    if last is not None and last[0]() is walls and last[1] == (resolution, max_range, pad):
        return last[2]  # the common case, every step: skip the weak-dictionary lookups
    per_index = _FIELDS.setdefault(walls, {})
    key = (float(resolution), float(max_range), float(pad))
    field = per_index.get(key)
    if field is None:
        field = per_index[key] = build_distance_field(walls.walls, resolution, max_range, pad)
    _LAST_FIELD["entry"] = (weakref.ref(walls), (resolution, max_range, pad), field)
    return field
