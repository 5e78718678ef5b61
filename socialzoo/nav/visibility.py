"""Who sees whom: exact wall occlusion of robot-human sight lines, fast on long lines."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from socialzoo.core.geometry import point_segment_dist2, segments_gap, segments_intersect, segments_meet
from socialzoo.core.jit import kernel
from socialzoo.core.walls import WallIndex, grid_cell
from socialzoo.nav.distance_field import DistanceField

# Sight lines: piece length of the distance-field pre-check, and the stretches (distances from
# the robot, m) in which lines are followed, stopping at the first wall.
_SIGHT_STEP = 0.25
_SIGHT_STRETCHES = (3.0, 10.0, math.inf)
# Pieces whose field margin is below this are measured exactly (m): a clearance certificate
# (socialzoo.nav.sight_cache) then lasts longer than the field's bound would let it.
_EXACT_BELOW = 0.1
# Candidate walls of those pieces come from a grid listing the walls within this reach of each
# cell (m): at least _EXACT_BELOW + _SIGHT_STEP, so the walls left out cannot set the minimum.
_EXACT_REACH = 0.5
# Up to this many sight lines, one plain test against the walls is cheaper than the above.
_FEW_LINES = 32


class Sight(NamedTuple):
    """Line-of-sight answers for M segments.

    Attributes:
        clear: (M,) bool, the segment touches no wall.
        clearance: (M,) for clear segments a lower bound on their distance to every wall, m
            (0 for blocked ones).
        wall: (M,) for blocked segments the index of a wall they touch, -1 for clear ones.
    """

    clear: np.ndarray
    clearance: np.ndarray
    wall: np.ndarray


def lines_of_sight(
    p0: np.ndarray, p1: np.ndarray, walls: WallIndex, field: DistanceField | None = None
) -> np.ndarray:
    """Whether segments [p0, p1] (M, 2) touch no wall; bool (M,). Exact.

    With a distance field and more than a few segments this is `sight_lines(...).clear`;
    otherwise one plain WallIndex.crosses test.
    """
    if len(p0) == 0:
        return np.ones(0, dtype=bool)
    if field is None or len(p0) <= _FEW_LINES:
        return ~walls.crosses(p0, p1)
    return sight_lines(p0, p1, walls, field).clear


def sight_lines(p0: np.ndarray, p1: np.ndarray, walls: WallIndex, field: DistanceField) -> Sight:
    """Exact wall occlusion of segments [p0, p1] (M, 2), with a clearance or a blocking wall each.

    Each segment is cut into pieces of at most `_SIGHT_STEP` m. A piece whose ends read wall
    distances d1, d2 in the field keeps at least (d1 + d2 - length) / 2 - error from every wall;
    only pieces without such a margin are tested against their candidate walls (which also gives
    their exact clearance). Segments are followed outwards from p0 in a few stretches
    (`_SIGHT_STRETCHES`), and a segment found blocked is not followed further: most sight lines
    in a building end at the first wall.

    The same answers as WallIndex.crosses, plus what socialzoo.nav.sight_cache needs to trust an answer
    on later steps (a clear line's clearance, a blocked line's wall). Suits many fresh lines, most of
    them blocked.
    """
    m = len(p0)
    clear = np.ones(m, dtype=bool)
    clearance = np.full(m, np.inf)
    wall = np.full(m, -1, dtype=np.intp)
    if m == 0:
        return Sight(clear, clearance, wall)
    delta = p1 - p0
    length = np.sqrt(delta[:, 0] ** 2 + delta[:, 1] ** 2)
    unit = delta / np.maximum(length, 1e-12)[:, None]
    slack = lookup_slack(field)
    begin = 0.0
    # Following few lines in stretches saves less than the extra calls cost.
    for end in _SIGHT_STRETCHES if m > _FEW_LINES else (math.inf,):
        # The first stretch takes every segment, points (zero length) included.
        lines = np.flatnonzero(clear & (length > begin)) if begin > 0.0 else np.arange(m)
        if len(lines) == 0:
            break
        a = p0[lines] + begin * unit[lines]
        b = p0[lines] + np.minimum(length[lines], end)[:, None] * unit[lines]
        hit_wall, margin = _stretch(a, b, walls, field, slack)
        blocked = hit_wall >= 0
        clear[lines[blocked]] = False
        wall[lines[blocked]] = hit_wall[blocked]
        clearance[lines] = np.minimum(clearance[lines], margin)
        begin = end
    clearance[~clear] = 0.0
    return Sight(clear, np.maximum(clearance, 0.0), wall)


@kernel
def near_sight_line(x0, y0, x1, y1, end_clearance, grid, cell_start, cell_walls, walls):  # type: ignore[no-untyped-def]
    """(a wall the segment [p0, p1] touches or -1, its clearance or 0); a scalar kernel.

    Every wall that can touch the segment is listed on the fine wall grid (grid, cell_start,
    cell_walls: GridTable.shape_args and its lists) for one of its samples: its start for a
    segment up to `reach` long, else points at most `reach` apart (as WallIndex.line_candidates).
    A segment that meets no wall is closest to a wall either at one of its own ends
    (`end_clearance`, a lower bound on both ends' wall distance) or at one of the wall's ends, so
    those distances give the clearance, capped at what the walls not listed are certainly
    farther than (`reach` less the farthest any point lies from its sample).

    The same answers as WallIndex.crosses; suits a few lines, or lines that were clear a moment ago
    (socialzoo.nav.sight_cache).
    """
    dx, dy = x1 - x0, y1 - y0
    len2 = dx * dx + dy * dy
    inv_len2 = 1.0 / len2 if len2 > 0.0 else 0.0
    length = math.sqrt(len2)
    reach = grid[5]
    if length <= reach:
        samples, from_sample = 1, length
    else:
        pieces = math.ceil(length / reach)
        samples, from_sample = int(pieces) + 1, 0.5 * length / pieces
    best2 = (reach - from_sample) ** 2
    for k in range(samples):
        frac = k / max(samples - 1, 1)
        cell = grid_cell(x0 + frac * dx, y0 + frac * dy, grid)
        for c in range(cell_start[cell], cell_start[cell + 1]):
            w = cell_walls[c]
            ax, ay, bx, by = walls[w, 0], walls[w, 1], walls[w, 2], walls[w, 3]
            if segments_meet(x0, y0, x1, y1, ax, ay, bx, by):
                return w, 0.0
            best2 = min(
                best2,
                point_segment_dist2(ax, ay, x0, y0, dx, dy, inv_len2),
                point_segment_dist2(bx, by, x0, y0, dx, dy, inv_len2),
            )
    return -1, max(min(math.sqrt(best2), end_clearance), 0.0)


def lookup_slack(field: DistanceField) -> float:
    """A distance-field lookup's largest overestimate of the true wall distance, m."""
    return field.resolution * math.sqrt(0.5) + 1e-6


def _stretch(
    a: np.ndarray, b: np.ndarray, walls: WallIndex, field: DistanceField, slack: float
) -> tuple[np.ndarray, np.ndarray]:
    """(a wall each segment [a, b] (M, 2) touches or -1, a lower bound on its wall distance)."""
    delta = b - a
    length = np.sqrt(delta[:, 0] ** 2 + delta[:, 1] ** 2)
    count = np.maximum(np.ceil(length / _SIGHT_STEP).astype(np.intp) + 1, 2)
    first = np.cumsum(count) - count
    seg = np.repeat(np.arange(len(a)), count)
    rank = np.arange(len(seg)) - np.repeat(first, count)
    points = a[seg] + (rank / (count - 1)[seg])[:, None] * delta[seg]
    # Piece k joins points k and k + 1 (pieces spanning two segments are ignored). A point of
    # it is within s of one end and (length - s) of the other, so it keeps a distance of at
    # least (d1 + d2 - length) / 2 - slack from every wall.
    dist = field.lookup(points)
    piece_len = (length / (count - 1))[seg[:-1]]
    margin = (dist[:-1] + dist[1:] - piece_len) * 0.5 - slack
    margin[first[1:] - 1] = np.inf
    hit_wall = np.full(len(a), -1, dtype=np.intp)
    near = np.flatnonzero(margin < _EXACT_BELOW)
    if len(near):
        exact, touched = _piece_clearance(points[near], points[near + 1], walls)
        margin[near] = exact
        hit = touched >= 0
        hit_wall[seg[near[hit]]] = touched[hit]
    return hit_wall, np.minimum.reduceat(margin, first)


def _piece_clearance(q0: np.ndarray, q1: np.ndarray, walls: WallIndex) -> tuple[np.ndarray, np.ndarray]:
    """Exact wall distance of short segments [q0, q1] (M, 2) (up to the grid's reach) and a wall
    each touches (-1 for none).

    The grid lists, for q0's cell, every wall within `reach` of q0; walls not listed are
    farther than reach - length from every point of the segment.
    """
    t = walls.table(reach=_EXACT_REACH)
    query, cand = t.candidates(t.cells(q0))
    delta = q1 - q0
    dist = np.maximum(t.reach - np.sqrt(delta[:, 0] ** 2 + delta[:, 1] ** 2), 0.0)
    touched = np.full(len(q0), -1, dtype=np.intp)
    if len(query):
        a, b, c, d = q0[query], q1[query], walls.wall_a[cand], walls.wall_b[cand]
        hit = segments_intersect(a, b, c, d)
        np.minimum.at(dist, query, np.where(hit, 0.0, segments_gap(a, b, c, d)))
        touched[query[hit]] = cand[hit]
    return dist, touched


def visible_humans(
    robot_pose: np.ndarray,
    human_pos: np.ndarray,
    human_mask: np.ndarray,
    walls: WallIndex | None,
    field: DistanceField | None = None,
) -> np.ndarray:
    """Humans each robot sees: present, and the robot-human line of sight touches no wall.

    No range or field-of-view limit (the SPEC sets none). Only present humans are tested.

    Args:
        robot_pose: (N, 3) x, y (m), theta (rad), world frame.
        human_pos: (N, H, 2) human centres, world frame, m.
        human_mask: (N, H) present humans (or any subset worth testing).
        walls: the map's wall index, or None for no walls.
        field: the walls' distance field (socialzoo.nav.distance_field), to clear
            lines far from any wall without testing them against the walls; same result.

    Returns:
        (N, H) bool.
    """
    visible = np.array(human_mask, dtype=bool)
    if walls is None or walls.num_walls == 0 or not visible.any():
        return visible
    start = np.broadcast_to(robot_pose[:, None, :2], human_pos.shape)[visible]
    visible[visible] = lines_of_sight(start, human_pos[visible], walls, field)
    return visible


def nearest_visible_ahead(
    robot_pose: np.ndarray,
    human_pos: np.ndarray,
    human_mask: np.ndarray,
    walls: WallIndex | None,
    count: int,
    field: DistanceField | None = None,
) -> np.ndarray:
    """Visibility of the humans ahead that target selection can use: (N, H) bool.

    Marks visible humans ahead of each robot (x > 0 in its frame), nearest first, until `count`
    are found; farther humans are left False. `select_target_human` gives the same answer with
    this as with every human's visibility, at the cost of a few sight lines per robot: the
    nearest `count` candidates are tested first, and the rest only for robots that still lack
    `count` visible ones.
    """
    n, num_humans = human_mask.shape
    visible = np.zeros((n, num_humans), dtype=bool)
    rel = human_pos - robot_pose[:, None, :2]
    ahead = (
        np.cos(robot_pose[:, 2])[:, None] * rel[..., 0] + np.sin(robot_pose[:, 2])[:, None] * rel[..., 1] > 0
    )
    cand = human_mask & ahead
    if not cand.any():
        return visible
    order = np.argsort(np.where(cand, rel[..., 0] ** 2 + rel[..., 1] ** 2, np.inf), axis=1, kind="stable")
    rows = np.arange(n)[:, None]
    ranked = cand[rows, order]  # candidates first, nearest first
    if ranked.sum() <= _FEW_LINES:  # few sight lines: one test of all of them is cheaper
        visible[cand] = visible_humans(robot_pose, human_pos, cand, walls, field)[cand]
        return visible & (np.cumsum(visible[rows, order], axis=1) <= count)[rows, np.argsort(order, axis=1)]
    first = ranked & (np.arange(num_humans) < count)
    seen = visible_humans(robot_pose, human_pos[rows, order], first, walls, field)
    short = seen.sum(axis=1) < count
    rest = ranked & ~first & short[:, None]
    if rest.any():
        seen |= visible_humans(robot_pose, human_pos[rows, order], rest, walls, field)
        # Keep only the nearest `count` visible ones (the rest cannot be chosen anyway).
        seen &= np.cumsum(seen, axis=1) <= count
    visible[rows, order] = seen
    return visible
