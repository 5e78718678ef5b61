"""The world's side of recorded people (Scenario.recorded): people who walk their recorded tracks, enter and leave
when they did, react to a robot in a hybrid crowd, and the measures against the recording (docs/recorded.md)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from socialzoo.core.metrics import names as metric_names
from socialzoo.core.state import WorldState
from socialzoo.env.replay_kernels import (
    UNUSED_OCCUPANT,
    account_people,
    account_robots,
    begin_episodes,
    enter_people,
    leave_tracks,
    load_row,
    occupants_now,
    place_people,
    reacting_people,
    reacting_totals,
)
from socialzoo.humans.models import MODEL_IDS, RECORDED_MODELS, REPLAY, PeopleConfig, PeoplePart
from socialzoo.scenarios.recorded_people import NEVER
from socialzoo.scenarios.scenario import Scenario

# The metrics of recorded scenes (socialzoo.core.metrics, source "recorded").
RECORDED_KEYS = metric_names("recorded")
# A time within this of a frame is on it, in frames.
_ON_FRAME = 1e-9


class RecordingError(ValueError):
    """A people spec that needs recorded people on a scenario that has none."""


class ReplayRunner:
    """The recorded people of B rows of R robots and H person slots.

    Time t of a row is its world steps times the world's dt; on a track of frame period dt_r a person is
    at frame f = t / dt_r, its position interpolated linearly between the frames around f and its
    velocity that segment's (so positions and velocities agree), present while both frames are
    recorded (or f is on a recorded frame). Who follows a track (WorldState.human_model REPLAY) and who
    a model walks is the people spec's (socialzoo.humans.models; the rules of replay, hybrid and the
    other models: docs/recorded.md). A person slot may hold several people one after another
    (socialzoo.scenarios.recorded_people.Occupants): each takes the slot at its entry frame, and a
    person a model still walks when the slot's next person enters leaves there. Each step the runner
    writes the followers' positions, velocities and presence after the world step (the models'
    computations for them are discarded), switches reacting people, and lets people leave. Rows
    without a recording cost nothing, and with none in the batch nothing here runs.

    Args:
        config: the people spec and the hybrid people's reaction rule.
        batch_size: B.
        num_robots: R.
        max_humans: H.
        dt: the world step, s.
        collision_distance: robot and person centres nearer than this touch, m.
        robot_visible: whether the people see the robots: hybrid people react only to robots
            they see (an invisible robot leaves them on their tracks, as replay).
    """

    def __init__(
        self,
        config: PeopleConfig,
        batch_size: int,
        num_robots: int,
        max_humans: int,
        dt: float,
        collision_distance: float,
        *,
        robot_visible: bool = True,
    ) -> None:
        b, r, h = batch_size, num_robots, max_humans
        self.parts: tuple[PeoplePart, ...] = config.parts
        # Per part of the spec (and a last entry for empty slots, kind -1): follows its track, may
        # react, the model that walks it off its track (not per row: compaction leaves them be).
        self._per_part: dict[str, np.ndarray] = {
            "follows": np.array([p.model in RECORDED_MODELS for p in self.parts] + [False]),
            "reacts": np.array([p.model == "hybrid" for p in self.parts] + [False]),
            "model": np.array([MODEL_IDS[p.walks_as] for p in self.parts] + [0], dtype=np.int8),
        }
        self._recorded_spec = config.recorded
        self.radius, self.react_time = config.react_radius, config.react_time
        self.dt, self.collision_distance = dt, collision_distance
        self.robot_visible = robot_visible
        self.recorded = np.zeros(b, dtype=bool)
        self.frame_dt = np.ones(b)
        # (B, T, H, 2) each row's recording in its first frame_count frames and people_count slots
        # (what lies beyond is not read: a reset writes only the recording's block). Frame-major:
        # a step reads every slot of a row on one or two frames.
        self.tracks = np.full((b, 1, h, 2), np.nan)
        self.track_vel = np.zeros((b, 1, h, 2))
        self.people_count = np.zeros(b, dtype=np.int64)
        self.frame_count = np.zeros(b, dtype=np.int64)
        # (B, H, L) the frame of each route point (socialzoo.scenarios.recorded_people.route_frames).
        self.route_frame = np.zeros((b, h, 1), dtype=np.int64)
        # (B, H, K) each slot's people, one after another (socialzoo.scenarios.recorded_people.Occupants).
        self.entry = np.full((b, h, 1), NEVER, dtype=np.int64)
        self.exit = np.full((b, h, 1), NEVER, dtype=np.int64)
        self.first = np.zeros((b, h, 1), dtype=np.int64)
        self.last = np.zeros((b, h, 1), dtype=np.int64)
        self.occupant_speed = np.ones((b, h, 1))
        self.shared = np.zeros((b, h), dtype=bool)  # a slot of more than one person
        self.occupant = np.full((b, h), -1, dtype=np.int64)  # who is in each slot now (-1: nobody yet)
        # Per slot, from the people spec: follows its track from entry; may react; the model after.
        self.follows = np.zeros((b, h), dtype=bool)
        self.reacts = np.zeros((b, h), dtype=bool)
        self.then = np.zeros((b, h), dtype=np.int8)
        # The person in each slot now: on its track; walked by a model and gone.
        self.on_track = np.zeros((b, h), dtype=bool)
        self.gone = np.zeros((b, h), dtype=bool)
        self.time_limit = np.full(b, np.inf)
        # Measures of the episode (until the robot's episode ends), the person in each slot now...
        self.elapsed = np.zeros(b)
        self.reacted_at = np.full((b, h), np.nan)
        self.exit_at = np.full((b, h), np.nan)
        self.walked = np.zeros((b, h))
        self.recorded_left = np.zeros((b, h))
        self.recorded_exit = np.zeros((b, h))
        self.rest = np.zeros((b, h))
        # ... and the reacting people who already left their slot: count, time lost, extra distance.
        self.folded = np.zeros((b, 3))
        self.robot_track = np.zeros((b, 1, 2))
        self.robot_track_len = np.zeros(b, dtype=np.int64)
        self.deviation = np.zeros((b, r))
        self.moves = np.zeros((b, r), dtype=np.int64)
        self.contact = np.zeros((b, r, h), dtype=bool)
        self.walked_into = np.zeros((b, r), dtype=np.int64)

    @property
    def active(self) -> bool:
        """Whether any row has recorded people."""
        return bool(self.recorded.any())

    # ------------------------------------------------------------------ reset
    def wanted(self, scenarios: Sequence[Scenario | None]) -> bool:
        """Whether a reset from `scenarios` involves recorded people (a recorded scenario, or a
        spec with replay or hybrid people, which refuses scenarios without them)."""
        return self._recorded_spec or any(s is not None and s.recorded is not None for s in scenarios)

    def reset(
        self, rows: np.ndarray, scenarios: Sequence[Scenario | None], state: WorldState, kinds: np.ndarray
    ) -> None:
        """Load the recordings of `rows` and place their people at time 0 in `state`.

        Args:
            rows: the rows, reset just now in `state`.
            scenarios: one per row (None: a task's own case without recorded people).
            state: the batch's state, its rows written from the scenarios.
            kinds: (len(rows), H) each slot's index into the people spec's parts (-1: empty).

        Raises:
            RecordingError: a replay or hybrid spec on a scenario without recorded people.
        """
        b = len(self.recorded)
        for i, (row, scenario) in enumerate(zip(rows.tolist(), scenarios, strict=True)):
            rec = None if scenario is None else scenario.recorded
            slot_kind = kinds[i]
            if rec is None:
                if self._recorded_spec:
                    name = (
                        "a task's own case"
                        if scenario is None
                        else f"scenario {scenario.family} seed {scenario.seed}"
                    )
                    raise RecordingError(
                        f"people spec {'+'.join(p.name for p in self.parts)!r}: replay and hybrid people "
                        f"need recorded people (a recorded scene's family), {name} has none"
                    )
                self.recorded[row] = False
                self.on_track[row] = False
                continue
            occupants = rec.occupants
            self._widen(
                rec.num_frames, rec.route_frames.shape[1], len(rec.robot_track), occupants.entry.shape[1]
            )
            self.recorded[row] = True
            self.frame_dt[row] = rec.dt
            self.time_limit[row] = rec.time_limit
            self.robot_track_len[row] = len(rec.robot_track)
            self.people_count[row], self.frame_count[row] = rec.num_people, rec.num_frames
            load_row(
                row, rec.tracks, rec.velocities, rec.route_frames, occupants.entry, occupants.exit,
                occupants.first, occupants.last, occupants.speed, occupants.shared, rec.follow, rec.robot_track,
                slot_kind, self._per_part["follows"], self._per_part["reacts"], self._per_part["model"], REPLAY,
                self.tracks, self.track_vel, self.route_frame, self.entry, self.exit, self.first, self.last,
                self.occupant_speed, self.shared, self.follows, self.reacts, self.then, self.robot_track,
            )  # fmt: skip
        fresh = rows[self.recorded[rows]]
        if len(fresh) == 0:
            return
        assert b == state.batch_size
        begin_episodes(
            fresh, self.follows, REPLAY, self.occupant, self.on_track, self.gone, self.reacted_at, self.exit_at,
            self.walked, self.recorded_left, self.recorded_exit, self.rest, self.elapsed, self.folded,
            self.deviation, self.moves, self.walked_into, self.contact, state.human_model,
        )  # fmt: skip
        self._place(state, fresh)

    def _widen(self, frames: int, route: int, robot_track: int, occupants: int) -> None:
        """Grow the frame, route, robot-track and occupant axes to hold a longer recording."""
        have = self.entry.shape[2]
        if occupants > have:
            grow = max(occupants, 2 * have) - have
            for name, fill in UNUSED_OCCUPANT:
                array = getattr(self, name)
                pad = np.full(array.shape[:2] + (grow,), fill, dtype=array.dtype)
                setattr(self, name, np.concatenate((array, pad), 2))
        have = self.tracks.shape[1]
        if frames > have:
            frames = max(frames, 2 * have)  # grow by doubling: a reset rarely reallocates
            b, h = self.tracks.shape[0], self.tracks.shape[2]
            self.tracks = np.concatenate((self.tracks, np.full((b, frames - have, h, 2), np.nan)), 1)
            self.track_vel = np.concatenate((self.track_vel, np.zeros((b, frames - have, h, 2))), 1)
        have = self.route_frame.shape[2]
        if route > have:
            route = max(route, 2 * have)
            self.route_frame = np.concatenate(
                (self.route_frame, np.repeat(self.route_frame[:, :, -1:], route - have, axis=2)), 2
            )
        have = self.robot_track.shape[1]
        if robot_track > have:
            robot_track = max(robot_track, 2 * have)
            self.robot_track = np.concatenate(
                (self.robot_track, np.zeros((len(self.robot_track), robot_track - have, 2))), 1
            )

    # ------------------------------------------------------------------ step
    def settle(self, after: WorldState, robot_vel: np.ndarray) -> None:
        """After a world step: write the followers where their tracks are, switch the hybrid people
        a robot came near to their model, let people enter and leave. `after` is the step's new
        state (its mask, model, waypoint and direction arrays are replaced, not written into).

        Args:
            after: the state after the step.
            robot_vel: (B, R, 2) the robots' velocity vectors after it, m/s.
        """
        rows = np.flatnonzero(self.recorded)
        for name in ("human_mask", "human_model", "human_route_len", "human_pref_speed"):
            setattr(after, name, getattr(after, name).copy())
        frame, weight = self._place(after, rows)
        self._react(after, rows, frame, weight, robot_vel)

    def _place(self, state: WorldState, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions, velocities and presence of `rows`' people at the rows' time (from step_count);
        returns ((len(rows),) the frame each row is on, (len(rows),) how far it is to the next)."""
        n = len(rows)
        t, i0, w = np.empty(n), np.empty(n, dtype=np.int64), np.empty(n)
        # Who is in each slot now; a slot's next person takes it at its entry frame.
        now = np.empty((n, self.tracks.shape[2]), dtype=np.int64)
        new = np.empty(now.shape, dtype=bool)
        if occupants_now(
            rows, state.step_count, self.dt, self.frame_dt, _ON_FRAME, self.entry, self.occupant,
            t, i0, w, now, new,
        ):  # fmt: skip
            self._enter(state, rows, new, now, t)
        place_people(
            rows, i0, w, t, now, new, self.tracks, self.track_vel, self.people_count, self.frame_count,
            self.on_track, self.gone, self.exit_at,
            state.human_direction, state.human_pos, state.human_vel, state.human_mask,
        )  # fmt: skip
        return i0, w

    def _enter(
        self, state: WorldState, rows: np.ndarray, new: np.ndarray, now: np.ndarray, t: np.ndarray
    ) -> None:
        """The people who take their slot now (new (n, H); now: who is in each slot): the one they
        follow is folded into the measures (a reacting person leaves here: its time lost and extra
        distance so far), and the slot follows its track or is walked from its entry along its own
        part of the slot's route."""
        enter_people(
            rows, new, now, t, self.follows, self.then, self.shared, self.first, self.last, self.occupant_speed,
            REPLAY, self.occupant, self.on_track, self.gone, self.reacted_at, self.exit_at, self.walked,
            self.recorded_exit, self.recorded_left, self.rest, self.folded, state.human_model,
            state.human_route_len, state.human_waypoint, state.human_direction, state.human_pref_speed,
        )  # fmt: skip

    def _react(
        self,
        state: WorldState,
        rows: np.ndarray,
        frame: np.ndarray,
        weight: np.ndarray,
        robot_vel: np.ndarray,
    ) -> None:
        """Hybrid people a robot came near leave their tracks (docs/recorded.md gives the rule); frame:
        (len(rows),) the frame each row is on, weight: how far each is to the next."""
        if state.num_robots == 0 or not self.robot_visible:
            return
        react = np.empty((len(rows), state.max_humans), dtype=bool)
        if not reacting_people(
            rows, self.reacts, self.on_track, state.human_mask, self.occupant, state.robot_pose,
            state.human_pos, state.human_vel, robot_vel, self.radius**2, self.react_time,
            self.collision_distance**2, react,
        ):  # fmt: skip
            return
        leave_tracks(
            rows, react, frame, weight, state.step_count, self.dt, self.frame_dt, self.then, self.occupant,
            self.first, self.last, self.route_frame, self.shared, self.exit, self.tracks, self.on_track,
            state.human_model, state.human_route_len, state.human_waypoint, state.human_direction, self.reacted_at,
            self.recorded_exit, self.recorded_left,
        )  # fmt: skip

    # ------------------------------------------------------------------ measures
    def account(
        self, before: WorldState, after: WorldState, robot_vel: np.ndarray, was_done: np.ndarray
    ) -> None:
        """Measure one step of the robots whose episode had not ended before it (was_done (B, R));
        robot_vel: (B, R, 2) the robots' velocity vectors after the step, m/s."""
        rows = np.flatnonzero(self.recorded & ~was_done.all(axis=1))
        if len(rows) == 0:
            return
        live = ~was_done[rows]
        self.elapsed[rows] += self.dt
        account_people(
            rows, self.reacted_at, self.gone, before.human_mask, before.human_pos, after.human_pos,
            after.human_route, after.human_route_len, self.walked, self.rest,
        )  # fmt: skip
        account_robots(
            rows, live, after.robot_pose, after.human_pos, after.human_vel, after.human_mask, robot_vel,
            self.robot_track, self.robot_track_len, self.collision_distance**2,
            self.deviation, self.moves, self.contact, self.walked_into,
        )  # fmt: skip

    def summaries(
        self, rows: np.ndarray | Sequence[int], arrival: Sequence[float], robot: int | np.ndarray = 0
    ) -> list[dict[str, Any]]:
        """The recorded metrics (RECORDED_KEYS) of `rows` for robot `robot` (one for every row, or
        one per row); arrival: each row's time to goal, s (NaN unless the episode succeeded). A row
        without a recording gets an empty dict."""
        rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        robots = np.broadcast_to(np.asarray(robot, dtype=np.intp), rows.shape)
        totals = np.empty((len(rows), 3))
        reacting_totals(
            rows, self.reacted_at, self.exit_at, self.rest, self.elapsed, self.occupant, self.occupant_speed,
            self.recorded_exit, self.walked, self.recorded_left, self.folded, totals,
        )  # fmt: skip
        points = self.robot_track_len[rows]
        person = np.where(points > 0, (points - 1) * self.frame_dt[rows], np.nan)
        moves = self.moves[rows, robots]
        with np.errstate(invalid="ignore", divide="ignore"):
            deviation = np.where((moves > 0) & (points > 1), self.deviation[rows, robots] / moves, np.nan)
        out: list[dict[str, Any]] = []
        for recorded, reached, person_time, deviated, (count, lost, extra), walked_into in zip(
            self.recorded[rows].tolist(),
            arrival,
            person.tolist(),
            deviation.tolist(),
            totals.tolist(),
            self.walked_into[rows, robots].tolist(),
            strict=True,
        ):
            if not recorded:
                out.append({})
                continue
            reached = float(reached)
            out.append(
                {
                    "person_time": person_time,
                    "person_time_ratio": reached / person_time
                    if person_time > 0 and math.isfinite(reached)
                    else math.nan,
                    "person_path_deviation": deviated,
                    "people_reacting": int(count),
                    "people_walked_into_robot": walked_into,
                    "reacting_time_lost": lost / count if count else math.nan,
                    "reacting_extra_distance": extra / count if count else math.nan,
                }
            )
        return out
