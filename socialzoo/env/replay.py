"""The world's side of recorded people (Scenario.recorded, socialzoo.scenarios.recorded): people who
walk their recorded tracks, enter and leave when they did, and, in a hybrid crowd, react to a robot.

Time t of a row is its world steps times the world's dt; on a track of frame period dt_r a person is
at frame f = t / dt_r, its position interpolated linearly between the frames around f and its
velocity that segment's (so positions and velocities agree), present while both frames are
recorded (or f is on a recorded frame). Who follows a track (WorldState.human_model REPLAY) and who
a model walks is the people spec's (socialzoo.humans.models):

- "replay": every person follows its track, whatever the robot does.
- "hybrid:MODEL": a person follows its track until a robot's centre comes within
  PeopleConfig.react_radius of it, or the two would meet (centres within the world's collision
  distance) within PeopleConfig.react_time keeping their velocities; from then on MODEL walks it
  along the rest of its recorded route (the route point after its current frame on) at its
  recorded mean speed, and it leaves the scene where the route ends. The rule has no randomness.
- any other model: the person enters at its first recorded frame and position and MODEL walks it
  along its route; it leaves where the route ends.

People marked `follow` in the scenario follow their tracks in every case. Each step the runner
writes the followers' positions, velocities and presence after the world step (the models'
computations for them are discarded), switches reacting people, and lets people leave.

It also measures the episode against the recording: the robot against the person it replaced
(its time over the person's, its mean distance to the person's path), the reacting people against
their tracks (time lost and extra distance), and contacts that people walked into. Rows without a
recording cost nothing, and with none in the batch nothing here runs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from socialzoo.core.metrics import names as metric_names
from socialzoo.core.state import WorldState
from socialzoo.humans.models import MODEL_IDS, RECORDED_MODELS, REPLAY, PeopleConfig, PeoplePart
from socialzoo.scenarios.scenario import Scenario

# The metrics of recorded scenes (socialzoo.core.metrics, source "recorded").
RECORDED_KEYS = metric_names("recorded")
# A time within this of a frame is on it, in frames.
_ON_FRAME = 1e-9


class RecordingError(ValueError):
    """A people spec that needs recorded people on a scenario that has none."""


class ReplayRunner:
    """The recorded people of B rows of R robots and H person slots (see the module docstring).

    Args:
        config: the people spec and the hybrid people's reaction rule.
        batch_size: B.
        num_robots: R.
        max_humans: H.
        dt: the world step, s.
        collision_distance: robot and person centres nearer than this touch, m.
    """

    def __init__(
        self,
        config: PeopleConfig,
        batch_size: int,
        num_robots: int,
        max_humans: int,
        dt: float,
        collision_distance: float,
    ) -> None:
        b, r, h = batch_size, num_robots, max_humans
        self.parts: tuple[PeoplePart, ...] = config.parts
        self._recorded_spec = config.recorded
        self.radius, self.react_time = config.react_radius, config.react_time
        self.dt, self.collision_distance = dt, collision_distance
        self.recorded = np.zeros(b, dtype=bool)
        self.frame_dt = np.ones(b)
        self.tracks = np.full((b, h, 1, 2), np.nan)
        self.track_vel = np.zeros((b, h, 1, 2))
        # (B, H, L) the frame of each route point (socialzoo.scenarios.recorded_people.route_frames).
        self.route_frame = np.zeros((b, h, 1), dtype=np.int64)
        self.on_track = np.zeros((b, h), dtype=bool)
        self.reacts = np.zeros((b, h), dtype=bool)
        self.then = np.zeros((b, h), dtype=np.int8)
        self.entered = np.zeros((b, h), dtype=bool)
        self.gone = np.zeros((b, h), dtype=bool)
        self.time_limit = np.full(b, np.inf)
        # Measures of the episode (until the robot's episode ends).
        self.elapsed = np.zeros(b)
        self.reacted_at = np.full((b, h), np.nan)
        self.exit_at = np.full((b, h), np.nan)
        self.walked = np.zeros((b, h))
        self.recorded_left = np.zeros((b, h))
        self.recorded_exit = np.zeros((b, h))
        self.robot_track = np.zeros((b, 1, 2))
        self.robot_track_len = np.zeros(b, dtype=np.int64)
        self.deviation = np.zeros((b, r))
        self.moves = np.zeros((b, r), dtype=np.int64)
        self.contact = np.zeros((b, r, h), dtype=bool)
        self.walked_into = np.zeros((b, r), dtype=np.int64)
        self.rest = np.zeros((b, h))
        self.speed = np.ones((b, h))

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
        recorded_part = np.array([p.model in RECORDED_MODELS for p in self.parts] + [False])
        hybrid_part = np.array([p.model == "hybrid" for p in self.parts] + [False])
        walks_as = np.array([MODEL_IDS[p.walks_as] for p in self.parts] + [0], dtype=np.int8)
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
            n, frames = rec.num_people, rec.num_frames
            self._widen(frames, rec.route_frames.shape[1], len(rec.robot_track))
            self.recorded[row] = True
            self.frame_dt[row] = rec.dt
            self.tracks[row] = np.nan
            self.tracks[row, :n, :frames] = rec.tracks
            self.track_vel[row] = 0.0
            self.track_vel[row, :n, :frames] = _segment_velocities(rec.tracks, rec.dt)
            self.route_frame[row] = 0
            frames_of = rec.route_frames
            self.route_frame[row, :n, : frames_of.shape[1]] = frames_of
            self.route_frame[row, :n, frames_of.shape[1] :] = frames_of[:, -1:]
            kind = slot_kind[:n]
            follow = rec.follow | recorded_part[kind]
            self.on_track[row] = False
            self.on_track[row, :n] = follow
            self.reacts[row] = False
            self.reacts[row, :n] = hybrid_part[kind] & ~rec.follow
            self.then[row] = 0
            self.then[row, :n] = np.where(rec.follow, REPLAY, walks_as[kind])
            state.human_model[row, :n] = np.where(follow, REPLAY, state.human_model[row, :n])
            self.time_limit[row] = rec.time_limit
            self.robot_track[row] = 0.0
            self.robot_track[row, : len(rec.robot_track)] = rec.robot_track
            self.robot_track_len[row] = len(rec.robot_track)
        fresh = rows[self.recorded[rows]]
        if len(fresh) == 0:
            return
        for name in ("entered", "gone", "contact"):
            getattr(self, name)[fresh] = False
        for name in (
            "elapsed",
            "walked",
            "deviation",
            "moves",
            "walked_into",
            "recorded_left",
            "recorded_exit",
        ):
            getattr(self, name)[fresh] = 0
        self.reacted_at[fresh] = np.nan
        self.exit_at[fresh] = np.nan
        assert b == state.batch_size
        self._place(state, fresh, state.human_mask[fresh].copy())

    def _widen(self, frames: int, route: int, robot_track: int) -> None:
        """Grow the frame, route and robot-track axes to hold a longer recording."""
        have = self.tracks.shape[2]
        if frames > have:
            frames = max(frames, 2 * have)  # grow by doubling: a reset rarely reallocates
            self.tracks = np.concatenate(
                (self.tracks, np.full(self.tracks.shape[:2] + (frames - have, 2), np.nan)), 2
            )
            self.track_vel = np.concatenate(
                (self.track_vel, np.zeros(self.track_vel.shape[:2] + (frames - have, 2))), 2
            )
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
        after.human_mask = after.human_mask.copy()
        after.human_model = after.human_model.copy()
        frame = self._place(after, rows, after.human_mask[rows].copy())
        self._react(after, rows, frame, robot_vel)

    def _place(self, state: WorldState, rows: np.ndarray, mask_before: np.ndarray) -> np.ndarray:
        """Positions, velocities and presence of `rows`' people at the rows' time (from step_count);
        returns (len(rows),) the frame each row is on."""
        t = state.step_count[rows] * self.dt
        frame = t / self.frame_dt[rows]
        h, frames = self.tracks.shape[1], self.tracks.shape[2]
        last = frames - 1
        i0 = np.minimum(np.floor(frame + _ON_FRAME).astype(np.int64), last)
        w = np.where(frame - i0 > _ON_FRAME, frame - i0, 0.0)
        i1 = np.minimum(i0 + 1, last)
        # One flat gather per frame: copying the rows' whole tracks would cost more than the step.
        base = (rows[:, None] * h + np.arange(h)[None, :]) * frames  # (n, H)
        flat_tracks = self.tracks.reshape(-1, 2)
        p0 = flat_tracks[base + i0[:, None]]
        p1 = flat_tracks[base + i1[:, None]]
        velocity = self.track_vel.reshape(-1, 2)[base + i0[:, None]]
        on_frame = (w == 0.0)[:, None]
        present = ~np.isnan(p0[..., 0]) & (on_frame | ~np.isnan(p1[..., 0]))
        where = np.where(on_frame[..., None], p0, p0 + w[:, None, None] * (p1 - p0))
        follow = self.on_track[rows]
        # Followers: where their tracks are, present while recorded.
        pos = np.where((follow & present)[..., None], where, state.human_pos[rows])
        vel = np.where((follow & present)[..., None], velocity, state.human_vel[rows])
        mask = np.where(follow, present, mask_before)
        # People a model walks: they enter at their first frame, on their track.
        entering = ~follow & ~self.entered[rows] & present
        pos = np.where(entering[..., None], where, pos)
        vel = np.where(entering[..., None], velocity, vel)
        waypoint = state.human_waypoint[rows]
        direction = state.human_direction[rows]
        waypoint = np.where(entering, np.minimum(1, state.human_route_len[rows] - 1), waypoint)
        direction = np.where(entering, 1, direction)
        walked = ~follow & (self.entered[rows] | entering)
        # ... and leave where their route ends (the route turned them back there).
        leaving = walked & ~self.gone[rows] & (direction < 0)
        gone = self.gone[rows] | leaving
        mask = np.where(~follow, walked & ~gone, mask)
        left_track = follow & self.entered[rows] & ~present & np.isnan(self.exit_at[rows])
        exit_at = self.exit_at[rows]
        exit_at = np.where((leaving | left_track) & np.isnan(exit_at), t[:, None], exit_at)
        self.exit_at[rows] = exit_at
        self.entered[rows] |= present | entering
        self.gone[rows] = gone
        state.human_pos[rows] = pos
        state.human_vel[rows] = vel
        state.human_mask[rows] = mask
        state.human_waypoint[rows] = waypoint
        state.human_direction[rows] = direction
        return i0

    def _react(self, state: WorldState, rows: np.ndarray, frame: np.ndarray, robot_vel: np.ndarray) -> None:
        """Hybrid people a robot came near leave their tracks (see the module docstring); frame:
        (len(rows),) the frame each row is on."""
        watch = self.reacts[rows] & self.on_track[rows] & state.human_mask[rows]
        if not watch.any() or state.num_robots == 0:
            return
        d = state.robot_pose[rows, :, None, :2] - state.human_pos[rows][:, None]  # (n, R, H, 2)
        v = robot_vel[rows][:, :, None] - state.human_vel[rows][:, None]  # relative velocity
        near = (d**2).sum(-1) < self.radius**2
        vv = (v**2).sum(-1)
        when = np.clip(-(d * v).sum(-1) / np.maximum(vv, 1e-12), 0.0, self.react_time)
        closest = d + when[..., None] * v
        meets = (closest**2).sum(-1) < self.collision_distance**2
        react = watch & (near | meets).any(1)
        if not react.any():
            return
        local, slot = np.nonzero(react)
        row = rows[local]
        t = state.step_count[row] * self.dt
        self.on_track[row, slot] = False
        state.human_model[row, slot] = self.then[row, slot]
        # The rest of its recorded route: the first route point after its current frame.
        frames = self.route_frame[row, slot]  # (k, L)
        ahead = (frames <= frame[local][:, None]).sum(-1)
        state.human_waypoint[row, slot] = np.minimum(ahead, state.human_route_len[row, slot] - 1)
        state.human_direction[row, slot] = 1
        self.entered[row, slot] = True
        self.reacted_at[row, slot] = t
        track = self.tracks[row, slot]  # (k, T, 2)
        on = ~np.isnan(track[..., 0])
        last_frame = track.shape[1] - 1 - np.argmax(on[:, ::-1], axis=1)
        self.recorded_exit[row, slot] = last_frame * self.frame_dt[row]
        seg = np.sqrt((np.diff(track, axis=1) ** 2).sum(-1))  # NaN where absent
        after = np.arange(track.shape[1] - 1)[None, :] >= frame[local][:, None]
        ahead_len = np.where(after & ~np.isnan(seg), seg, 0.0).sum(-1)
        self.recorded_left[row, slot] = ahead_len

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
        off_track = ~np.isnan(self.reacted_at[rows]) & ~self.gone[rows]
        step = after.human_pos[rows] - before.human_pos[rows]
        self.walked[rows] += np.where(off_track, np.sqrt((step**2).sum(-1)), 0.0)
        robot = after.robot_pose[rows, :, :2]  # (n, R, 2)
        has_track = self.robot_track_len[rows] > 1
        if has_track.any():
            dist = _polyline_distance(robot, self.robot_track[rows], self.robot_track_len[rows])
            self.deviation[rows] += np.where(live & has_track[:, None], dist, 0.0)
        self.moves[rows] += live
        d = after.human_pos[rows][:, None] - robot[:, :, None]  # robot -> person (n, R, H, 2)
        dist2 = (d**2).sum(-1)
        close = (dist2 < self.collision_distance**2) & after.human_mask[rows][:, None]
        onset = close & ~self.contact[rows]
        if onset.any():
            unit = d / np.maximum(np.sqrt(dist2), 1e-9)[..., None]
            person_in = -(after.human_vel[rows][:, None] * unit).sum(-1)
            robot_in = (robot_vel[rows][:, :, None] * unit).sum(-1)
            self.walked_into[rows] += (onset & (person_in > robot_in) & live[..., None]).sum(-1)
        self.contact[rows] = close
        # What summaries read of an episode that has not ended: the straight way left to each
        # person's route end, and its speed.
        end = np.take_along_axis(
            after.human_route[rows], (after.human_route_len[rows] - 1)[..., None, None].repeat(2, -1), 2
        )[:, :, 0]
        self.rest[rows] = np.sqrt(((end - after.human_pos[rows]) ** 2).sum(-1))
        self.speed[rows] = after.human_pref_speed[rows]

    def summaries(self, rows: np.ndarray, arrival: Sequence[float], robot: int = 0) -> list[dict[str, Any]]:
        """The recorded metrics (RECORDED_KEYS) of `rows` for robot `robot`; arrival: each row's
        time to goal, s (NaN unless the episode succeeded)."""
        out: list[dict[str, Any]] = []
        for row, reached in zip(np.asarray(rows, dtype=np.intp).tolist(), arrival, strict=True):
            if not self.recorded[row]:
                out.append({})
                continue
            person = (
                float((self.robot_track_len[row] - 1) * self.frame_dt[row])
                if self.robot_track_len[row]
                else math.nan
            )
            reacted = ~np.isnan(self.reacted_at[row])
            entry: dict[str, Any] = {
                "person_time": person,
                "person_time_ratio": float(reached) / person
                if person > 0 and math.isfinite(float(reached))
                else math.nan,
                "person_path_deviation": float(self.deviation[row, robot] / self.moves[row, robot])
                if self.moves[row, robot] and self.robot_track_len[row] > 1
                else math.nan,
                "people_reacting": int(reacted.sum()),
                "people_walked_into_robot": int(self.walked_into[row, robot]),
            }
            if reacted.any():
                # Not gone yet: the episode's time plus the straight way left to its exit at its speed.
                exit_at, speed, rest = self.exit_at[row], self.speed[row], self.rest[row]
                done = ~np.isnan(exit_at)
                at = np.where(done, exit_at, self.elapsed[row] + rest / np.maximum(speed, 1e-9))
                extra = np.where(done, 0.0, rest)
                entry["reacting_time_lost"] = float((at - self.recorded_exit[row])[reacted].mean())
                entry["reacting_extra_distance"] = float(
                    (self.walked[row] + extra - self.recorded_left[row])[reacted].mean()
                )
            else:
                entry["reacting_time_lost"] = math.nan
                entry["reacting_extra_distance"] = math.nan
            out.append(entry)
        return out


def _segment_velocities(tracks: np.ndarray, dt: float) -> np.ndarray:
    """(n, T, 2) velocity on the segment from each frame to the next (the one before it at a
    track's last frame; 0 for a person seen on one frame only), m/s."""
    vel = np.zeros(tracks.shape)
    forward = (tracks[:, 1:] - tracks[:, :-1]) / dt  # NaN where either end is absent
    vel[:, :-1] = np.where(np.isnan(forward), 0.0, forward)
    ends = ~np.isnan(tracks[:, :, 0]) & np.concatenate(
        (np.isnan(forward[..., 0]), np.ones((len(tracks), 1), dtype=bool)), 1
    )
    back = np.concatenate((np.zeros((len(tracks), 1, 2)), np.where(np.isnan(forward), 0.0, forward)), 1)
    return np.where(ends[..., None], back, vel)


def _polyline_distance(points: np.ndarray, lines: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(n, R) distance of points (n, R, 2) to each row's polyline lines (n, L, 2) of lengths[i] points."""
    a, b = lines[:, None, :-1], lines[:, None, 1:]  # (n, 1, S, 2)
    ab = b - a
    p = points[:, :, None]
    t = np.clip(((p - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12), 0.0, 1.0)
    dist = np.sqrt(((a + t[..., None] * ab - p) ** 2).sum(-1))  # (n, R, S)
    valid = np.arange(lines.shape[1] - 1)[None, :] < (lengths - 1)[:, None]
    return np.where(valid[:, None], dist, np.inf).min(-1)
