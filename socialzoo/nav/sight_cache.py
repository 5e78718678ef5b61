"""Robot-human visibility kept from step to step: only sight lines that may have changed are re-tested.

Between two steps a robot and a human move a few centimetres, so most sight lines keep their
answer, and each line carries a certificate that proves it without touching the walls:

- a clear line with clearance c (a lower bound on its distance to every wall) stays clear while
  both of its ends stay within c of where they were when it was tested: every point of the new
  line is then within c of a point of the old one;
- a blocked line stays blocked while it still crosses the wall that blocked it (one segment test).

Every other line (new, expired, or whose human just appeared) is tested exactly with
`socialzoo.nav.visibility.sight_lines`, so the answers are always those of a full test.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from socialzoo.core.geometry import segments_intersect
from socialzoo.core.walls import WallIndex
from socialzoo.nav.distance_field import DistanceField
from socialzoo.nav.visibility import Sight, near_sight_lines, sight_lines

UNKNOWN, CLEAR, BLOCKED = 0, 1, 2
# Taken off every clearance so that rounding in the displacement test cannot matter, m.
_ROUNDING = 1e-9
# More fresh lines than this are tested with the distance-field pieces (see SightCache.visible).
_MANY_FRESH = 256


class SightCache:
    """Which humans each of N observers sees, for an (N, H) grid of sight lines, kept across steps.

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
        status = np.where(human_mask, self.status, UNKNOWN).astype(np.int8)
        moved_observer = observer[:, None, :] - self.observer_at
        moved_human = human_pos - self.human_at
        moved2 = np.maximum(
            moved_observer[..., 0] ** 2 + moved_observer[..., 1] ** 2,
            moved_human[..., 0] ** 2 + moved_human[..., 1] ** 2,
        )
        expired = (status == CLEAR) & (moved2 >= self.clearance2)
        num_humans = status.shape[1]
        blocked = np.flatnonzero(status == BLOCKED)
        if len(blocked):
            wall = self.wall.reshape(-1).take(blocked)
            still = segments_intersect(
                observer.take(blocked // num_humans, axis=0),
                human_pos.reshape(-1, 2).take(blocked, axis=0),
                self.walls.wall_a.take(wall, axis=0),
                self.walls.wall_b.take(wall, axis=0),
            )
            expired.reshape(-1)[blocked[~still]] = True
        self.lines_asked += int(np.count_nonzero(human_mask))
        fresh = np.flatnonzero((status == UNKNOWN) & human_mask)
        stale = np.flatnonzero(expired & human_mask)
        # Many fresh lines (after a reset) are mostly blocked by the first walls they meet, which
        # the pieces of `sight_lines` find without following them further; a few lines, or lines
        # known clear a moment ago, cost less with `near_sight_lines`.
        if len(fresh) > _MANY_FRESH:
            self._retest(fresh, status, observer, human_pos, sight_lines)
            fresh = fresh[:0]
        self._retest(np.concatenate((fresh, stale)), status, observer, human_pos, near_sight_lines)
        self.status = status
        return status == CLEAR

    def _retest(
        self,
        lines: np.ndarray,
        status: np.ndarray,
        observer: np.ndarray,
        human_pos: np.ndarray,
        method: Callable[[np.ndarray, np.ndarray, WallIndex, DistanceField], Sight],
    ) -> None:
        """Test flat line indices `lines` exactly and store their answers and certificates."""
        if len(lines) == 0:
            return
        self.lines_tested += len(lines)
        start = observer.take(lines // status.shape[1], axis=0)
        end = human_pos.reshape(-1, 2).take(lines, axis=0)
        sight = method(start, end, self.walls, self.field)
        status.reshape(-1)[lines] = np.where(sight.clear, CLEAR, BLOCKED)
        clearance = np.maximum(sight.clearance - _ROUNDING, 0.0)
        self.clearance2.reshape(-1)[lines] = clearance**2
        self.wall.reshape(-1)[lines] = sight.wall
        self.observer_at.reshape(-1, 2)[lines] = start
        self.human_at.reshape(-1, 2)[lines] = end
