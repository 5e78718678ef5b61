"""The recorded side of a scenario (Scenario.recorded): every recorded person's track on the recording's frames,
and the person the robot took the place of (made by socialzoo.scenarios.recorded, played by socialzoo.env.replay)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from socialzoo.core.validation import check_number

# A recorded person's route: its track's points this many seconds apart (4 frames at 2.5 Hz; frames_in),
# and its last.
ROUTE_TIME = 1.6
# A person below this mean speed is given this speed should a model walk it, m/s.
MIN_SPEED = 0.3
# Unused occupant entries (Occupants) hold this frame.
NEVER = np.iinfo(np.int64).max // 4
# Recorded companions: people who enter on the same frame within this distance of each other, m, and with
# velocities within COMPANION_SPEED, m/s, walk as a group ("groups"; the realism study takes a subject's
# companions by the same thresholds).
COMPANION_DISTANCE = 1.2
COMPANION_SPEED = 0.5
# A group of recorded companions has at most this many people (Moussaid et al. 2010: groups of 2 to 4).
MAX_COMPANIONS = 4


def runs(track: np.ndarray) -> list[tuple[int, int]]:
    """The (first, last) frames of each run of frames on which a slot's track is recorded (one
    run per person who occupies the slot; track: (T, 2), NaN absent)."""
    on = ~np.isnan(track[:, 0])
    edges = np.flatnonzero(np.diff(np.concatenate(([0], on.astype(np.int8), [0]))))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def frames_in(seconds: float, dt: float) -> int:
    """The whole number of frames of dt s nearest to `seconds`, at least 1: the recordings' rules are
    in seconds, whatever a file's frame rate."""
    return max(1, round(seconds / dt))


def slot_route(slot_runs: list[tuple[int, int]], stride: int) -> np.ndarray:
    """The frames of the route points of everyone in a slot, from its runs (runs), one person after
    another: each person's first frame, every `stride` frames on, and its last."""
    return np.concatenate([run_route(a, b, stride) for a, b in slot_runs]).astype(np.int64)


def run_route(first: int, last: int, stride: int) -> np.ndarray:
    """The route frames of one person seen on frames first..last: every `stride`-th from its first
    (frames_in(ROUTE_TIME, dt)), and its last."""
    frames = np.arange(first, last + 1, stride)
    return frames if frames[-1] == last else np.append(frames, last)


def path_length(points: np.ndarray) -> float:
    """The length of a path of points (k, 2), m."""
    return float(np.sqrt((np.diff(points, axis=0) ** 2).sum(-1)).sum()) if len(points) > 1 else 0.0


def mean_speed(positions: np.ndarray, dt: float) -> float:
    """A recorded person's mean speed over its positions (k, 2) every dt s, at least MIN_SPEED, m/s:
    the speed a model walks it at."""
    return speed_over(path_length(positions), (len(positions) - 1) * dt)


def speed_over(length: float, time: float) -> float:
    """length / time, at least MIN_SPEED (MIN_SPEED for no time), m/s (mean_speed)."""
    return max(length / time, MIN_SPEED) if time > 0 else MIN_SPEED


def exit_route(start: np.ndarray, exit_: np.ndarray, reach: float) -> np.ndarray:
    """(2, 2) a modelled person's route, m: from its start to `reach` m beyond its exit, on the line from
    the start through the exit (the exit itself if the two coincide).

    A person leaves within the waypoint radius `reach` of its route's end; the end beyond the exit makes
    one that walks towards it leave at its exit, as the recorded person did, not `reach` m short of it
    and held there while the recorded person walks on."""
    way = exit_ - start
    length = float(np.hypot(*way))
    return np.stack((start, exit_ + way * (reach / length) if length > 0 else exit_))


@dataclass(frozen=True)
class Occupants:
    """Who occupies each slot of a RecordedPeople, one after another: (S, K) arrays, K the most
    people of one slot (unused entries at frame NEVER).

    Attributes:
        entry, exit: each person's first and last recorded frame.
        first, last: the indices of its first and last point in its slot's route (slot_route).
        speed: its mean recorded speed (at least MIN_SPEED), m/s.
    """

    entry: np.ndarray
    exit: np.ndarray
    first: np.ndarray
    last: np.ndarray
    speed: np.ndarray

    @cached_property
    def shared(self) -> np.ndarray:
        """(S,) the slots that more than one person occupies."""
        return (self.entry < NEVER).sum(1) > 1


def _frozen(value: Any, dtype: type, ndim: int, what: str) -> np.ndarray:
    arr: np.ndarray = np.array(value, dtype=dtype)
    if arr.ndim != ndim:
        raise ValueError(f"RecordedPeople.{what} must have {ndim} dimensions, got shape {arr.shape}")
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class RecordedPeople:
    """The recorded side of a scenario: everyone's track, and the person the robot replaced.

    Attributes:
        dt: seconds between the tracks' frames.
        tracks: (n, T, 2) the position of each person slot's occupant on frames 0..T-1 (frame 0 at
            the episode's start), m, NaN while absent; a slot holds people one after another
            (each run of recorded frames is one person: Occupants).
        follow: (n,) people who follow their track whatever the people spec says (the recorded
            others when one person's model is measured against its track); default none.
        time_limit: the robot's time budget, s (inf: the task's own).
        robot_track: (T_r, 2) the path of the person the robot replaced, from the episode's start,
            m; (0, 2) when the robot replaced nobody.
        scene: the recording's name.
        first_frame: the recording's frame at the episode's start.
        persons: each person's id in the recording, slot by slot and in each slot in order.
    """

    dt: float
    tracks: np.ndarray
    follow: np.ndarray = None  # type: ignore[assignment]
    time_limit: float = math.inf
    robot_track: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    scene: str = ""
    first_frame: int = 0
    persons: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        check_number("RecordedPeople", "dt", self.dt, low=0.0, low_open=True)
        tracks = _frozen(self.tracks, np.float64, 3, "tracks")
        if tracks.shape[2] != 2 or tracks.shape[1] < 1:
            raise ValueError(f"RecordedPeople.tracks must be (n, T >= 1, 2), got {tracks.shape}")
        if np.isinf(tracks).any():
            raise ValueError("RecordedPeople.tracks must be finite or NaN (absent)")
        present = ~np.isnan(tracks[..., 0])
        if (present != ~np.isnan(tracks[..., 1])).any() or not present.any(axis=1).all():
            raise ValueError(
                "RecordedPeople.tracks: every person is present on some frame, x and y NaN together"
            )
        n = len(tracks)
        object.__setattr__(self, "tracks", tracks)
        follow = np.zeros(n, dtype=bool) if self.follow is None else self.follow
        object.__setattr__(self, "follow", _frozen(follow, bool, 1, "follow"))
        persons = np.arange(n) if self.persons is None else self.persons
        object.__setattr__(self, "persons", _frozen(persons, np.int64, 1, "persons"))
        if len(self.follow) != n:
            raise ValueError(f"RecordedPeople.follow must hold {n} values, got {len(self.follow)}")
        robot_track = _frozen(np.reshape(self.robot_track, (-1, 2)), np.float64, 2, "robot_track")
        if not np.isfinite(robot_track).all():
            raise ValueError("RecordedPeople.robot_track must be finite")
        object.__setattr__(self, "robot_track", robot_track)
        if not (self.time_limit > 0):
            raise ValueError(f"RecordedPeople.time_limit must be > 0, got {self.time_limit!r}")

    @property
    def num_people(self) -> int:
        """n, the recorded people."""
        return len(self.tracks)

    @property
    def num_frames(self) -> int:
        """T, the frames of the tracks."""
        return self.tracks.shape[1]

    @cached_property
    def slot_runs(self) -> tuple[list[tuple[int, int]], ...]:
        """Each slot's (first, last) frames of each person in it, one after another (runs)."""
        return tuple(runs(track) for track in self.tracks)

    @property
    def route_stride(self) -> int:
        """Frames between a person's route points: ROUTE_TIME s (frames_in)."""
        return frames_in(ROUTE_TIME, self.dt)

    @cached_property
    def slot_routes(self) -> tuple[np.ndarray, ...]:
        """Each slot's route frames (slot_route), unpadded."""
        return tuple(slot_route(slot, self.route_stride) for slot in self.slot_runs)

    @cached_property
    def velocities(self) -> np.ndarray:
        """(n, T, 2) each slot's velocity on the segment from each frame to the next (the one before
        it at a person's last frame; 0 for a person seen on one frame only), m/s: what a replayed
        person moves at between frames."""
        tracks = self.tracks
        forward = np.nan_to_num((tracks[:, 1:] - tracks[:, :-1]) / self.dt)  # 0 where an end is absent
        gap = np.isnan(tracks[:, 1:, 0]) | np.isnan(tracks[:, :-1, 0])
        vel = np.zeros(tracks.shape)
        vel[:, :-1] = forward
        last = ~np.isnan(tracks[:, :, 0]) & np.concatenate((gap, np.ones((len(tracks), 1), dtype=bool)), 1)
        back = np.concatenate((np.zeros((len(tracks), 1, 2)), forward), 1)
        return np.where(last[..., None], back, vel)

    @cached_property
    def occupants(self) -> Occupants:
        """Who occupies each slot, one after another (Occupants)."""
        per_slot = self.slot_runs
        width = max((len(r) for r in per_slot), default=1)
        shape = (len(per_slot), width)
        entry, exit_ = np.full(shape, NEVER, dtype=np.int64), np.full(shape, NEVER, dtype=np.int64)
        first, last = np.zeros(shape, dtype=np.int64), np.zeros(shape, dtype=np.int64)
        speed = np.full(shape, MIN_SPEED)
        for s, (track, slot_runs) in enumerate(zip(self.tracks, per_slot, strict=True)):
            # Segment lengths once per slot (NaN across absences); a person's path is its runs' sum.
            segments = np.sqrt((np.diff(track, axis=0) ** 2).sum(-1))
            index = 0
            for k, (a, b) in enumerate(slot_runs):
                points = len(run_route(a, b, self.route_stride))
                entry[s, k], exit_[s, k] = a, b
                first[s, k], last[s, k] = index, index + points - 1
                index += points
                speed[s, k] = speed_over(float(segments[a:b].sum()), (b - a) * self.dt)
        return Occupants(entry, exit_, first, last, speed)

    def companion_groups(self, members: np.ndarray) -> np.ndarray:
        """(n,) the walking group of each slot among the slots `members` (n,) marks (the index of its
        first member, -1: none, as Scenario.human_group): a slot's person and the later slots' people who
        enter on the same frame within COMPANION_DISTANCE of it with velocities within COMPANION_SPEED
        of its own, up to MAX_COMPANIONS in all, in slot order. A slot that more than one person occupies
        walks alone (its next person would inherit the group)."""
        occupants, vel = self.occupants, self.velocities
        entry = occupants.entry[:, 0]
        free = np.asarray(members, dtype=bool) & ~occupants.shared
        group = np.full(self.num_people, -1, dtype=np.int64)
        for s in np.flatnonzero(free).tolist():
            if group[s] >= 0:
                continue
            f = entry[s]
            others = np.flatnonzero(free & (group < 0) & (entry == f) & (np.arange(self.num_people) > s))
            near = np.hypot(*(self.tracks[others, f] - self.tracks[s, f]).T) <= COMPANION_DISTANCE
            alike = np.hypot(*(vel[others, f] - vel[s, f]).T) <= COMPANION_SPEED
            mates = others[near & alike][: MAX_COMPANIONS - 1]
            if len(mates):
                group[s] = s
                group[mates] = s
        return group

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, RecordedPeople):
            return NotImplemented
        values = [(getattr(self, k), getattr(other, k)) for k in ("dt", "time_limit", "scene", "first_frame")]
        arrays = [
            (getattr(self, k), getattr(other, k)) for k in ("tracks", "follow", "robot_track", "persons")
        ]
        return all(a == b for a, b in values) and all(
            a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind == "f") for a, b in arrays
        )

    __hash__ = None  # type: ignore[assignment]

    def to_json(self) -> dict[str, Any]:
        """JSON-ready; absent positions are null, floats exact. "num_frames" keeps T where no track
        does (an episode with nobody else in it)."""
        tracks = np.where(np.isnan(self.tracks), None, self.tracks).tolist()  # type: ignore[call-overload]
        return {
            "dt": self.dt,
            "num_frames": self.num_frames,
            "tracks": tracks,
            "follow": self.follow.tolist(),
            "time_limit": None if math.isinf(self.time_limit) else self.time_limit,
            "robot_track": self.robot_track.tolist(),
            "scene": self.scene,
            "first_frame": self.first_frame,
            "persons": self.persons.tolist(),
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RecordedPeople:
        """Inverse of `to_json` (ValueError or KeyError naming the field on bad data)."""
        tracks = np.array(data["tracks"], dtype=object)
        tracks = np.where(tracks == None, np.nan, tracks).astype(np.float64)  # noqa: E711 (elementwise)
        if "num_frames" in data:
            frames = int(data["num_frames"])
            if tracks.size == 0:  # nobody: [] holds no shape
                tracks = tracks.reshape(0, frames, 2)
            elif tracks.ndim != 3 or tracks.shape[1] != frames:
                raise ValueError(
                    f"RecordedPeople.num_frames is {frames}, but the tracks have shape {tracks.shape}"
                )
        limit = data.get("time_limit")
        return cls(
            dt=float(data["dt"]),
            tracks=tracks,
            follow=np.array(data["follow"], dtype=bool),
            time_limit=math.inf if limit is None else float(limit),
            robot_track=np.array(data["robot_track"], dtype=np.float64).reshape(-1, 2),
            scene=str(data.get("scene", "")),
            first_frame=int(data.get("first_frame", 0)),
            persons=np.array(data["persons"], dtype=np.int64),
        )
