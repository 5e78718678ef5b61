"""The world's side of recorded people (Scenario.recorded): people who walk their recorded tracks, enter and leave
when they did, react to a robot in a hybrid crowd, and the measures against the recording (docs/recorded.md)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from socialzoo.core.metrics import names as metric_names
from socialzoo.core.state import WorldState
from socialzoo.env.recording_bank import PATH_CHUNK, RecordingBank
from socialzoo.env.replay_kernels import (
    account_step,
    begin_episodes,
    row_measures,
    settle_rows,
)
from socialzoo.humans.models import MODEL_IDS, RECORDED_MODELS, REPLAY, PeopleConfig, PeoplePart
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
        contacts_in_step: people_walked_into_robot counts the contacts of the CrowdNav task's
            judgement (the closest approach during a step, socialzoo.env.crowd_outcome) instead of
            the world's at the steps' ends.
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
        contacts_in_step: bool = False,
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
        self.robot_visible, self.contacts_in_step = robot_visible, contacts_in_step
        self.recorded = np.zeros(b, dtype=bool)
        self.frame_dt = np.ones(b)
        # Each row's recording: a pointer into the recordings the rows play, each stored once (a reset
        # copies nothing of it).
        self.bank = RecordingBank(b)
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
        """Point `rows` at their recordings (the bank's, adding those it lacks) and place their people
        at time 0 in `state`.

        Args:
            rows: the rows, reset just now in `state`.
            scenarios: one per row (None: a task's own case without recorded people).
            state: the batch's state, its rows written from the scenarios.
            kinds: (len(rows), H) each slot's index into the people spec's parts (-1: empty).

        Raises:
            RecordingError: a replay or hybrid spec on a scenario without recorded people.
        """
        recordings = [None if s is None else s.recorded for s in scenarios]
        missing = [k for k, r in enumerate(recordings) if r is None]
        if self._recorded_spec and missing:
            scenario = scenarios[missing[0]]
            name = (
                "a task's own case"
                if scenario is None
                else f"scenario {scenario.family} seed {scenario.seed}"
            )
            raise RecordingError(
                f"people spec {'+'.join(p.name for p in self.parts)!r}: replay and hybrid people "
                f"need recorded people (a recorded scene's family), {name} has none"
            )
        entries = self.bank.point(rows, recordings)
        fresh = rows
        if missing:  # a task's own cases among them (a recorded scene's rows all have recordings)
            has = entries >= 0
            self.recorded[rows[~has]] = False
            self.on_track[rows[~has]] = False
            self.time_limit[rows[~has]] = np.inf  # the task's own budget, not a recording's of before
            fresh, entries, kinds = rows[has], entries[has], kinds[has]
            if len(fresh) == 0:
                return
        self.recorded[fresh] = True
        assert len(self.recorded) == state.batch_size
        self.frame_dt[fresh] = self.bank.dt[entries]
        self.time_limit[fresh] = self.bank.time_limit[entries]
        bank = self.bank
        begin_episodes(
            fresh, kinds, bank.slot_at, bank.people, bank.follow, self._per_part["follows"],
            self._per_part["reacts"], self._per_part["model"], REPLAY, self.follows, self.reacts, self.then,
            self.occupant, self.on_track, self.gone, self.reacted_at, self.exit_at, self.walked, self.recorded_left,
            self.recorded_exit, self.rest, self.elapsed, self.folded, self.deviation, self.moves, self.walked_into,
            self.contact, state.human_model,
        )  # fmt: skip
        # The robots' velocity state stands in for their velocity vectors: nobody reacts at time 0.
        self._settle(state, fresh, state.robot_vel, react=False)

    def release(self, rows: np.ndarray) -> None:
        """`rows` start episodes without recorded people (their recordings may be forgotten)."""
        self.recorded[rows] = False
        self.time_limit[rows] = np.inf  # the task's own budget, not a recording's of before
        self.bank.release(rows)

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
        self._settle(after, rows, robot_vel, react=after.num_robots > 0 and self.robot_visible)

    def _settle(self, state: WorldState, rows: np.ndarray, robot_vel: np.ndarray, *, react: bool) -> None:
        """`rows`' people at the rows' time (from step_count), in place in `state`: who is in each slot
        (a slot's next person takes it at its entry frame: the one it follows is folded into the
        measures), their positions, velocities and presence, and with `react` the hybrid people a robot
        came near leaving their tracks (docs/recorded.md gives the rule; robot_vel (B, R, 2), the robots'
        velocity vectors, m/s, read only then)."""
        bank = self.bank
        settle_rows(
            rows, state.step_count, self.dt, self.frame_dt, _ON_FRAME, react, self.radius**2, self.react_time,
            self.collision_distance**2, REPLAY, bank.slot_at, bank.people, bank.point_at, bank.frames,
            bank.occupants_at, bank.occupants, bank.shared, bank.route_at, bank.route_points, bank.entry, bank.exit,
            bank.first, bank.last, bank.speed, bank.route_frame, bank.pos, bank.vel, self.follows, self.reacts,
            self.then, self.occupant, self.on_track, self.gone, self.reacted_at, self.exit_at, self.walked,
            self.recorded_exit, self.recorded_left, self.rest, self.folded, state.human_pos, state.human_vel,
            state.human_mask, state.human_model, state.human_route_len, state.human_waypoint, state.human_direction,
            state.human_pref_speed, state.robot_pose, robot_vel,
        )  # fmt: skip

    # ------------------------------------------------------------------ measures
    def account(
        self, before: WorldState, after: WorldState, robot_vel: np.ndarray, was_done: np.ndarray
    ) -> None:
        """Measure one step of the robots whose episode had not ended before it (was_done (B, R));
        robot_vel: (B, R, 2) the robots' velocity vectors after the step, m/s."""
        bank = self.bank
        account_step(
            self.recorded, was_done, self.dt, after.step_count, bank.people, self.elapsed, self.reacted_at,
            self.gone, self.exit_at, before.human_mask, before.human_pos, after.human_pos, after.human_route,
            after.human_route_len, self.walked, self.rest, after.robot_pose, after.human_vel, after.human_mask,
            robot_vel, bank.robot_at, bank.robot_points, bank.robot, bank.robot_box, PATH_CHUNK,
            self.collision_distance**2, self.deviation, self.moves, self.contact, self.walked_into,
            self.contacts_in_step, before.robot_pose, before.human_vel, self.collision_distance,
        )  # fmt: skip

    def summaries(
        self, rows: np.ndarray | Sequence[int], arrival: Sequence[float], robot: int | np.ndarray = 0
    ) -> list[dict[str, Any]]:
        """The recorded metrics (RECORDED_KEYS) of `rows` for robot `robot` (one for every row, or
        one per row); arrival: each row's time to goal, s (NaN unless the episode succeeded). A row
        without a recording gets an empty dict."""
        rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        robots = np.asarray(robot, dtype=np.intp)
        # The task passes one robot per row; np.broadcast_to cost more than the kernel's work.
        robots = np.full(rows.shape, robots) if robots.ndim == 0 else robots.reshape(rows.shape)
        measures = np.empty((len(rows), 6))
        bank = self.bank
        row_measures(
            rows, robots, self.reacted_at, self.exit_at, self.rest, self.elapsed, self.occupant, bank.slot_at,
            bank.people, bank.occupants_at, bank.speed, self.recorded_exit, self.walked, self.recorded_left,
            self.folded, self.frame_dt, bank.robot_points, self.deviation, self.moves, self.walked_into, measures,
        )  # fmt: skip
        out: list[dict[str, Any]] = []
        for recorded, reached, (count, lost, extra, person_time, deviated, walked_into) in zip(
            self.recorded[rows].tolist(), arrival, measures.tolist(), strict=True
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
                    "people_walked_into_robot": int(walked_into),
                    "reacting_time_lost": lost / count if count else math.nan,
                    "reacting_extra_distance": extra / count if count else math.nan,
                }
            )
        return out
