"""The batched world state: a dataclass of numpy arrays with a leading batch axis B (a single env is the batch
of size 1; absent humans are masked out)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from socialzoo.core.jit import kernel


@dataclass
class WorldState:
    """State of B worlds with R robots and up to H humans each.

    All positions and velocities are in the world frame, SI units.

    Attributes:
        robot_pose: (B, R, 3) x, y (m), heading theta (rad).
        robot_vel: (B, R, 2) linear speed v (m/s) and angular speed omega (rad/s).
        robot_goal: (B, R, 3) goal pose x, y (m), theta (rad).
        human_pos: (B, H, 2) position, m.
        human_vel: (B, H, 2) velocity, m/s.
        human_pref_speed: (B, H) preferred (and maximum) walking speed, m/s.
        human_mask: (B, H) True for humans present in the scenario.
        human_route: (B, H, L, 2) route waypoints from start to goal, m; rows padded by repeating
            the last waypoint.
        human_route_len: (B, H) number of valid waypoints in each route (>= 1).
        human_waypoint: (B, H) index of the waypoint the human walks to.
        human_direction: (B, H) +1 walking towards the goal end of the route, -1 back to the start.
        step_count: (B,) physics steps since reset.
        noise_key: (B,) uint64 key of each row's counter-based noise stream (laser noise).
        human_model: (B, H) int8, the model that drives each human (socialzoo.humans.models:
            0 social force, 1 ORCA, 2 a learned policy); default all social force.
        human_group: (B, H) int64, the walking group of each human (the slot of its first
            member), -1 for none; default none.
    """

    robot_pose: np.ndarray
    robot_vel: np.ndarray
    robot_goal: np.ndarray
    human_pos: np.ndarray
    human_vel: np.ndarray
    human_pref_speed: np.ndarray
    human_mask: np.ndarray
    human_route: np.ndarray
    human_route_len: np.ndarray
    human_waypoint: np.ndarray
    human_direction: np.ndarray
    step_count: np.ndarray
    noise_key: np.ndarray
    human_model: np.ndarray = None  # type: ignore[assignment]
    human_group: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        shape = self.human_mask.shape
        if self.human_model is None:
            self.human_model = np.zeros(shape, dtype=np.int8)
        if self.human_group is None:
            self.human_group = np.full(shape, -1, dtype=np.int64)

    @property
    def batch_size(self) -> int:
        """B, the number of worlds."""
        return self.robot_pose.shape[0]

    @property
    def num_robots(self) -> int:
        """R, the robots per world."""
        return self.robot_pose.shape[1]

    @property
    def max_humans(self) -> int:
        """H, the human slots per world (present or not)."""
        return self.human_pos.shape[1]

    @property
    def human_target(self) -> np.ndarray:
        """(B, H, 2) the waypoint each human walks to, m."""
        # A kernel's gather: numpy's take of a flat index (three broadcast index arrays cost more
        # still) took twice as long on a batch step's cold route array. A recorded scene's step
        # gathers its model-moved people's in socialzoo.humans.people.step_people_packed's packing.
        target = np.empty(self.human_waypoint.shape + (2,), dtype=self.human_route.dtype)
        _waypoint_points(self.human_route, self.human_waypoint, target)
        return target

    def copy(self) -> WorldState:
        """Deep copy of every array."""
        return WorldState(**{f.name: getattr(self, f.name).copy() for f in dataclasses.fields(self)})

    def rows(self, index: np.ndarray | slice | int) -> WorldState:
        """The sub-batch at `index` (copies): a row, a slice, row indices or a (B,) mask."""
        if isinstance(index, int):
            index = slice(index, index + 1)
        if isinstance(index, slice):
            return WorldState(**{name: getattr(self, name)[index].copy() for name in _FIELDS})
        # An index array's take is a copy already, and cheaper than indexing (the observations of a
        # batch's reset rows take them on every reset).
        index = np.asarray(index)
        if index.dtype == np.bool_:
            index = np.flatnonzero(index)
        return WorldState(**{name: getattr(self, name).take(index, axis=0) for name in _FIELDS})

    def set_rows(self, index: np.ndarray | slice, other: WorldState) -> None:
        """Overwrite rows at `index` with `other`'s rows, padding human axes where they differ; the
        route axis of every row first widens to `other`'s where that is longer."""
        self.widen_routes(other.human_route.shape[2])
        for f in dataclasses.fields(self):
            dst = getattr(self, f.name)
            src = getattr(other, f.name)
            if dst.shape[1:] != src.shape[1:]:
                src = pad_to(src, dst.shape[1:], f.name)
            dst[index] = src

    def widen_routes(self, length: int) -> None:
        """Widen the route axis of every row to `length` points where it is shorter (repeating
        each route's last point, pad_to)."""
        route = self.human_route
        if length > route.shape[2]:
            self.human_route = pad_to(route, (route.shape[1], length, 2), "human_route")

    @staticmethod
    def concatenate(states: list[WorldState]) -> WorldState:
        """Stack states along the batch axis, padding human and route axes to the largest."""
        out = {}
        for f in dataclasses.fields(WorldState):
            arrays = [getattr(s, f.name) for s in states]
            shape = tuple(max(a.shape[i] for a in arrays) for i in range(1, arrays[0].ndim))
            out[f.name] = np.concatenate([pad_to(a, shape, f.name) for a in arrays], axis=0)
        return WorldState(**out)


# The state's fields, in order (dataclasses.fields builds them anew on every call).
_FIELDS = tuple(f.name for f in dataclasses.fields(WorldState))


def pad_to(array: np.ndarray, shape: tuple[int, ...], name: str) -> np.ndarray:
    """Pad the non-batch axes of a state array up to `shape`.

    Human axes are padded with absent humans (mask False); route axes repeat the last waypoint
    so that a padded route is still a valid route.
    """
    if array.shape[1:] == shape:
        return array
    if any(have > want for have, want in zip(array.shape[1:], shape, strict=True)):
        raise ValueError(f"cannot shrink state field {name} from {array.shape[1:]} to {shape}")
    if name == "human_route" and array.shape[1] == shape[0]:
        # Only the route axis grows (every reset of rows with shorter routes): np.pad's edge mode
        # by two writes, without its general machinery.
        have = array.shape[2]
        out = np.empty(array.shape[:1] + shape, dtype=array.dtype)
        out[:, :, :have] = array
        out[:, :, have:] = array[:, :, have - 1 : have]
        return out
    widths = [(0, 0)] + [(0, want - have) for have, want in zip(array.shape[1:], shape, strict=True)]
    if name == "human_route":
        return np.pad(array, widths, mode="edge")
    fill = 1 if name in ("human_route_len", "human_direction") else (-1 if name == "human_group" else 0)
    return np.pad(array, widths, mode="constant", constant_values=fill)


@kernel
def _waypoint_points(route, waypoint, out):  # type: ignore[no-untyped-def]
    """WorldState.human_target into out (B, H, 2): route (B, H, L, 2) at each waypoint (B, H)."""
    for b in range(waypoint.shape[0]):
        for h in range(waypoint.shape[1]):
            w = waypoint[b, h]
            out[b, h, 0], out[b, h, 1] = route[b, h, w, 0], route[b, h, w, 1]
