"""Legal start/goal poses for a wall map that comes without them (`generate_legal_poses`)."""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from socialzoo.core.walls import WallIndex
from socialzoo.maps.map_file import POSE_CLEARANCE, MapError, segment_clearance
from socialzoo.maps.roadmap import GRID_STEPS, Box, FreeSpace, RoadmapConfig, free_space


def _ridge(clearance: np.ndarray) -> np.ndarray:
    """Cells on the clearance ridge (medial axis): a local maximum along some grid direction."""
    c = np.where(np.isfinite(clearance), clearance, 1e9)
    padded = np.pad(c, 1, mode="edge")
    nx, ny = c.shape
    eps = 1e-6
    ridge = np.zeros(c.shape, dtype=bool)
    for di, dj in GRID_STEPS:
        fwd = padded[1 + di : 1 + di + nx, 1 + dj : 1 + dj + ny]
        back = padded[1 - di : 1 - di + nx, 1 - dj : 1 - dj + ny]
        # Strict on one side at least, so a cell beside a straight wall (flat along it) is no ridge.
        ridge |= (c >= fwd - eps) & (c >= back - eps) & ((c > fwd + eps) | (c > back + eps))
    return ridge


def _graph_distances(nodes: np.ndarray, edges: np.ndarray) -> np.ndarray:
    n = len(nodes)
    length = np.hypot(*(nodes[edges[:, 0]] - nodes[edges[:, 1]]).T) if len(edges) else np.zeros(0)
    matrix = sparse.coo_matrix((length, (edges[:, 0], edges[:, 1])), shape=(n, n)).tocsr()
    return csgraph.shortest_path(matrix, directed=False)


def generate_legal_poses(
    walls: np.ndarray,
    nodes: np.ndarray,
    edges: np.ndarray,
    space: FreeSpace | None = None,
    region: Box | None = None,
    seed_point: tuple[float, float] | np.ndarray | None = None,
    config: RoadmapConfig | None = None,
    seed: int = 0,
    index: WallIndex | None = None,
) -> np.ndarray:
    """Legal start/goal poses spread over the interior, facing along the free space.

    Candidates are clearance-ridge cells (corridor centre lines, room centres) with at least
    config.pose_clearance, one per half-metre block, that see a graph node along a line keeping
    config.join_clearance from walls (the robot can drive from the pose to the graph and back).
    Poses are picked by farthest-point sampling in walking distance (to the nearest visible node,
    along the graph, then out again), scaled by clearance up to config.good_clearance: dead ends
    and rooms come first; they keep config.pose_separation from each other. A building with fewer
    than two such places config.pose_separation apart (tight spaces: rooms and corridors narrower
    than 1.2 m, a room less than about 3 m across) gets candidates down to config.free_clearance
    plus one grid cell. Each pose faces the direction with the most free space around it.

    Deterministic given the seed.

    Args:
        walls: (W, 4) wall segments, m.
        nodes: the navigation graph's nodes, (N, 2) m.
        edges: the navigation graph's edges, (E, 2) node index pairs.
        space: the free space (built from walls, region and seed_point when not given).
        region: see free_space.
        seed_point: see free_space.
        config: num_poses, pose_clearance, pose_separation, good_clearance.
        seed: seeds the tie-breaking order.
        index: the walls' WallIndex, if already built.

    Returns:
        (P, 3) poses x, y (m), theta (rad), 2 <= P <= config.num_poses.

    Raises:
        MapError: no two places for a pose config.pose_separation apart, even in tight spaces; the
            message names the free space, its extent and what a pose needs there.
    """
    config = config or RoadmapConfig()
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    index = index or WallIndex(walls)
    space = space or free_space(walls, region, seed_point, config, index)
    nodes = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    rng = np.random.default_rng(seed)

    ridge = _ridge(space.clearance)
    tight = max(POSE_CLEARANCE, config.free_clearance + space.resolution)
    graph_dist = _graph_distances(nodes, edges)
    for clearance in dict.fromkeys((config.pose_clearance, min(tight, config.pose_clearance))):
        points, value, attach = _candidates(space, ridge, clearance, nodes, index, config, rng)
        # Two poses at least: a start and a goal (two places closer than pose_separation count
        # as one: a small room's candidates are all within it).
        hop = np.hypot(*(points - nodes[attach]).T)
        chosen = _spread(points, value, hop, attach, graph_dist, config) if len(points) >= 2 else []
        if len(chosen) >= 2:
            break
    if len(chosen) < 2:
        raise MapError(_no_place_message(space, nodes, clearance, config, len(points)))
    pos = points[chosen]
    return np.concatenate((pos, _open_heading(index, pos)[:, None]), axis=1)


def _spread(
    points: np.ndarray,
    value: np.ndarray,
    hop: np.ndarray,
    attach: np.ndarray,
    graph_dist: np.ndarray,
    config: RoadmapConfig,
) -> list[int]:
    """Indices of the candidates (K, 2) picked by farthest-point sampling in walking distance
    (hop (K,) to their attach node (K,), then along the graph), scaled by clearance (value (K,)),
    at least config.pose_separation apart, at most config.num_poses."""

    def walking(from_k: int) -> np.ndarray:
        d = hop + graph_dist[attach, attach[from_k]] + hop[from_k]
        same = attach == attach[from_k]
        d[same] = np.hypot(*(points[same] - points[from_k]).T)
        # Poses must also stand apart in a straight line (two poses either side of a thin wall
        # are far apart on foot but would still overlap).
        return np.minimum(d, np.hypot(*(points - points[from_k]).T))

    quality = np.minimum(value / config.good_clearance, 1.0)
    # Start from the candidate farthest from the roomiest one (a far end of the building).
    nearest = walking(int(np.argmax(value)))
    nearest[~np.isfinite(nearest)] = -1.0
    chosen = [int(np.argmax(nearest * quality))]
    nearest = walking(chosen[0])
    while len(chosen) < config.num_poses:
        score = np.where(np.isfinite(nearest), nearest, -1.0) * quality
        if len(chosen) == 1:
            # The goal for the start: the best candidate far enough away, even where a closer
            # one scores higher (a small room's roomy middle against its far corners).
            score[nearest < config.pose_separation] = -1.0
        best = int(np.argmax(score))
        if nearest[best] < config.pose_separation or score[best] <= 0:
            break
        chosen.append(best)
        nearest = np.minimum(nearest, walking(best))
    return chosen


def _candidates(
    space: FreeSpace,
    ridge: np.ndarray,
    clearance: float,
    nodes: np.ndarray,
    index: WallIndex,
    config: RoadmapConfig,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (K, 2), clearance (K,), attach node (K,)) of the pose candidates with `clearance`:
    the roomiest ridge cell of each half-metre block, in a seeded order, that joins one of its
    eight nearest nodes by a straight line keeping config.join_clearance from walls (the
    nearest such node is its attach node)."""
    cells = np.argwhere(space.interior & (space.clearance >= clearance) & ridge)
    if len(cells) == 0:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0, dtype=np.int64)
    block = max(1, round(0.5 / space.resolution))
    block_id = (cells[:, 0] // block) * (space.shape[1] // block + 1) + cells[:, 1] // block
    value = space.clearance[cells[:, 0], cells[:, 1]]
    order = np.lexsort((-value, block_id))
    first = order[np.r_[True, block_id[order][1:] != block_id[order][:-1]]]
    cells = cells[first]
    cells = cells[rng.permutation(len(cells))]
    points = space.centres(cells)
    value = space.clearance[cells[:, 0], cells[:, 1]]
    k = min(8, len(nodes))
    near = np.argsort(((points[:, None, :] - nodes[None, :, :]) ** 2).sum(-1), axis=1, kind="stable")[:, :k]
    starts = np.repeat(points[:, None, :], k, axis=1).reshape(-1, 2)
    ends = nodes[near].reshape(-1, 2)
    seen = ~index.crosses(starts, ends)
    if config.join_clearance > 0 and seen.any():
        seen[seen] = segment_clearance(index, starts[seen], ends[seen])[0] >= config.join_clearance
    seen = seen.reshape(len(points), k)
    has = seen.any(axis=1)
    points, value, near, seen = points[has], value[has], near[has], seen[has]
    return points, value, near[np.arange(len(points)), np.argmax(seen, axis=1)]


def _no_place_message(
    space: FreeSpace, nodes: np.ndarray, clearance: float, config: RoadmapConfig, found: int
) -> str:
    """Why no legal poses can be placed, naming the part of the plan: the free space the graph
    lies in, its extent and area, and what a pose needs there."""
    cells = np.argwhere(space.interior)
    if len(cells) == 0:
        return f"found {found} places for legal poses: the free space is empty"
    lo, hi = space.centres(cells.min(axis=0)[None])[0], space.centres(cells.max(axis=0)[None])[0]
    area = len(cells) * space.resolution**2
    widest = float(space.clearance[space.interior].max())
    need = f"no point {clearance:.2f} m from every wall"
    if config.join_clearance > 0:
        need += f" that joins a graph node by a line {config.join_clearance:.2f} m from walls"
    why = f"its rooms and passages are narrower than the {2 * clearance:.2f} m a pose needs"
    if widest >= clearance:
        # Room enough: what fails is the join (the graph lies elsewhere, or behind walls).
        inside = int(space.contains(nodes).sum())
        why = f"{inside} of the graph nodes lie in it, and no place with room for a pose sees one"
    if found:
        need = f"no two such places {config.pose_separation:.1f} m apart"
        why = f"it is too small for a start and a goal {config.pose_separation:.1f} m apart"
    return (
        f"found {found} places for legal poses with {clearance:.2f} m clearance: the free space the robot "
        f"can drive ({area:.1f} m^2 between ({lo[0]:.1f}, {lo[1]:.1f}) and ({hi[0]:.1f}, {hi[1]:.1f}), "
        f"at most {widest:.2f} m from a wall, {len(nodes)} graph nodes) has {need}: {why}"
    )


def _open_heading(index: WallIndex, points: np.ndarray, max_range: float = 8.0) -> np.ndarray:
    """(P,) heading (rad) of the most open direction: the longest free ray, smoothed over 45 degrees."""
    angles = np.linspace(-np.pi, np.pi, 72, endpoint=False)
    ranges = index.cast_rays(points, np.broadcast_to(angles, (len(points), len(angles))), max_range)
    kernel = np.ones(9) / 9.0
    wrapped = np.concatenate((ranges[:, -4:], ranges, ranges[:, :4]), axis=1)
    smooth = np.stack([np.convolve(r, kernel, mode="valid") for r in wrapped]).reshape(len(points), -1)
    return angles[np.argmax(smooth, axis=1)]
