"""Wall segments with a uniform-grid spatial index."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from socialzoo.core.geometry import (
    PARALLEL_EPS,
    closest_point_on_segment,
    segment_hits_box,
    segments_intersect,
    to_frame,
)
from socialzoo.core.jit import kernel

# Most cells a grid table may have: building one holds about 40 bytes a cell, so 25 M cells (a
# 1.25 km square at the default 25 cm) take about 1 GB. Walls spread wider are walls whose
# coordinates are not metres (a 10 m room drawn in millimetres spans 10 km) or a stray far-off wall.
MAX_TABLE_CELLS = 25_000_000


@dataclass(frozen=True)
class GridTable:
    """Candidate walls per grid cell, in compressed rows: every wall within `reach` of the cell.

    Attributes:
        cell_size: side of a square cell, metres.
        reach: a wall closer than this to any point of a cell is listed for that cell, metres.
        origin: world position of the grid's lower-left corner, shape (2,), metres.
        num_x, num_y: number of cells along x and y.
        cell_start: (num_x * num_y + 1,) offsets into cell_walls; cell c lists
            cell_walls[cell_start[c]:cell_start[c + 1]].
        cell_walls: (total,) wall indices.
        walls: (W, 4) the indexed wall segments.
    """

    cell_size: float
    reach: float
    origin: np.ndarray
    num_x: int
    num_y: int
    cell_start: np.ndarray
    cell_walls: np.ndarray
    walls: np.ndarray

    def cells(self, points: np.ndarray) -> np.ndarray:
        """Flat cell index of world points (..., 2); points outside the grid map to its border."""
        flat = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
        out = np.empty(len(flat), dtype=np.intp)
        _cells_all(flat, self.shape_args, out)
        return out.reshape(points.shape[:-1])

    @cached_property
    def shape_args(self) -> tuple[float, float, float, int, int, float]:
        """(origin x, origin y, 1 / cell_size, num_x, num_y, reach): the grid for `grid_cell`."""
        return (
            float(self.origin[0]),
            float(self.origin[1]),
            1.0 / self.cell_size,
            self.num_x,
            self.num_y,
            self.reach,
        )

    @cached_property
    def cell_count(self) -> np.ndarray:
        """(num_x * num_y,) number of candidate walls per cell."""
        return np.diff(self.cell_start)

    @cached_property
    def cell_clearance(self) -> np.ndarray:
        """(num_x * num_y,) a lower bound on the distance from any point of a cell to any wall, m.

        Cells with no candidate wall are at least `reach` away from every wall.
        """
        clearance = np.full(self.num_x * self.num_y, self.reach)
        cell_of = np.repeat(np.arange(self.num_x * self.num_y), self.cell_count)
        ix, iy = np.divmod(cell_of, self.num_y)
        centre = self.origin + (np.stack((ix, iy), axis=-1) + 0.5) * self.cell_size
        walls = self.walls
        _, dist = closest_point_on_segment(centre, walls[self.cell_walls, 0:2], walls[self.cell_walls, 2:4])
        np.minimum.at(clearance, cell_of, dist - self.cell_size * math.sqrt(0.5))
        return np.maximum(clearance, 0.0)

    @property
    def max_candidates(self) -> int:
        """The largest number of candidate walls in one cell."""
        return int(self.cell_count.max(initial=0))

    def candidates(self, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All (query, wall) candidate pairs for flat query cells (N,).

        Returns:
            (query, wall): int arrays (M,), grouped by query in increasing order.
        """
        counts = self.cell_count.take(cells)
        query = np.repeat(np.arange(len(cells)), counts)
        # Position of each pair in cell_walls: its cell's start plus its rank within the group.
        shift = np.repeat(self.cell_start.take(cells) - (np.cumsum(counts) - counts), counts)
        return query, self.cell_walls.take(np.arange(len(query)) + shift)


def build_grid_table(walls: np.ndarray, cell_size: float, reach: float) -> GridTable:
    """Index walls (W, 4) on a grid whose cells list every wall within `reach` of them.

    Raises:
        ValueError: a non-positive cell size or reach, or walls spread so wide that the grid would
            have more than MAX_TABLE_CELLS cells (naming their extent, before any memory is taken).
    """
    if cell_size <= 0 or reach <= 0:
        raise ValueError(f"cell_size and reach must be positive, got {cell_size}, {reach}")
    a, b = walls[:, 0:2], walls[:, 2:4]
    if len(walls):
        wall_lo, wall_hi = np.minimum(a, b).min(axis=0), np.maximum(a, b).max(axis=0)
        lo, hi = wall_lo - reach - cell_size, wall_hi + reach + cell_size
    else:
        lo, hi = np.zeros(2), np.full(2, cell_size)
    num_x = max(1, math.ceil((hi[0] - lo[0]) / cell_size))
    num_y = max(1, math.ceil((hi[1] - lo[1]) / cell_size))
    if num_x * num_y > MAX_TABLE_CELLS:
        (x0, y0), (x1, y1) = wall_lo, wall_hi
        raise ValueError(
            f"the walls span {x1 - x0:.6g} x {y1 - y0:.6g} m (from ({x0:.6g}, {y0:.6g}) to ({x1:.6g}, "
            f"{y1:.6g})): their {100 * cell_size:g} cm wall grid would have {num_x * num_y:.3g} cells, "
            f"more than the {MAX_TABLE_CELLS:,} it may have; check that the coordinates are metres "
            "(a plan in millimetres is 1000 times too large) or remove a stray far-off wall"
        )
    half_diag = cell_size * math.sqrt(0.5)
    cell_ids: list[np.ndarray] = []
    wall_ids: list[np.ndarray] = []
    # Build time only: one pass per wall over the cells of its expanded bounding box.
    for w in range(len(walls)):
        ix0, iy0 = np.floor((np.minimum(a[w], b[w]) - reach - lo) / cell_size).astype(int)
        ix1, iy1 = np.floor((np.maximum(a[w], b[w]) + reach - lo) / cell_size).astype(int)
        gx, gy = np.meshgrid(
            np.arange(max(ix0, 0), min(ix1, num_x - 1) + 1),
            np.arange(max(iy0, 0), min(iy1, num_y - 1) + 1),
            indexing="ij",
        )
        centres = lo + (np.stack((gx, gy), axis=-1) + 0.5) * cell_size
        _, dist = closest_point_on_segment(centres, a[w], b[w])
        flat = (gx * num_y + gy)[dist <= reach + half_diag]
        cell_ids.append(flat)
        wall_ids.append(np.full(len(flat), w))
    cell_of = np.concatenate(cell_ids) if cell_ids else np.zeros(0, dtype=np.intp)
    wall_of = np.concatenate(wall_ids) if wall_ids else np.zeros(0, dtype=np.intp)
    order = np.lexsort((wall_of, cell_of))
    counts = np.bincount(cell_of, minlength=num_x * num_y)
    cell_start = np.concatenate(([0], np.cumsum(counts))).astype(np.intp)
    return GridTable(
        cell_size=cell_size,
        reach=reach,
        origin=lo,
        num_x=num_x,
        num_y=num_y,
        cell_start=cell_start,
        cell_walls=wall_of[order].astype(np.intp),
        walls=walls,
    )


def prune_to_nearest(table: GridTable) -> GridTable:
    """The table with, per cell, only the walls that can be nearest to some point of the cell.

    A wall can be nearest to a point of the cell only if its distance to the cell's centre,
    less half the cell diagonal (a lower bound on its distance to any point of the cell), is at
    most the smallest over listed walls of their farthest distance to the cell (reached at one
    of its corners, distance to a segment being convex). The answers of nearest-wall queries
    are unchanged; the number of candidate pairs drops to a few per cell.
    """
    cell_of = np.repeat(np.arange(table.num_x * table.num_y), table.cell_count)
    ix, iy = np.divmod(cell_of, table.num_y)
    lower = table.origin + np.stack((ix, iy), axis=-1) * table.cell_size
    a, b = table.walls[table.cell_walls, 0:2], table.walls[table.cell_walls, 2:4]
    half = 0.5 * table.cell_size
    centre_dist = closest_point_on_segment(lower + half, a, b)[1]
    farthest = np.zeros(len(cell_of))
    for corner in ((0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)):
        point = lower + np.array(corner) * table.cell_size
        farthest = np.maximum(farthest, closest_point_on_segment(point, a, b)[1])
    bound = np.full(table.num_x * table.num_y, np.inf)
    np.minimum.at(bound, cell_of, farthest)
    keep = centre_dist - half * math.sqrt(2.0) <= bound[cell_of] + 1e-9
    counts = np.bincount(cell_of[keep], minlength=table.num_x * table.num_y)
    return GridTable(
        cell_size=table.cell_size,
        reach=table.reach,
        origin=table.origin,
        num_x=table.num_x,
        num_y=table.num_y,
        cell_start=np.concatenate(([0], np.cumsum(counts))).astype(np.intp),
        cell_walls=table.cell_walls[keep],
        walls=table.walls,
    )


@kernel
def grid_cell(px: float, py: float, grid: tuple[float, float, float, int, int, float]) -> int:
    """Flat cell index of one point (GridTable.cells); grid is GridTable.shape_args.

    Coordinates are truncated to cells, then clamped: points outside the grid map to its border.
    """
    ox, oy, inv_cell, num_x, num_y, _ = grid
    ix = min(max(int((px - ox) * inv_cell), 0), num_x - 1)
    iy = min(max(int((py - oy) * inv_cell), 0), num_y - 1)
    return ix * num_y + iy


@kernel
def _cells_all(points, grid, out):  # type: ignore[no-untyped-def]
    """grid_cell of every row of points (N, 2) into out (N,)."""
    for k in range(points.shape[0]):
        out[k] = grid_cell(points[k, 0], points[k, 1], grid)


@kernel
def _nearest_on_grid(points, grid, cell_start, cell_walls, segments, closest, dist):
    """Fill closest (N, 2) and dist (N,) with each point's nearest listed wall point.

    grid: GridTable.shape_args. Points with no wall within reach get dist inf and themselves as
    closest point. The first of equally near walls wins.
    """
    reach = grid[5]
    for q in range(points.shape[0]):
        px, py = points[q, 0], points[q, 1]
        cell = grid_cell(px, py, grid)
        best, bx, by = np.inf, px, py
        for k in range(cell_start[cell], cell_start[cell + 1]):
            ax, ay, abx, aby, inv_len2 = segments[cell_walls[k]]
            frac = min(max(((px - ax) * abx + (py - ay) * aby) * inv_len2, 0.0), 1.0)
            cx = ax + frac * abx
            cy = ay + frac * aby
            d = math.sqrt((px - cx) ** 2 + (py - cy) ** 2)
            if d < best:
                best, bx, by = d, cx, cy
        if best > reach:
            best, bx, by = np.inf, px, py
        closest[q, 0] = bx
        closest[q, 1] = by
        dist[q] = best


class WallIndex:
    """Wall segments of one map and the grid tables that answer geometric queries on them.

    Queries gather (query, candidate wall) pairs from the grid and work on those pairs only, so
    their cost follows the number of walls actually near each query.

    Args:
        walls: wall segments, shape (W, 4) as (x1, y1, x2, y2), world frame, metres.
        cell_size: grid cell side for the fine table, metres.
        reach: how far the fine table looks around a cell, metres; nearest-wall answers are exact
            up to this distance, and footprints must fit inside it.
    """

    def __init__(self, walls: np.ndarray, cell_size: float = 0.25, reach: float = 1.0) -> None:
        walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
        if not np.all(np.isfinite(walls)):
            raise ValueError("walls contain NaN or infinite coordinates")
        self.walls = walls
        self.wall_a = walls[:, 0:2].copy()
        self.wall_b = walls[:, 2:4].copy()
        ab = self.wall_b - self.wall_a
        len2 = (ab**2).sum(-1)
        # Zero-length walls act as points: their projection parameter is forced to 0.
        inv_len2 = np.where(len2 > 0.0, 1.0 / np.where(len2 > 0.0, len2, 1.0), 0.0)
        # (W, 5) rows (ax, ay, abx, aby, 1 / |ab|^2) for the compiled nearest-wall query.
        self._segments = np.column_stack((self.wall_a, ab, inv_len2))
        self.cell_size = cell_size
        self.reach = reach
        self._tables: dict[tuple[float, float], GridTable] = {}

    @property
    def num_walls(self) -> int:
        """W, the number of wall segments."""
        return len(self.walls)

    def table(self, cell_size: float | None = None, reach: float | None = None) -> GridTable:
        """The grid table for (cell_size, reach), built on first use and cached."""
        key = (cell_size or self.cell_size, reach or self.reach)
        if key not in self._tables:
            self._tables[key] = build_grid_table(self.walls, *key)
        return self._tables[key]

    @cached_property
    def fine(self) -> GridTable:
        """The grid table with the default cell size and reach, built once."""
        return self.table()

    @cached_property
    def nearest_candidates(self) -> GridTable:
        """The fine table pruned to the walls that can be nearest to a point of each cell."""
        return prune_to_nearest(self.fine)

    def nearest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nearest wall point to each point, within `reach`.

        Args:
            points: shape (..., 2), world frame.

        Returns:
            (closest, dist): closest wall point (..., 2) and its distance (...,); where no wall is
            within reach, dist is inf and closest is the query point itself.
        """
        t = self.nearest_candidates
        flat = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
        closest = np.empty_like(flat)
        dist = np.empty(len(flat))
        _nearest_on_grid(flat, t.shape_args, t.cell_start, t.cell_walls, self._segments, closest, dist)
        return closest.reshape(points.shape), dist.reshape(points.shape[:-1])

    def line_candidates(self, p0: np.ndarray, p1: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
        """Every wall that can touch each segment [p0, p1] (M, 2), as (segment, wall) pairs.

        A segment up to `reach` long is covered by its start; a longer one by sample points
        spaced at most `reach` apart. Each sample contributes its cell's candidates (every wall
        within reach of it), so any wall touching the segment is listed.

        Returns:
            (segment, wall, repeated): int arrays (P,), and whether a pair may be listed more
            than once (a segment longer than `reach` has several samples).
        """
        t = self.fine
        delta = p1 - p0
        length = np.sqrt(delta[:, 0] ** 2 + delta[:, 1] ** 2)
        num_samples = np.where(length <= t.reach, 1, np.ceil(length / t.reach).astype(np.intp) + 1)
        if len(p0) == 0 or num_samples.max() == 1:
            query, wall = t.candidates(t.cells(p0))
            return query, wall, False
        seg_of_sample = np.repeat(np.arange(len(p0)), num_samples)
        rank = np.arange(len(seg_of_sample)) - np.repeat(np.cumsum(num_samples) - num_samples, num_samples)
        frac = rank / np.maximum(num_samples - 1, 1).take(seg_of_sample)
        samples = p0.take(seg_of_sample, axis=0) + frac[:, None] * delta.take(seg_of_sample, axis=0)
        query, wall = t.candidates(t.cells(samples))
        return seg_of_sample.take(query), wall, True

    def crosses(self, p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
        """Whether segments [p0, p1] (..., 2) touch any wall; returns bool (...,).

        The candidates of `line_candidates` are tested; a (segment, wall) pair met at several
        samples is tested once.
        """
        shape = p0.shape[:-1]
        a0 = p0.reshape(-1, 2)
        a1 = p1.reshape(-1, 2)
        if len(a0) == 0:
            return np.zeros(shape, dtype=bool)
        seg, wall, repeated = self.line_candidates(a0, a1)
        if repeated:
            seg, wall = np.divmod(np.unique(seg * self.num_walls + wall), self.num_walls)
        hit = segments_intersect(
            a0.take(seg, axis=0), a1.take(seg, axis=0), self.wall_a[wall], self.wall_b[wall]
        )
        return (np.bincount(seg[hit], minlength=len(a0)) > 0).reshape(shape)

    def footprint_hits(self, pose: np.ndarray, half_length: float, half_width: float) -> np.ndarray:
        """Whether rectangular footprints centred at poses (..., 3) touch any wall; bool (...,)."""
        t = self.fine
        if math.hypot(half_length, half_width) > t.reach:
            raise ValueError(
                f"footprint half-diagonal {math.hypot(half_length, half_width):.3f} m exceeds the "
                f"wall index reach {t.reach} m"
            )
        flat = pose.reshape(-1, 3)
        result = np.zeros(len(flat), dtype=bool)
        # Only footprints in cells closer to a wall than their half-diagonal need the exact test.
        near = np.flatnonzero(
            t.cell_clearance.take(t.cells(flat[:, :2])) <= math.hypot(half_length, half_width)
        )
        if len(near):
            query, wall = t.candidates(t.cells(flat[near, :2]))
            a = to_frame(self.wall_a[wall], flat[near[query]])
            b = to_frame(self.wall_b[wall], flat[near[query]])
            hit = segment_hits_box(a, b, half_length, half_width)
            result[near] = np.bincount(query[hit], minlength=len(near)) > 0
        return result.reshape(pose.shape[:-1])

    def cast_rays(self, origins: np.ndarray, angles: np.ndarray, max_range: float) -> np.ndarray:
        """Range to the first wall along rays, capped at max_range.

        Args:
            origins: ray origins, shape (N, 2), world frame.
            angles: world-frame ray angles, shape (N, M), radians.
            max_range: metres.

        Returns:
            Ranges, shape (N, M), metres, in [0, max_range].
        """
        t = self.table(cell_size=max(self.cell_size, max_range / 4.0), reach=max_range)
        origins = np.ascontiguousarray(origins, dtype=np.float64)
        query, wall = t.candidates(t.cells(origins))
        direction = np.stack((np.cos(angles), np.sin(angles)), axis=-1)  # (N, M, 2)
        ranges = np.full(angles.shape, float(max_range))
        # Compiled pair by pair: a (pairs, M) array per temporary was GiBs for a building's
        # hundreds of walls within a 10 m range at B = 512.
        _lower_to_hits(origins, direction, query, wall, self.wall_a, self.wall_b, ranges)
        return ranges


@kernel
def _lower_to_hits(origins, direction, query, wall, wall_a, wall_b, ranges):  # type: ignore[no-untyped-def]
    """Lower ranges (N, M) to where each ray of origin query[p] (direction (N, M, 2)) hits wall[p],
    for every candidate pair p: socialzoo.core.geometry.ray_segment_hit's arithmetic, pair by pair.
    A tie takes the later pair, as np.minimum.at does (the sign of a zero range is kept)."""
    for p in range(query.shape[0]):
        q, w = query[p], wall[p]
        sx, sy = wall_b[w, 0] - wall_a[w, 0], wall_b[w, 1] - wall_a[w, 1]
        aox, aoy = wall_a[w, 0] - origins[q, 0], wall_a[w, 1] - origins[q, 1]
        for m in range(direction.shape[1]):
            dx, dy = direction[q, m, 0], direction[q, m, 1]
            denom = dx * sy - dy * sx
            if abs(denom) <= PARALLEL_EPS:
                continue
            t = (aox * sy - aoy * sx) / denom
            u = (aox * dy - aoy * dx) / denom
            if t >= 0.0 and u >= 0.0 and u <= 1.0 and t <= ranges[q, m]:
                ranges[q, m] = t
