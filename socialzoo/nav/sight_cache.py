"""Robot-human visibility kept from step to step: only sight lines that may have changed are re-tested."""

from __future__ import annotations

import numpy as np

from socialzoo.core.geometry import segments_meet
from socialzoo.core.jit import kernel
from socialzoo.core.walls import WallIndex
from socialzoo.nav.distance_field import DistanceField, field_distance
from socialzoo.nav.visibility import lookup_slack, near_sight_line, sight_lines

UNKNOWN, CLEAR, BLOCKED = 0, 1, 2
# Taken off every clearance so that rounding in the displacement test cannot matter, m.
_ROUNDING = 1e-9
# More fresh lines than this are tested with the distance-field pieces (see SightCache.visible).
_MANY_FRESH = 256


class SightCache:
    """Which humans each of N observers sees, for an (N, H) grid of sight lines, kept across steps.

    Between two steps a robot and a human move a few centimetres, so most sight lines keep their
    answer, and each line carries a certificate that proves it without touching the walls:

    - a clear line with clearance c (a lower bound on its distance to every wall) stays clear while
      both of its ends stay within c of where they were when it was tested: every point of the new
      line is then within c of a point of the old one;
    - a blocked line stays blocked while it still crosses the wall that blocked it (one segment test).

    Every other line (new, expired, or whose human just appeared) is tested exactly with
    `socialzoo.nav.visibility.near_sight_line` (or `sight_lines` for many fresh lines), so the
    answers are always those of a full test. The per-line bookkeeping is one compiled kernel.

    Args:
        walls: the map's wall index.
        field: the walls' distance field (socialzoo.nav.distance_field).
        num_observers: N (robots, one per batch row and robot).
        num_humans: H.

    Call `forget(rows)` whenever observers or humans of those rows jump (a reset); humans that
    leave the mask are forgotten automatically.
    """

    def __init__(self, walls: WallIndex, field: DistanceField, num_observers: int, num_humans: int) -> None:
        self.walls = walls
        self.field = field
        shape = (num_observers, num_humans)
        self.status = np.zeros(shape, dtype=np.int8)
        self.clearance2 = np.zeros(shape)  # squared (clearance - rounding) of clear lines
        self.wall = np.full(shape, -1, dtype=np.intp)
        self.observer_at = np.zeros((*shape, 2))  # line ends when last tested
        self.human_at = np.zeros((*shape, 2))
        self.lines_tested = 0  # sight lines tested exactly, for benchmarks
        self.lines_asked = 0

    def forget(self, rows: np.ndarray) -> None:
        """Drop what is known about the sight lines of observers `rows`."""
        self.status[rows] = UNKNOWN

    def visible(self, observer: np.ndarray, human_pos: np.ndarray, human_mask: np.ndarray) -> np.ndarray:
        """(N, H) bool: human present and the observer-human line touches no wall.

        Args:
            observer: (N, 2) observer positions, world frame, m.
            human_pos: (N, H, 2) human positions, world frame, m.
            human_mask: (N, H) present humans.
        """
        observer = np.ascontiguousarray(observer, dtype=np.float64)
        visible = np.empty(human_mask.shape, dtype=bool)
        t = self.walls.fine
        args = (
            observer, human_pos, human_mask, self.status, self.clearance2, self.wall, self.observer_at,
            self.human_at, t.shape_args, t.cell_start, t.cell_walls, self.walls.walls,
            self.field.shape_args, self.field.codes, lookup_slack(self.field), visible,
        )  # fmt: skip
        # Many fresh lines (after a reset) are mostly blocked by the first walls they meet, which
        # the pieces of `sight_lines` find without following them further; a few lines, or lines
        # known clear a moment ago, cost less with `near_sight_line`. The kernel declines (-1)
        # when there are more fresh lines than `_MANY_FRESH`.
        tested = _renew_sight_lines(*args, _MANY_FRESH)
        if tested < 0:
            fresh = np.flatnonzero((self.status == UNKNOWN) & human_mask)
            self._retest(fresh, observer, human_pos)
            tested = len(fresh) + _renew_sight_lines(*args, fresh.size)
        self.lines_asked += int(np.count_nonzero(human_mask))
        self.lines_tested += tested
        return visible

    def _retest(self, lines: np.ndarray, observer: np.ndarray, human_pos: np.ndarray) -> None:
        """Test flat line indices `lines` with `sight_lines` and store answers and certificates."""
        start = observer.take(lines // self.status.shape[1], axis=0)
        end = human_pos.reshape(-1, 2).take(lines, axis=0)
        sight = sight_lines(start, end, self.walls, self.field)
        self.status.reshape(-1)[lines] = np.where(sight.clear, CLEAR, BLOCKED)
        clearance = np.maximum(sight.clearance - _ROUNDING, 0.0)
        self.clearance2.reshape(-1)[lines] = clearance**2
        self.wall.reshape(-1)[lines] = sight.wall
        self.observer_at.reshape(-1, 2)[lines] = start
        self.human_at.reshape(-1, 2)[lines] = end


@kernel
def _renew_sight_lines(
    observer, human_pos, human_mask, status, clearance2, wall, observer_at, human_at,
    grid, cell_start, cell_walls, walls, field_shape, field_codes, field_slack, visible, max_fresh,
):  # fmt: skip
    """Bring every present line's answer up to date and write `visible`; returns lines tested.

    Absent humans' lines are forgotten. A clear line is kept while both ends moved less than its
    clearance, a blocked line while it still crosses its wall; the others are tested with
    `near_sight_line` and get a new certificate. If more than `max_fresh` lines have never been
    tested, nothing but the forgetting is done and -1 is returned.
    """
    num_observers, num_humans = human_mask.shape
    fresh = 0
    for n in range(num_observers):
        for h in range(num_humans):
            if not human_mask[n, h]:
                status[n, h] = UNKNOWN
            elif status[n, h] == UNKNOWN:
                fresh += 1
    if fresh > max_fresh:
        return -1
    tested = 0
    for n in range(num_observers):
        ox, oy = observer[n, 0], observer[n, 1]
        end_observer = field_distance(ox, oy, field_shape, field_codes)
        for h in range(num_humans):
            visible[n, h] = False
            if not human_mask[n, h]:
                continue
            hx, hy = human_pos[n, h, 0], human_pos[n, h, 1]
            known = status[n, h]
            if known == CLEAR:
                moved2 = max(
                    (ox - observer_at[n, h, 0]) ** 2 + (oy - observer_at[n, h, 1]) ** 2,
                    (hx - human_at[n, h, 0]) ** 2 + (hy - human_at[n, h, 1]) ** 2,
                )
                if moved2 >= clearance2[n, h]:
                    known = UNKNOWN
            elif known == BLOCKED:
                w = wall[n, h]
                if not segments_meet(ox, oy, hx, hy, walls[w, 0], walls[w, 1], walls[w, 2], walls[w, 3]):
                    known = UNKNOWN
            if known == UNKNOWN:
                tested += 1
                end = min(end_observer, field_distance(hx, hy, field_shape, field_codes)) - field_slack
                w, clearance = near_sight_line(ox, oy, hx, hy, end, grid, cell_start, cell_walls, walls)
                known = CLEAR if w < 0 else BLOCKED
                clearance = max(clearance - _ROUNDING, 0.0)
                clearance2[n, h] = clearance * clearance
                wall[n, h] = w
                observer_at[n, h, 0], observer_at[n, h, 1] = ox, oy
                human_at[n, h, 0], human_at[n, h, 1] = hx, hy
            status[n, h] = known
            visible[n, h] = known == CLEAR
    return tested
