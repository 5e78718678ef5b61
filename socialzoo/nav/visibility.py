"""Who sees whom: exact wall occlusion of robot-human sight lines, fast on long lines.

A sight line joins two centres and is blocked when it touches any wall. With the map's distance
field (socialzoo.nav.local_planner.distance_field) the pieces of a line far from every wall are
cleared without testing them against the walls; the answer is the same as WallIndex.crosses.
"""

from __future__ import annotations

import math

import numpy as np

from socialzoo.core.walls import WallIndex
from socialzoo.nav.distance_field import DistanceField

# Sight lines: piece length of the distance-field pre-check, and the stretches (distances from
# the robot, m) in which lines are followed, stopping at the first wall.
_SIGHT_STEP = 0.25
_SIGHT_STRETCHES = (3.0, 10.0, math.inf)
# Up to this many sight lines, one plain test against the walls is cheaper than the above.
_FEW_LINES = 32


def lines_of_sight(
    p0: np.ndarray, p1: np.ndarray, walls: WallIndex, field: DistanceField | None = None
) -> np.ndarray:
    """Whether segments [p0, p1] (M, 2) touch no wall; bool (M,). Exact.

    With a distance field, each segment is cut into pieces of at most `_SIGHT_STEP` m; a piece
    whose ends read wall distances summing to more than its length (plus the field's error)
    cannot touch a wall, so only the other pieces are tested against the walls. Segments are
    followed outwards from p0 in a few stretches (`_SIGHT_STRETCHES`), and a segment found
    blocked is not followed further: most sight lines in a building end at the first wall.
    """
    clear = np.ones(len(p0), dtype=bool)
    if len(p0) == 0:
        return clear
    if field is None or len(p0) <= _FEW_LINES:
        return ~walls.crosses(p0, p1)
    delta = p1 - p0
    length = np.sqrt(delta[:, 0] ** 2 + delta[:, 1] ** 2)
    unit = delta / np.maximum(length, 1e-12)[:, None]
    slack = field.resolution * math.sqrt(0.5) + 1e-6  # a lookup's largest overestimate
    begin = 0.0
    for end in _SIGHT_STRETCHES:
        lines = np.flatnonzero(clear & (length > begin))
        if len(lines) == 0:
            break
        a = p0[lines] + begin * unit[lines]
        b = p0[lines] + np.minimum(length[lines], end)[:, None] * unit[lines]
        clear[lines[_stretch_blocked(a, b, walls, field, slack)]] = False
        begin = end
    return clear


def _stretch_blocked(
    a: np.ndarray, b: np.ndarray, walls: WallIndex, field: DistanceField, slack: float
) -> np.ndarray:
    """Which segments [a, b] (M, 2) touch a wall, testing only their pieces near one; bool (M,)."""
    delta = b - a
    length = np.sqrt(delta[:, 0] ** 2 + delta[:, 1] ** 2)
    count = np.maximum(np.ceil(length / _SIGHT_STEP).astype(np.intp) + 1, 2)
    seg = np.repeat(np.arange(len(a)), count)
    rank = np.arange(len(seg)) - np.repeat(np.cumsum(count) - count, count)
    points = a[seg] + (rank / (count - 1)[seg])[:, None] * delta[seg]
    # Piece k joins points k and k + 1; a point of it is within d of one end and (piece - d) of
    # the other, so the piece clears every wall when the ends' distances sum to more than its
    # length (plus twice the field's error).
    dist = field.lookup(points)
    piece_len = (length / (count - 1))[seg[:-1]]
    close = dist[:-1] + dist[1:] <= piece_len + 2.0 * slack
    piece = np.flatnonzero(close & (seg[1:] == seg[:-1]))
    hit = walls.crosses(points[piece], points[piece + 1])
    return np.bincount(seg[piece[hit]], minlength=len(a)) > 0


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
        field: the walls' distance field (socialzoo.nav.local_planner.distance_field), to clear
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
