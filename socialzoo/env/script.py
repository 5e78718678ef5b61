"""The world's side of scenario scripts (socialzoo.scenarios.script): waiting and signalling people, people who
follow a robot, robots that escort a person, and doors."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from socialzoo.core.state import WorldState
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.script import (
    ACCOMPANY,
    ARRIVE_RADIUS,
    ESCORT_GRACE,
    ESCORT_SHARE,
    FOLLOW,
    LEAD,
    REACH,
    SLOW_DISTANCE,
    STOP_RADIUS,
)

# A released person keeps signalling until it is this far from its stop point, m.
SIGNAL_RADIUS = 3.0
# The per-person fields a script sets (Script's arrays of the same names).
_PERSON_FIELDS = ("stop", "release", "wait", "gate", "gesture", "follow", "gap", "stay")
# Each field's value in a row without a script (ScriptRunner._clear).
_EMPTY = (
    ("released", False), ("reached", False), ("reached_at", np.inf), ("signal", 0),
    ("stop", -1), ("release", np.inf), ("wait", np.inf), ("gate", np.nan), ("gesture", 0),
    ("follow", -1), ("gap", 0.0), ("stay", False),
    ("escort", -1), ("escort_kind", REACH), ("band", 0.0), ("doors", 0.0),
    ("escort_axis", 0.0), ("escort_time", 0.0), ("escort_out", 0.0), ("escort_stretch", 0.0),
    ("escort_lost", False),
)  # fmt: skip


class ScriptRunner:
    """The scripts of B rows of R robots and H person slots (below).

    People who wait at a point until a time or a robot's passing and signal meanwhile, people who
    walk after a robot, robots that escort a person, and doors that open and close on a schedule.

    The core (socialzoo.env.core.BatchedCore) asks `ScriptRunner` for the preferred speeds of a
    step (`speeds`), lets the world step, then `settle`s the step: waiting people keep heading for
    their stop point, releases and signals are updated, each escort's record is kept (whether its
    person is in its place, Script's docstring), and a robot touching a closed door collides. Rows
    without a script cost nothing; with no script in the batch nothing here runs, so unscripted
    episodes are the world's exact steps.

    A waiting person slows down within SLOW_DISTANCE of its stop point (its preferred speed scaled
    by the distance left) and stands within STOP_RADIUS of it (socialzoo.scenarios.script's
    constants); a person following a robot slows the same way within SLOW_DISTANCE of its gap and
    stands inside the gap. People's speed is capped at their preferred speed
    (socialzoo.humans.motion), so a standing person is not pushed about.

    Args:
        batch_size: B.
        num_robots: R.
        max_humans: H.
        dt: the world step, s.
        door_reach: a robot whose centre is nearer than this to a closed door touches it, m (its
            disc radius, or the half-width of a rectangular footprint).
    """

    def __init__(
        self, batch_size: int, num_robots: int, max_humans: int, dt: float, door_reach: float
    ) -> None:
        b, r, h = batch_size, num_robots, max_humans
        self.dt, self.door_reach = dt, door_reach
        self.scripted = np.zeros(b, dtype=bool)
        self.stop = np.full((b, h), -1, dtype=np.int64)
        self.release = np.full((b, h), np.inf)
        self.wait = np.full((b, h), np.inf)
        self.stay = np.zeros((b, h), dtype=bool)
        # (B, H) when each person came to stand at its stop, s (inf: not yet).
        self.reached_at = np.full((b, h), np.inf)
        self.gate = np.full((b, h, 4), np.nan)
        self.gesture = np.zeros((b, h), dtype=np.int8)
        self.follow = np.full((b, h), -1, dtype=np.int64)
        self.gap = np.zeros((b, h))
        self.released = np.zeros((b, h), dtype=bool)
        self.reached = np.zeros((b, h), dtype=bool)
        self.escort = np.full((b, r), -1, dtype=np.int64)
        self.escort_kind = np.zeros((b, r), dtype=np.int64)
        self.band = np.zeros((b, r, 2))
        # (B, R, 2) each escorting robot's way: the unit vector from its start to its goal.
        self.escort_axis = np.zeros((b, r, 2))
        # (B, R) each escort's time so far, its time with the person out of its place, and the
        # current stretch out of it, s; and whether the escort is lost (Script's docstring).
        self.escort_time = np.zeros((b, r))
        self.escort_out = np.zeros((b, r))
        self.escort_stretch = np.zeros((b, r))
        self.escort_lost = np.zeros((b, r), dtype=bool)
        self.doors = np.zeros((b, 0, 6))
        # (B, H) the gesture each person shows now (0: none), observed by the robots.
        self.signal = np.zeros((b, h), dtype=np.int8)
        # (B, D) each door closed now.
        self.closed = np.zeros((b, 0), dtype=bool)

    @property
    def active(self) -> bool:
        """Whether any row has a script."""
        return bool(self.scripted.any())

    # ------------------------------------------------------------------ reset
    def reset(self, rows: np.ndarray, scenarios: Sequence[Scenario | None], state: WorldState) -> None:
        """Load the scripts of `rows` (None or unscripted: nothing scripted) into their slots."""
        scripts = [s.script for s in scenarios if s is not None and s.script is not None]
        if not scripts and not self.active:  # nothing scripted before or after (every recorded scene's reset)
            return
        h = self.stop.shape[1]
        most_doors = max([len(script.doors) for script in scripts] + [0])
        if most_doors > self.doors.shape[1]:
            grown = np.zeros((len(self.doors), most_doors, 6))
            grown[..., 4:] = np.inf  # padding doors are never closed: open from 0 to forever
            grown[..., 4] = -np.inf
            grown[:, : self.doors.shape[1]] = self.doors
            self.doors = grown
            self.closed = np.zeros(grown.shape[:2], dtype=bool)
        self._clear(rows)
        for row, scenario in zip(rows.tolist(), scenarios, strict=True):
            script = None if scenario is None else scenario.script
            if script is None:
                continue
            self.scripted[row] = True
            n = script.num_humans
            for name in _PERSON_FIELDS:
                getattr(self, name)[row, :n] = getattr(script, name)
            r = min(script.num_robots, self.escort.shape[1])
            self.escort[row, :r] = script.escort[:r]
            self.escort_kind[row, :r] = script.escort_kind[:r]
            self.band[row, :r] = script.band[:r]
            self.doors[row, : len(script.doors)] = script.doors
            if h and n:
                self._hold_waypoints(state, np.array([row]))
                self._follow_routes(state, np.array([row]))
        if self.active:
            self._update(state, rows)
            way = state.robot_goal[rows, :, :2] - state.robot_pose[rows, :, :2]
            length = np.hypot(way[..., 0], way[..., 1])[..., None]
            escorting = (self.escort[rows] >= 0)[..., None] & (length > 0.0)
            self.escort_axis[rows] = np.where(escorting, way / np.maximum(length, 1e-12), 0.0)

    def _clear(self, rows: np.ndarray) -> None:
        """Empty `rows`' scripts, all at once (what a script in which nobody waits, follows or
        escorts, and with no doors, holds); `reset` then writes the scripted rows' own. Rows that
        held no script are empty already (only scripted rows are written, and a step leaves an
        empty row empty), so a reset of unscripted rows writes nothing."""
        if not self.scripted[rows].any():
            return
        self.scripted[rows] = False
        for name, fill in _EMPTY:
            getattr(self, name)[rows] = fill
        self.doors[rows, :, 4], self.doors[rows, :, 5] = -np.inf, np.inf  # padding doors: open for ever

    # ------------------------------------------------------------------ step
    def speeds(self, state: WorldState) -> np.ndarray:
        """(B, H) the preferred speeds of the next step: slowed or zero for waiting people near their
        stop point and following people near their robot (the state's own where nothing waits)."""
        pref = state.human_pref_speed
        waiting = self._waiting(state)
        staying = self.stay & state.human_mask & self.scripted[:, None]
        following = (self.follow >= 0) & state.human_mask & self.scripted[:, None]
        if not (waiting.any() or staying.any() or following.any()):
            return pref
        target = state.human_target
        dist = np.hypot(*(target - state.human_pos).transpose(2, 0, 1))
        factor = np.ones(pref.shape)
        at_stop = np.clip(dist / SLOW_DISTANCE, 0.0, 1.0) * (dist >= STOP_RADIUS)
        at_end = staying & ~waiting & (state.human_waypoint == state.human_route_len - 1)
        factor = np.where((waiting & (state.human_waypoint == self.stop)) | at_end, at_stop, factor)
        at_gap = np.clip((dist - self.gap) / SLOW_DISTANCE, 0.0, 1.0)
        factor = np.where(following, at_gap, factor)
        return pref * factor

    def settle(self, before: WorldState, after: WorldState) -> np.ndarray:
        """After a world step from `before`: keep the step's true preferred speeds, hold waiting people
        on their stop point, move followers' routes to their robots, update releases and signals.

        Returns:
            (B, R) robots touching a closed door after the step.
        """
        after.human_pref_speed = before.human_pref_speed
        rows = np.flatnonzero(self.scripted)
        self._update(after, rows)
        self._hold_waypoints(after, rows, before)
        self._follow_routes(after, rows)
        self._keep_escorts(after)
        return self.door_contacts(after)

    def door_contacts(self, state: WorldState) -> np.ndarray:
        """(B, R) robots whose centre is within door_reach of a door closed now."""
        return self.closed_door_distances(state) < self.door_reach

    def closed_door_distances(self, state: WorldState) -> np.ndarray:
        """(B, R) each robot centre's distance to the nearest door closed now, m (inf: none closed)."""
        if self.doors.shape[1] == 0:
            return np.full(state.robot_pose.shape[:2], np.inf)
        pos = state.robot_pose[:, :, None, :2]  # (B, R, 1, 2)
        a, b = self.doors[:, None, :, 0:2], self.doors[:, None, :, 2:4]  # (B, 1, D, 2)
        ab = b - a
        t = np.clip(((pos - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12), 0.0, 1.0)
        dist = np.hypot(*(a + t[..., None] * ab - pos).transpose(3, 0, 1, 2))  # (B, R, D)
        return np.where(self.closed[:, None, :], dist, np.inf).min(-1)

    # ------------------------------------------------------------------ robots
    def escort_in_place(self, state: WorldState) -> np.ndarray:
        """(B, R) whether each escorting robot's person is in its place now: within the band and
        ahead of the robot (FOLLOW), behind it (LEAD) or beside it (ACCOMPANY), within 45 degrees,
        in the frame of the robot's way (Script's docstring); False for robots that escort no one."""
        person = np.maximum(self.escort, 0)
        where = np.take_along_axis(state.human_pos, person[..., None], axis=1)  # (B, R, 2)
        offset = where - state.robot_pose[..., :2]
        dist = np.hypot(offset[..., 0], offset[..., 1])
        axis = self.escort_axis
        along = (offset * axis).sum(-1)
        across = np.abs(offset[..., 0] * axis[..., 1] - offset[..., 1] * axis[..., 0])
        kind = self.escort_kind
        placed = np.where(
            kind == FOLLOW, along > across, np.where(kind == LEAD, -along > across, across >= np.abs(along))
        )
        placed &= np.isin(kind, (FOLLOW, LEAD, ACCOMPANY))
        inside = (dist >= self.band[..., 0]) & (dist <= self.band[..., 1])
        return (self.escort >= 0) & inside & placed

    def escort_ok(self, state: WorldState) -> np.ndarray:
        """(B, R) whether each robot may count its goal as reached: its escorted person in its place
        now and its escort not lost (Script's docstring; robots that escort no one: always)."""
        kept = ~self.escort_lost & (self.escort_out <= (1.0 - ESCORT_SHARE) * self.escort_time + 1e-9)
        return (self.escort < 0) | (self.escort_in_place(state) & kept)

    # ------------------------------------------------------------------ internals
    def _keep_escorts(self, state: WorldState) -> None:
        """Count the step into each escort's record (its time, its time and stretch out of place,
        lost after a stretch longer than ESCORT_GRACE), after a world step to `state`."""
        escorting = self.escort >= 0
        if not escorting.any():
            return
        out = escorting & ~self.escort_in_place(state)
        self.escort_time += np.where(escorting, self.dt, 0.0)
        self.escort_out += np.where(out, self.dt, 0.0)
        self.escort_stretch = np.where(out, self.escort_stretch + self.dt, 0.0)
        self.escort_lost |= self.escort_stretch > ESCORT_GRACE + 1e-9

    def _waiting(self, state: WorldState) -> np.ndarray:
        """(B, H) people of scripted rows who wait at their stop, not released yet."""
        return (self.stop >= 0) & ~self.released & state.human_mask & self.scripted[:, None]

    def _update(self, state: WorldState, rows: np.ndarray) -> None:
        """Releases (time, gates), arrivals at stop points, signals and door states of `rows`."""
        if len(rows) == 0:
            return
        now = state.step_count[rows, None] * self.dt  # (k, 1)
        gate = self.gate[rows]  # (k, H, 4)
        robots = state.robot_pose[rows, :, :2]  # (k, R, 2)
        side = ((robots[:, None, :, :] - gate[:, :, None, :2]) * gate[:, :, None, 2:]).sum(-1)  # (k, H, R)
        passed = np.nan_to_num(side, nan=-1.0).max(-1) > 0
        self.released[rows] |= (now >= self.release[rows]) | passed
        stop = np.maximum(self.stop[rows], 0)
        route = state.human_route[rows]  # (k, H, L, 2)
        stop_point = np.take_along_axis(route, stop[..., None, None].repeat(2, -1), axis=2)[:, :, 0]
        close = np.hypot(*(stop_point - state.human_pos[rows]).transpose(2, 0, 1)) < ARRIVE_RADIUS
        at_stop = (self.stop[rows] >= 0) & (state.human_waypoint[rows] <= self.stop[rows] + 1)
        self.reached[rows] |= close & at_stop
        # The wait clock runs from when the person stands (within STOP_RADIUS, where it stops).
        dist = np.hypot(*(stop_point - state.human_pos[rows]).transpose(2, 0, 1))
        standing = (dist < STOP_RADIUS) & at_stop & np.isinf(self.reached_at[rows])
        self.reached_at[rows] = np.where(standing, now, self.reached_at[rows])
        self.released[rows] |= now >= self.reached_at[rows] + self.wait[rows]
        near = np.hypot(*(stop_point - state.human_pos[rows]).transpose(2, 0, 1)) < SIGNAL_RADIUS
        showing = self.reached[rows] & (~self.released[rows] | near) & state.human_mask[rows]
        self.signal[rows] = np.where(showing, self.gesture[rows], 0)
        doors = self.doors[rows]
        self.closed[rows] = (now < doors[..., 4]) | (now >= doors[..., 5])

    def _hold_waypoints(self, state: WorldState, rows: np.ndarray, before: WorldState | None = None) -> None:
        """Waiting people who reached their stop keep heading for it (the world advances a waypoint
        within its reach radius, short of the stop point itself, and turns a person round at its
        route's end), and people who stay keep heading for their route's end."""
        waypoint, direction = state.human_waypoint[rows], state.human_direction[rows]
        stop = self.stop[rows]
        left = waypoint > stop
        if before is not None:  # it headed for its stop before the step (the world moved it on, or back)
            left |= (before.human_waypoint[rows] == stop) & (waypoint != stop)
        waiting = self._waiting(state)[rows] & left
        last = state.human_route_len[rows] - 1
        staying = self.stay[rows] & ~self._waiting(state)[rows] & ((direction < 0) | (waypoint > last))
        if waiting.any() or staying.any():
            target = np.where(waiting, stop, np.where(staying, last, waypoint))
            state.human_waypoint[rows] = target
            state.human_direction[rows] = np.where(waiting | staying, 1, direction)

    def _follow_routes(self, state: WorldState, rows: np.ndarray) -> None:
        """The route of each person who follows a robot: the robot's position (every route point)."""
        follow = self.follow[rows]
        if not (follow >= 0).any():
            return
        k, p = np.nonzero(follow >= 0)
        row = rows[k]
        state.human_route[row, p] = state.robot_pose[row, follow[k, p], None, :2]
        state.human_route_len[row, p] = 1
        state.human_waypoint[row, p] = 0
