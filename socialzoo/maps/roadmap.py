"""Navigation graphs for wall maps that come without them: the free space, its roadmap and the walking paths
that join and repair graphs (scipy's ndimage and sparse.csgraph)."""

from __future__ import annotations

import itertools
import logging
import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse import csgraph

from socialzoo.core.geometry import wall_distances
from socialzoo.core.validation import check_fields, check_int, check_number
from socialzoo.core.walls import WallIndex
from socialzoo.maps.map_file import (
    NODE_CLEARANCE,
    POSE_CLEARANCE,
    graph_components,
    segment_clearance,
)

logger = logging.getLogger(__name__)

Box = tuple[float, float, float, float]

# 8-neighbourhood steps on the grid (cells) used for geodesic distances.
GRID_STEPS = ((1, 0), (0, 1), (1, 1), (1, -1))
# Wider closing radii tried, in order, where the usual one finds no enclosed room (an outline
# drawn with wide gaps: doorways to space the plan does not map), m.
CLOSING_RADII = (2.0, 2.5, 3.0, 4.0, 5.0)
# Most cells a free-space grid may have: an import holds about 70 bytes a cell at its peak, so
# 100 M cells (a 500 m square at 5 cm) take about 7 GB; a larger grid would exhaust the memory
# (the pedsim airport scene, 854 x 894 m, was killed by the kernel without a word).
MAX_GRID_CELLS = 100_000_000


@dataclass(frozen=True, kw_only=True)
class RoadmapConfig:
    """How a roadmap and its legal poses are built; lengths in metres.

    Attributes:
        resolution: grid cell side (5 cm: fine enough that every door of 0.88 m or more keeps
            a passable cell on its centre line; at 10 cm a door under 0.98 m may close).
        margin: free border around the walls' bounding box when no region is given.
        free_clearance: a cell is passable with at least this clearance: the local planner's
            wall distance (0.37 m) and its distance field's lookup error (0.02 m), so that no
            route leads through a gap the robot cannot drive through (doors under 0.78 m are
            closed; 0.9 m doors stay open).
        closing_radius: openings in the outer walls narrower than twice this count as closed when
            telling the inside of a building from the outside.
        node_clearance: least clearance of a generated node.
        min_spacing, max_spacing: generated nodes keep at least spacing_per_clearance times their
            clearance, clipped to [min_spacing, max_spacing], walking distance from each other.
        spacing_per_clearance: see above.
        edge_clearance: least distance between an edge and any wall (at most 0.5 m; above the
            local planner's 0.37 m wall distance, so the robot can follow its edges).
        keep_clearance: paths that join components are straightened only where the straight
            line keeps the walking path's own wall distance, up to this (minus 5 cm): through
            the middle of doorways, off the corners (socialzoo.maps.roadmap.pull_string); 0 lets
            them pass as close as edge_clearance allows.
        max_edge_length: longest edge considered.
        detour_tolerance: an edge i-j is dropped when some node k gives a path i-k-j at most this
            many times longer.
        num_poses: legal poses wanted.
        pose_clearance: least clearance of a generated legal pose (a building with fewer than
            two such places gets poses down to free_clearance + resolution: tight spaces).
        join_clearance: a generated legal pose joins a graph node by a straight line at least
            this far from every wall, m: the robot can drive it (its wall distance 0.37 m and
            the field's lookup error); 0 accepts any wall-free line, as the shipped maps were
            built (a line through a crack between two wall segments left goals unreachable).
        pose_separation: generated poses keep at least this walking distance from each other.
        good_clearance: poses are preferred up to this clearance (room centres over corners).
    """

    resolution: float = 0.05
    margin: float = 2.0
    free_clearance: float = 0.39
    closing_radius: float = 1.5
    node_clearance: float = 0.45
    min_spacing: float = 1.5
    max_spacing: float = 5.0
    spacing_per_clearance: float = 3.0
    edge_clearance: float = 0.4
    keep_clearance: float = 0.45
    max_edge_length: float = 15.0
    detour_tolerance: float = 1.15
    num_poses: int = 25
    pose_clearance: float = 0.6
    join_clearance: float = 0.39
    pose_separation: float = 2.0
    good_clearance: float = 1.0

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("margin", "pose_separation", "keep_clearance", "join_clearance"))
        if self.min_spacing > self.max_spacing:
            raise ValueError(
                f"RoadmapConfig.min_spacing {self.min_spacing} exceeds max_spacing {self.max_spacing}"
            )
        check_number("RoadmapConfig", "edge_clearance", self.edge_clearance, high=0.5)
        check_number("RoadmapConfig", "keep_clearance", self.keep_clearance, low=0, high=0.5)
        check_number("RoadmapConfig", "join_clearance", self.join_clearance, low=0, high=0.5)
        check_number("RoadmapConfig", "detour_tolerance", self.detour_tolerance, low=1)
        check_int("RoadmapConfig", "num_poses", self.num_poses, low=2)
        if self.node_clearance < NODE_CLEARANCE or self.pose_clearance < POSE_CLEARANCE:
            raise ValueError(
                f"RoadmapConfig.node_clearance and pose_clearance must be at least the validation "
                f"clearances {NODE_CLEARANCE} and {POSE_CLEARANCE} m, got {self.node_clearance} and "
                f"{self.pose_clearance}"
            )


@dataclass(frozen=True, eq=False)
class FreeSpace:
    """The free space of a map on a grid.

    Attributes:
        origin: (2,) world position of the grid's lower-left corner, m.
        resolution: cell side, m.
        clearance: (nx, ny) distance from each cell centre to the nearest wall, m (exact up to 1 m,
            a grid estimate beyond).
        interior: (nx, ny) bool, the passable cells of the area being mapped: connected to the seed
            point, inside the building outline, at least free_clearance from walls.
        closures: (K, 4) virtual walls x1, y1, x2, y2 that closed openings of the outline to
            unmapped space when the interior was found (see free_space); they bound the interior
            but are not walls of the map.
    """

    origin: np.ndarray
    resolution: float
    clearance: np.ndarray
    interior: np.ndarray
    closures: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, columns) of the grid."""
        return (int(self.clearance.shape[0]), int(self.clearance.shape[1]))

    def centres(self, cells: np.ndarray) -> np.ndarray:
        """World positions (K, 2) of cell centres; cells (K, 2) int (i along x, j along y)."""
        return self.origin + (np.asarray(cells, dtype=np.float64) + 0.5) * self.resolution

    def cell_of(self, points: np.ndarray) -> np.ndarray:
        """Cells (K, 2) int holding world points (K, 2), clipped to the grid."""
        ij = np.floor((np.asarray(points, dtype=np.float64) - self.origin) / self.resolution).astype(np.int64)
        return np.clip(ij, 0, np.array(self.shape) - 1)

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Whether world points (K, 2) fall in interior cells; bool (K,)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        ij = np.floor((points - self.origin) / self.resolution).astype(np.int64)
        inside = ((ij >= 0) & (ij < np.array(self.shape))).all(axis=1)
        out = np.zeros(len(points), dtype=bool)
        out[inside] = self.interior[ij[inside, 0], ij[inside, 1]]
        return out


@dataclass(frozen=True, eq=False)
class Roadmap:
    """A navigation graph and the free space it was built on.

    Attributes:
        nodes: (N, 2) node positions, m.
        edges: (E, 2) node index pairs, i < j.
        space: the free space.
    """

    nodes: np.ndarray
    edges: np.ndarray
    space: FreeSpace = field(repr=False)


# ----------------------------------------------------------------------------- walls


def _fixed(value: float, digits: int) -> str:
    """`value` with `digits` decimals, or in 3 significant digits past 1e12 (1e+200, not 201 digits)."""
    return f"{value:.{digits}f}" if abs(value) < 1e12 else f"{value:.3g}"


def _bounds(walls: np.ndarray, region: Box | None, margin: float) -> Box:
    pts = walls.reshape(-1, 2)
    if region is None:
        if len(walls) == 0:
            raise ValueError("a map without walls needs a region to bound its free space")
        lo, hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
    x0, y0, x1, y1 = (float(v) for v in region)
    if not (x0 < x1 and y0 < y1):
        raise ValueError(f"region must be (xmin, ymin, xmax, ymax) with min < max, got {region}")
    lo, hi = pts.min(axis=0, initial=np.inf), pts.max(axis=0, initial=-np.inf)
    if len(walls) and (x1 < lo[0] or x0 > hi[0] or y1 < lo[1] or y0 > hi[1]):
        # Else: "found 0 places for legal poses ..., at most inf m from a wall", not a word of why.
        raise ValueError(
            f"region {[x0, y0, x1, y1]} holds no part of the plan, whose walls span ({lo[0]:.2f}, "
            f"{lo[1]:.2f}) to ({hi[0]:.2f}, {hi[1]:.2f}): give the region in the plan's coordinates"
        )
    return (x0, y0, x1, y1)


# ----------------------------------------------------------------------------- free space


def _grid_clearance(index: WallIndex, origin: np.ndarray, shape: tuple[int, int], res: float) -> np.ndarray:
    """(nx, ny) wall clearance of cell centres: exact within the index reach, estimated beyond."""
    walls = index.walls
    clearance = np.full(shape, np.inf)
    if len(walls) == 0:
        return clearance
    # Rasterise the walls (samples half a cell apart), then estimate clearance by a distance
    # transform; only cells that may be within reach of a wall get the exact (costlier) query.
    length = np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1])
    counts = np.ceil(length / (0.5 * res)).astype(np.int64) + 1
    wall_of = np.repeat(np.arange(len(walls)), counts)
    frac = (np.arange(len(wall_of)) - np.repeat(np.cumsum(counts) - counts, counts)) / np.repeat(
        np.maximum(counts - 1, 1), counts
    )
    pts = walls[wall_of, 0:2] + frac[:, None] * (walls[wall_of, 2:4] - walls[wall_of, 0:2])
    ij = np.floor((pts - origin) / res).astype(np.int64)
    ok = ((ij >= 0) & (ij < np.array(shape))).all(axis=1)
    occupied = np.zeros(shape, dtype=bool)
    occupied[ij[ok, 0], ij[ok, 1]] = True
    if not occupied.any():
        return clearance
    estimate = ndimage.distance_transform_edt(~occupied) * res
    near = np.argwhere(estimate <= index.reach + res)
    exact = np.empty(len(near))
    for start in range(0, len(near), 200_000):
        chunk = near[start : start + 200_000]
        exact[start : start + len(chunk)] = index.nearest(origin + (chunk + 0.5) * res)[1]
    clearance = estimate.astype(np.float64)
    clearance[near[:, 0], near[:, 1]] = np.where(np.isfinite(exact), exact, estimate[near[:, 0], near[:, 1]])
    return clearance


def free_space(
    walls: np.ndarray,
    region: Box | None = None,
    seed_point: tuple[float, float] | np.ndarray | None = None,
    config: RoadmapConfig | None = None,
    index: WallIndex | None = None,
    anchors: np.ndarray | None = None,
) -> FreeSpace:
    """Rasterise a map's free space and find the area to be mapped.

    The outside is what a flood fill from the grid border reaches through gaps wider than twice
    config.closing_radius; the interior is the passable cells (clearance >= free_clearance) that
    are not outside and are connected to the seed point (without one: to the area holding the
    most anchors, or the largest area when no anchor lies in any).
    A seed point outside every closed outline is allowed: its connected free space is used.
    Without region, seed point and anchors, an outline open to space the plan does not map (a
    room whose doorways lead nowhere) is closed: where no enclosed area has room for a start and
    a goal (legal poses pose_separation apart), nothing is enclosed, or wider closing encloses
    twice the largest area, the openings (up to 10 m) get virtual walls (FreeSpace.closures) and
    the interior ends at them; the walls themselves are not changed. Closed outlines give the same interior as before.

    Args:
        walls: (W, 4) wall segments, m.
        region: optional (xmin, ymin, xmax, ymax): the grid covers exactly this box; by default the
            walls' bounding box grown by config.margin.
        seed_point: optional (x, y) in the area to be mapped, m.
        config: grid and clearance settings.
        index: the walls' WallIndex, if already built.
        anchors: optional (K, 2) points that should lie in the area to be mapped, m (a given
            navigation graph's nodes: the area people walk in).

    Raises:
        ValueError: a seed point outside the grid or too close to a wall, no free space at all, or
            a grid of more than MAX_GRID_CELLS cells (named with its extent, before any is made).
    """
    config = config or RoadmapConfig()
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    res = config.resolution
    x0, y0, x1, y1 = _bounds(walls, region, config.margin)
    # Counted in floating point, where a plan in the wrong units (1e200 m across) is inf cells, not
    # an OverflowError of math.ceil or of the message's int-to-float.
    cells = max(1.0, float(np.ceil((x1 - x0) / res))) * max(1.0, float(np.ceil((y1 - y0) / res)))
    if cells > MAX_GRID_CELLS:
        raise ValueError(
            f"the plan spans {_fixed(x1 - x0, 0)} x {_fixed(y1 - y0, 0)} m (from ({_fixed(x0, 1)}, "
            f"{_fixed(y0, 1)}) to ({_fixed(x1, 1)}, {_fixed(y1, 1)}), margin included): its {100 * res:.0f} cm "
            f"free-space grid would have {_fixed(cells / 1e6, 0)} M cells, more than the {MAX_GRID_CELLS / 1e6:.0f} M "
            f"(about 7 GB of memory) an import handles; import a part of it with a region (map import "
            f"--region XMIN YMIN XMAX YMAX), or check that its coordinates are metres"
        )
    shape = (max(1, math.ceil((x1 - x0) / res)), max(1, math.ceil((y1 - y0) / res)))
    index = index or WallIndex(walls)
    origin = np.array([x0, y0])
    clearance = _grid_clearance(index, origin, shape, res)
    passable = clearance >= config.free_clearance

    inside = passable & ~_outside(clearance, config.closing_radius, res)
    closures = np.zeros((0, 4))

    if seed_point is not None:
        seed = np.asarray(seed_point, dtype=np.float64).reshape(2)
        if not (x0 <= seed[0] < x1 and y0 <= seed[1] < y1):
            raise ValueError(
                f"seed point ({seed[0]:.2f}, {seed[1]:.2f}) lies outside the grid {(x0, y0, x1, y1)}"
            )
        i, j = np.floor((seed - origin) / res).astype(np.int64)
        if not passable[i, j]:
            # Name the point's own clearance; the grid cell (whose centre decides) may differ a bit.
            exact = float(index.nearest(seed[None])[1][0])
            gap = exact if exact < config.free_clearance else float(clearance[i, j])
            raise ValueError(
                f"seed point ({seed[0]:.2f}, {seed[1]:.2f}) is {gap:.2f} m from a wall "
                f"(needs {config.free_clearance:.2f})"
            )
        if not inside[i, j]:
            logger.info("seed point (%.2f, %.2f) is outside every closed outline", *seed)
        area = inside if inside[i, j] else passable
        labels, _ = ndimage.label(area)
        interior = labels == labels[i, j]
    else:
        area = inside if inside.any() else passable
        labels, count = ndimage.label(area)
        if count == 0:
            raise ValueError(f"no free space with {config.free_clearance} m clearance in {(x0, y0, x1, y1)}")
        sizes = np.bincount(labels.ravel(), minlength=count + 1)
        sizes[0] = 0
        pick = int(np.argmax(sizes))
        if anchors is not None and len(anchors):
            ij = np.floor((np.reshape(anchors, (-1, 2)) - origin) / res).astype(np.int64)
            ij = ij[((ij >= 0) & (ij < np.array(shape))).all(axis=1)]  # the anchors on the grid
            held = np.bincount(labels[ij[:, 0], ij[:, 1]], minlength=count + 1)
            held[0] = 0
            if held.max() > 0:
                # Most anchors first, the larger area among equals.
                pick = int(np.lexsort((sizes, held))[-1])
        interior = labels == pick
        if region is None and (anchors is None or len(anchors) == 0):
            closed = _close_openings(index, origin, clearance, passable, inside, interior, config)
            if closed is not None:
                interior, closures = closed
    return FreeSpace(origin=origin, resolution=res, clearance=clearance, interior=interior, closures=closures)


def describe_closures(closures: np.ndarray) -> str:
    """The virtual walls of FreeSpace.closures in words, for an import's report."""
    closures = np.asarray(closures, dtype=np.float64).reshape(-1, 4)
    width = np.hypot(closures[:, 2] - closures[:, 0], closures[:, 3] - closures[:, 1])
    where = ", ".join(
        f"{w:.1f} m from ({c[0]:.2f}, {c[1]:.2f}) to ({c[2]:.2f}, {c[3]:.2f})"
        for c, w in zip(closures, width, strict=True)
    )
    return (
        f"the building's outline is open to space the plan does not map (no enclosed area has room "
        f"for the robot): {len(closures)} opening(s) closed by virtual walls ({where}); the map's "
        f"walls are unchanged, its graph and poses stay inside"
    )


def _outside(clearance: np.ndarray, radius: float, res: float) -> np.ndarray:
    """Cells outside the building: what a flood fill from the grid border reaches through cells
    at least `radius` from walls (openings narrower than 2 x radius stop it), grown back by the
    radius so that it reaches the outer walls again."""
    labels, _ = ndimage.label(clearance >= radius)
    border = np.concatenate((labels[0], labels[-1], labels[:, 0], labels[:, -1]))
    outside = np.isin(labels, np.unique(border[border > 0]))
    return ndimage.distance_transform_edt(~outside) * res <= radius + res


def _largest(area: np.ndarray) -> np.ndarray:
    """The largest 4-connected component of a bool grid (all False when there is none)."""
    labels, count = ndimage.label(area)
    if count == 0:
        return area.copy()
    sizes = np.bincount(labels.ravel(), minlength=count + 1)
    sizes[0] = 0
    return labels == int(np.argmax(sizes))


def _has_room(interior: np.ndarray, clearance: np.ndarray, config: RoadmapConfig) -> bool:
    """Whether an area holds places for a start and a goal: two cells with the tight-space clearance
    of legal_poses, pose_separation apart along x or y (a pocket between walls holds one at most)."""
    tight = max(POSE_CLEARANCE, config.free_clearance + config.resolution)
    cells = np.argwhere(interior & (clearance >= tight))
    return len(cells) > 0 and float(np.ptp(cells, axis=0).max()) * config.resolution >= config.pose_separation


def _close_openings(
    index: WallIndex,
    origin: np.ndarray,
    clearance: np.ndarray,
    passable: np.ndarray,
    inside: np.ndarray,
    interior: np.ndarray,
    config: RoadmapConfig,
) -> tuple[np.ndarray, np.ndarray] | None:
    """The interior of a plan whose outline is open to unmapped space, and the virtual walls that
    close it; None when the outline needs no closing or closing finds no room either.

    Needed when no enclosed area holds a place for a legal pose (openings wider than
    2 x closing_radius let the outside in: a room whose doorways lead to space the plan does not
    map), when nothing is enclosed at all (the outside then reaches every passable cell), or when
    closing the openings encloses an area at least twice the largest one found (a closet was
    enclosed, the building beside it was open). The
    openings are found with the wider CLOSING_RADII, one at a time: where the area they enclose
    meets the outside, a virtual wall joins the nearest wall points (snapped to a wall's end
    within 0.5 m) across the opening. The outside is then found again with the usual
    closing_radius and these virtual walls, so the interior ends at them (no wider erosion); the
    map's walls stay as drawn.
    """
    # With room already, only an opening that hides a much larger area (the building beside the
    # closet that alone was closed) is worth closing.
    need = 2 * int(interior.sum()) if inside.any() and _has_room(interior, clearance, config) else 0
    res = config.resolution
    for radius in CLOSING_RADII:
        if radius <= config.closing_radius:
            continue
        enclosed = _largest(passable & ~_outside(clearance, radius, res))
        if enclosed.sum() < need or not _has_room(enclosed, clearance, config):
            continue
        closures = _openings(index, origin, res, passable, enclosed)
        if len(closures) == 0:
            continue
        centres = origin + (np.argwhere(np.ones(clearance.shape, dtype=bool)) + 0.5) * res
        virtual = wall_distances(centres, closures).reshape(clearance.shape)
        closed = _largest(passable & ~_outside(np.minimum(clearance, virtual), config.closing_radius, res))
        if closed.sum() >= need and _has_room(closed, clearance, config):
            logger.debug("outline open to unmapped space: %d openings closed by virtual walls", len(closures))
            return closed, closures
    return None


def _openings(
    index: WallIndex, origin: np.ndarray, res: float, passable: np.ndarray, enclosed: np.ndarray
) -> np.ndarray:
    """Virtual walls (K, 4) across the openings where an enclosed area meets the outside: each
    run of passable cells beside it (the opening's mouth) joins the wall points nearest its two
    ends."""
    cross = ndimage.generate_binary_structure(2, 1)
    mouth = passable & ~enclosed & ndimage.binary_dilation(enclosed, structure=cross)
    labels, count = ndimage.label(mouth, structure=np.ones((3, 3), dtype=bool))
    ends = index.walls.reshape(-1, 2)
    closures = []
    for k in range(1, count + 1):
        points = origin + (np.argwhere(labels == k) + 0.5) * res
        a = points[np.argmax(np.hypot(*(points - points.mean(axis=0)).T))]
        b = points[np.argmax(np.hypot(*(points - a).T))]
        near, dist = index.nearest(np.stack((a, b)))
        if not np.isfinite(dist).all():
            continue
        for m in range(2):
            gap = np.hypot(*(ends - near[m]).T)
            if gap.min() <= 0.5:
                near[m] = ends[int(np.argmin(gap))]
        if np.hypot(*(near[1] - near[0])) > 2 * res:
            closures.append(near.reshape(4))
    return np.array(closures, dtype=np.float64).reshape(-1, 4)


# ----------------------------------------------------------------------------- nodes and edges


def place_nodes(space: FreeSpace, config: RoadmapConfig | None = None, seed: int = 0) -> np.ndarray:
    """Spread graph nodes over the interior, most clearance first.

    Each accepted node covers the interior cells within its spacing (spacing_per_clearance times its
    clearance, clipped to [min_spacing, max_spacing]) in walking distance, so a wall between two
    rooms does not hide one room from getting its own node; the next node is the uncovered cell
    with most clearance. Rooms thus get a node near their centre, corridors a chain along their
    centre line.

    Returns:
        (N, 2) node positions, m (cell centres).
    """
    config = config or RoadmapConfig()
    rng = np.random.default_rng(seed)
    res = space.resolution
    candidate = space.interior & (space.clearance >= config.node_clearance)
    flat = np.flatnonzero(candidate.ravel())
    # Most clearance first (to the centimetre); the seeded shuffle breaks ties.
    key = np.round(space.clearance.ravel()[flat], 2)
    order = flat[np.lexsort((rng.permutation(len(flat)), -key))]
    covered = np.zeros(space.shape, dtype=bool)
    nx, ny = space.shape
    chosen: list[tuple[int, int]] = []
    for cell in order:
        i, j = divmod(int(cell), ny)
        if covered[i, j]:
            continue
        chosen.append((i, j))
        radius = float(
            np.clip(
                config.spacing_per_clearance * space.clearance[i, j], config.min_spacing, config.max_spacing
            )
        )
        n = math.ceil(radius / res)
        i0, i1, j0, j1 = max(i - n, 0), min(i + n + 1, nx), max(j - n, 0), min(j + n + 1, ny)
        start = np.zeros((i1 - i0, j1 - j0), dtype=bool)
        start[i - i0, j - j0] = True
        # Walking distance: grow through interior cells only, then keep the Euclidean disk.
        walk = ndimage.binary_dilation(
            start, structure=np.ones((3, 3), dtype=bool), iterations=n, mask=space.interior[i0:i1, j0:j1]
        )
        di = np.arange(i0, i1)[:, None] - i
        dj = np.arange(j0, j1)[None, :] - j
        covered[i0:i1, j0:j1] |= walk & ((di**2 + dj**2) * res**2 <= radius**2)
    return space.centres(np.array(chosen, dtype=np.int64).reshape(-1, 2))


def _prune_detours(nodes: np.ndarray, edges: np.ndarray, tolerance: float) -> np.ndarray:
    """Drop edges (longest first) that a two-edge detour replaces within `tolerance`."""
    if len(edges) == 0:
        return edges
    length = np.hypot(*(nodes[edges[:, 0]] - nodes[edges[:, 1]]).T)
    dist = {(int(i), int(j)): float(d) for (i, j), d in zip(edges, length, strict=True)}
    adjacent: list[set[int]] = [set() for _ in range(len(nodes))]
    for i, j in dist:
        adjacent[i].add(j)
        adjacent[j].add(i)

    def d(a: int, b: int) -> float:
        return dist[(min(a, b), max(a, b))]

    # Longest first; stable on (i, j) so the result does not depend on float ties.
    for k in np.lexsort((edges[:, 1], edges[:, 0], -length)):
        i, j = int(edges[k, 0]), int(edges[k, 1])
        via = adjacent[i] & adjacent[j]
        if any(d(i, m) + d(m, j) <= tolerance * dist[(i, j)] for m in via):
            adjacent[i].discard(j)
            adjacent[j].discard(i)
            del dist[(i, j)]
    return np.array(sorted(dist), dtype=np.int64).reshape(-1, 2)


def build_edges(
    nodes: np.ndarray,
    walls: np.ndarray | WallIndex,
    clearance: float = 0.3,
    max_length: float = 15.0,
    detour_tolerance: float = 1.15,
) -> np.ndarray:
    """Join nodes by straight lines that keep `clearance` from every wall, then thin them out.

    Every pair closer than max_length whose segment stays at least `clearance` from all walls is a
    candidate; an edge is then dropped (longest first) when a path through one other node is at
    most detour_tolerance times longer. Dropping never disconnects the graph.

    Args:
        nodes: (N, 2) node positions, m.
        walls: (W, 4) wall segments, or their WallIndex.
        clearance: least wall distance along an edge, m (at most 0.5).
        max_length: longest edge, m.
        detour_tolerance: >= 1.

    Returns:
        (E, 2) node index pairs i < j, sorted.
    """
    index = walls if isinstance(walls, WallIndex) else WallIndex(np.asarray(walls, dtype=np.float64))
    if not 0.0 < clearance <= 0.5 * index.reach:
        raise ValueError(f"clearance must be in (0, {0.5 * index.reach}] m, got {clearance}")
    nodes = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
    i, j = np.triu_indices(len(nodes), k=1)
    length = np.hypot(*(nodes[i] - nodes[j]).T)
    near = length <= max_length
    i, j = i[near], j[near]
    clear = np.ones(len(i), dtype=bool)
    for start in range(0, len(i), 4096):
        part = slice(start, start + 4096)
        clear[part] = segment_clearance(index, nodes[i[part]], nodes[j[part]])[0] >= clearance
    edges = np.stack((i[clear], j[clear]), axis=1).astype(np.int64)
    return _prune_detours(nodes, edges, detour_tolerance)


def grid_graph(space: FreeSpace) -> tuple[sparse.csr_matrix, np.ndarray]:
    """Sparse 8-neighbour graph over interior cells, weighted to prefer clearance.

    Returns:
        (graph, cell_id): CSR matrix over interior cells, and (nx, ny) vertex id per cell (-1 off).
    """
    interior = space.interior
    cell_id = np.full(space.shape, -1, dtype=np.int64)
    cell_id[interior] = np.arange(int(interior.sum()))
    # Walking next to a wall costs up to 3x: paths keep to the middle of corridors and doors.
    penalty = 1.0 + 2.0 * np.clip(1.0 - space.clearance, 0.0, 1.0)
    rows, cols, weights = [], [], []
    nx, ny = space.shape
    for di, dj in GRID_STEPS:
        a = (slice(max(-di, 0), nx - max(di, 0)), slice(max(-dj, 0), ny - max(dj, 0)))
        b = (slice(max(di, 0), nx - max(-di, 0)), slice(max(dj, 0), ny - max(-dj, 0)))
        both = interior[a] & interior[b]
        step = math.hypot(di, dj) * space.resolution
        rows.append(cell_id[a][both])
        cols.append(cell_id[b][both])
        weights.append(step * 0.5 * (penalty[a][both] + penalty[b][both]))
    n = int(interior.sum())
    graph = sparse.coo_matrix(
        (np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    ).tocsr()
    return graph, cell_id


def pull_string(
    path: np.ndarray,
    index: WallIndex,
    clearance: float,
    max_length: float,
    path_clearance: np.ndarray | None = None,
    keep_clearance: float = 0.0,
    slack: float = 0.05,
    floor: float = 0.0,
) -> list[int]:
    """Indices of the path points (L, 2) kept when straight clear shortcuts replace the rest.

    A shortcut keeps at least `clearance` from every wall. With path_clearance (L,) (the wall
    distance of each path point) and keep_clearance > 0, it also keeps min(keep_clearance, the
    least path_clearance of the points it replaces) - slack: it never passes much closer to a wall
    than the walking path did, so a straightened path still goes through the middle of a doorway
    and keeps off the corners it turns round. And it keeps min(floor, that least path_clearance)
    without any slack: through a door barely wider than the robot needs (0.8 m for its 0.39 m),
    the path keeps to the door's centre line, where the robot can follow it, rather than the
    slack's 5 cm off it, where it cannot.
    """
    keep = [0]
    i = 0
    last = len(path) - 1
    while i < last:
        ahead = np.arange(i + 1, last + 1)
        ahead = ahead[np.hypot(*(path[ahead] - path[i]).T) <= max_length]
        need = np.full(len(ahead), clearance)
        if path_clearance is not None and keep_clearance > 0 and len(ahead):
            least = np.minimum.accumulate(np.minimum(path_clearance[ahead], path_clearance[i]))
            need = np.maximum(need, np.minimum(least, keep_clearance) - slack)
            need = np.maximum(need, np.minimum(least, floor) - 1e-9)
        ok = segment_clearance(index, np.broadcast_to(path[i], (len(ahead), 2)), path[ahead])[0] >= need
        ok &= ~index.crosses(np.broadcast_to(path[i], (len(ahead), 2)), path[ahead])
        # Next cell at least (grid steps are clear of walls even where the clearance check is not).
        i = int(ahead[np.flatnonzero(ok)[-1]]) if ok.any() else i + 1
        keep.append(i)
    return keep


class Walker:
    """Walking paths through a free space's interior: shortest paths on its grid graph (grid_graph),
    straightened into clear segments (pull_string) that keep to the middle of passages."""

    def __init__(self, space: FreeSpace, index: WallIndex, config: RoadmapConfig) -> None:
        self.space = space
        self.index = index
        self.config = config
        self.graph, self.cell_id = grid_graph(space)
        self.id_cells = np.argwhere(space.interior)  # vertex id -> cell, in the order cell_id numbers them

    def vertex(self, points: np.ndarray) -> np.ndarray:
        """Grid-graph vertices (K,) of the cells holding points (K, 2); -1 outside the interior."""
        return np.asarray(self.cell_id[tuple(self.space.cell_of(points).T)])

    def corners(self, walk: list[int], a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Corner points (L, 2) of a walk of grid vertices straightened, its ends set to a and b."""
        space, config = self.space, self.config
        cells = self.id_cells[walk]
        path = space.centres(cells)
        path[0], path[-1] = a, b
        corners = pull_string(
            path,
            self.index,
            min(config.edge_clearance, config.free_clearance - space.resolution),
            config.max_edge_length,
            space.clearance[cells[:, 0], cells[:, 1]],
            config.keep_clearance,
            floor=config.free_clearance,
        )
        return path[corners]

    def path(self, a: np.ndarray, b: np.ndarray, limit: float) -> np.ndarray | None:
        """Corner points (L, 2) of a straightened walking path from a to b (ends included), or
        None when there is none of weighted length at most `limit`."""
        va, vb = (int(v) for v in self.vertex(np.stack((a, b))))
        if va < 0 or vb < 0:
            return None
        dist, pred = csgraph.dijkstra(
            self.graph, directed=False, indices=va, limit=limit, return_predecessors=True
        )
        return self.corners(_walk(pred, vb), a, b) if np.isfinite(dist[vb]) else None


def _walk(pred: np.ndarray, end: int) -> list[int]:
    """The grid vertices of a shortest path (dijkstra's predecessors `pred`) that ends at `end`."""
    walk = [end]
    while pred[walk[-1]] >= 0:
        walk.append(int(pred[walk[-1]]))
    return walk[::-1]


def add_chain(
    nodes: list[np.ndarray], edges: list[tuple[int, ...]], i: int, j: int, corners: np.ndarray
) -> None:
    """Join nodes i and j through the inner points of `corners` (appended to `nodes` as new nodes)
    by edges (i < j pairs appended to `edges`)."""
    chain = [i]
    for p in corners[1:-1]:
        nodes.append(p)
        chain.append(len(nodes) - 1)
    chain.append(j)
    edges.extend((min(p, q), max(p, q)) for p, q in itertools.pairwise(chain))


def connect_components(
    space: FreeSpace,
    nodes: np.ndarray,
    edges: np.ndarray,
    index: WallIndex,
    config: RoadmapConfig | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Join the graph's components along walking paths through the free space.

    While the graph is disconnected, the shortest grid path (keeping to the middle of passages)
    from the largest component to the nearest other one is straightened into clear segments whose
    corners become new nodes. Nodes outside the interior cannot be joined and stay as they are.

    Returns:
        (nodes, edges) with the added nodes appended after the given ones.
    """
    config = config or RoadmapConfig()
    nodes = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    if len(nodes) < 2 or len(np.unique(graph_components(len(nodes), edges))) == 1:
        return nodes, edges
    walker = Walker(space, index, config)
    vertex = walker.vertex(nodes)
    node_list = list(nodes)
    edge_list = [tuple(e) for e in edges.tolist()]
    while True:
        label = graph_components(len(node_list), np.array(edge_list, dtype=np.int64).reshape(-1, 2))
        names, sizes = np.unique(label, return_counts=True)
        if len(names) == 1:
            break
        main = names[np.argmax(sizes)]
        source_nodes = np.flatnonzero((label == main) & (vertex[: len(label)] >= 0))
        # The grid graph stores each neighbour pair once (four of the eight steps): undirected.
        dist, pred = csgraph.dijkstra(
            walker.graph,
            directed=False,
            indices=vertex[source_nodes],
            min_only=True,
            return_predecessors=True,
        )[:2]
        others = np.flatnonzero((label != main) & (vertex[: len(label)] >= 0))
        if len(source_nodes) == 0 or len(others) == 0 or not np.isfinite(dist[vertex[others]]).any():
            logger.warning("connect_components: %d graph components cannot be joined", len(names))
            break
        target = int(others[np.argmin(dist[vertex[others]])])
        walk = _walk(pred, int(vertex[target]))
        start = int(source_nodes[np.flatnonzero(vertex[source_nodes] == walk[0])[0]])
        corners = walker.corners(walk, node_list[start], node_list[target])
        add_chain(node_list, edge_list, start, target, corners)
        added = np.array(node_list[len(vertex) :], dtype=np.float64).reshape(-1, 2)
        vertex = np.concatenate((vertex, walker.vertex(added)))
    return np.array(node_list, dtype=np.float64).reshape(-1, 2), np.array(
        sorted(set(edge_list)), dtype=np.int64
    )


def build_roadmap(
    walls: np.ndarray,
    region: Box | None = None,
    seed_point: tuple[float, float] | np.ndarray | None = None,
    config: RoadmapConfig | None = None,
    seed: int = 0,
    index: WallIndex | None = None,
    space: FreeSpace | None = None,
) -> Roadmap:
    """A connected navigation graph over a map's interior (see free_space for what that is).

    The free space is rasterised (exact wall clearance per grid cell), the building interior is found
    by flood fill from a seed point, graph nodes are spread over it (most clearance first, one per
    room, a few metres apart along corridors) and joined by straight lines that keep clear of walls.
    Everything is deterministic given the seed. `space`, free_space's result for these arguments
    when the caller has it already (rasterising a large building takes seconds), is used as given.

    Returns:
        the Roadmap: nodes (N, 2), edges (E, 2) and the free space they were built on.
    """
    config = config or RoadmapConfig()
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    index = index or WallIndex(walls)
    if space is None:
        space = free_space(walls, region, seed_point, config, index)
    nodes = place_nodes(space, config, seed)
    edges = build_edges(nodes, index, config.edge_clearance, config.max_edge_length, config.detour_tolerance)
    nodes, edges = connect_components(space, nodes, edges, index, config)
    return Roadmap(nodes=nodes, edges=edges, space=space)
