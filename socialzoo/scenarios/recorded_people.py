"""The recorded side of a scenario (Scenario.recorded): every recorded person's track on the
recording's frames, and the person the robot took the place of (socialzoo.scenarios.recorded makes
them from a recording; socialzoo.env.replay plays them)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from socialzoo.core.validation import check_number

# A recorded person's route: its track's points this many frames apart (1.6 s at 2.5 Hz), and its last.
ROUTE_STRIDE = 4


def route_frames(track: np.ndarray) -> np.ndarray:
    """The frames of a recorded person's route points: its first present frame, every ROUTE_STRIDE
    frames on, and its last present frame, those where it is present (track: (T, 2), NaN absent)."""
    on = np.flatnonzero(~np.isnan(track[:, 0]))
    frames = np.unique(np.concatenate((on[0] + np.arange(0, on[-1] - on[0] + 1, ROUTE_STRIDE), on[-1:])))
    return frames[~np.isnan(track[frames, 0])]


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
        tracks: (n, T, 2) each person's position on frames 0..T-1 (frame 0 at the episode's start),
            m, NaN while absent; one track per person of the scenario, in its order.
        follow: (n,) people who follow their track whatever the people spec says (the recorded
            others when one person's model is measured against its track); default none.
        time_limit: the robot's time budget, s (inf: the task's own).
        robot_track: (T_r, 2) the path of the person the robot replaced, from the episode's start,
            m; (0, 2) when the robot replaced nobody.
        scene: the recording's name.
        first_frame: the recording's frame at the episode's start.
        persons: (n,) each person's id in the recording.
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
        for name in ("follow", "persons"):
            if len(getattr(self, name)) != n:
                raise ValueError(
                    f"RecordedPeople.{name} must hold {n} values, got {len(getattr(self, name))}"
                )
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

    @property
    def present(self) -> np.ndarray:
        """(n, T) whether each person is on the scene at each frame."""
        return ~np.isnan(self.tracks[..., 0])

    @cached_property
    def route_frames(self) -> np.ndarray:
        """(n, L) the frames of each person's route points (route_frames), padded by repeating its last."""
        frames = [route_frames(track) for track in self.tracks]
        width = max((len(f) for f in frames), default=1)
        out = np.zeros((len(frames), width), dtype=np.int64)
        for k, f in enumerate(frames):
            out[k, : len(f)] = f
            out[k, len(f) :] = f[-1]
        return out

    @property
    def robot_time(self) -> float:
        """The replaced person's recorded time from entry to exit, s (nan: nobody replaced)."""
        return (len(self.robot_track) - 1) * self.dt if len(self.robot_track) else math.nan

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, RecordedPeople):
            return NotImplemented
        return (self.dt, self.time_limit, self.scene, self.first_frame) == (
            other.dt,
            other.time_limit,
            other.scene,
            other.first_frame,
        ) and all(
            a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
            for a, b in (
                (self.tracks, other.tracks),
                (self.follow, other.follow),
                (self.robot_track, other.robot_track),
                (self.persons, other.persons),
            )
        )

    __hash__ = None  # type: ignore[assignment]

    def to_json(self) -> dict[str, Any]:
        """JSON-ready; absent positions are null, floats exact."""
        tracks = np.where(np.isnan(self.tracks), None, self.tracks).tolist()  # type: ignore[call-overload]
        return {
            "dt": self.dt,
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
