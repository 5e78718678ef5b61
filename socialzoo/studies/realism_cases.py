"""The recorded cases of the realism study: an ETH/UCY scene's tracks on one grid, a seeded sample of its people,
their 4.8 s windows and whole tracks, and each case's recorded positions and constant-velocity walk."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

# The prediction literature's protocol: 8 observed frames (3.2 s), 12 predicted (4.8 s).
OBS_FRAMES = 8
PRED_FRAMES = 12


@dataclass(frozen=True)
class SceneTracks:
    """A scene on one grid: every track's positions on every frame.

    Attributes:
        name: the scene.
        dt: s per frame.
        grid: (N, F, 2) positions, m, NaN where absent.
        first: (N,) each track's first frame.
        last: (N,) each track's last frame.
    """

    name: str
    dt: float
    grid: np.ndarray
    first: np.ndarray
    last: np.ndarray

    @classmethod
    def of(cls, recording: Any) -> SceneTracks:
        """From a socialzoo.data.tracks.Recording."""
        return cls(
            name=recording.name,
            dt=float(recording.dt),
            grid=recording.grid(),
            first=recording.spans[:, 0],
            last=recording.spans[:, 1],
        )

    def mean_speed(self, k: int) -> float:
        """Track k's mean recorded speed, at least MIN_SPEED, m/s (socialzoo.scenarios.recorded_people)."""
        from socialzoo.scenarios.recorded_people import mean_speed

        return mean_speed(self.grid[k, self.first[k] : self.last[k] + 1], self.dt)


@dataclass(frozen=True)
class Cases:
    """Cases of one scene: person (track index), start frame, frames simulated after it.

    Attributes:
        person: (n,) track indices.
        start: (n,) the start frame (the last observed one, or the entry).
        frames: (n,) frames simulated after the start.
        kind: "windows" or "tracks".
    """

    person: np.ndarray
    start: np.ndarray
    frames: np.ndarray
    kind: str

    def __len__(self) -> int:
        return len(self.person)

    def take(self, index: np.ndarray) -> Cases:
        """The cases at `index`."""
        return Cases(self.person[index], self.start[index], self.frames[index], self.kind)


def window_cases(scene: SceneTracks, persons: np.ndarray | None = None) -> Cases:
    """Every 4.8 s window of `persons` (default all tracks).

    The prediction literature's 4.8 s protocol: every frame t0 at which the person has been seen OBS_FRAMES
    frames (t0 - 7 .. t0) and is still seen PRED_FRAMES frames later. The model starts at its position at t0
    with the observed velocity (t0 - 1 -> t0), its goal the track's last position and its preferred speed its
    mean recorded speed; ADE and FDE over frames t0 + 1 .. t0 + 12.
    """
    persons = np.arange(len(scene.first)) if persons is None else np.asarray(persons)
    starts = [
        np.arange(scene.first[k] + OBS_FRAMES - 1, scene.last[k] - PRED_FRAMES + 1) for k in persons.tolist()
    ]
    person = np.repeat(persons, [len(t0) for t0 in starts]).astype(np.int64)
    begin = np.concatenate([np.zeros(0, dtype=np.int64), *starts]).astype(np.int64)
    return Cases(person, begin, np.full(len(person), PRED_FRAMES), "windows")


def track_cases(scene: SceneTracks, persons: np.ndarray | None = None) -> Cases:
    """Each of `persons` (default all tracks seen on 2 frames or more) from entry to its track's end.

    The entry is its first frame, with the velocity of its first segment (as socialzoo.env.replay enters a
    modelled person). ADE over the frames where the simulated person is still on the scene, FDE at the
    track's last frame (the simulated person where it left, if it left earlier), and the
    distributions of speeds and nearest-neighbour distances (against the recorded ones of the same frames,
    scipy.stats.wasserstein_distance), and contacts (within COLLISION_DISTANCE of another person on a frame).
    """
    persons = np.arange(len(scene.first)) if persons is None else np.asarray(persons)
    persons = persons[scene.last[persons] > scene.first[persons]]
    return Cases(
        persons.astype(np.int64), scene.first[persons], scene.last[persons] - scene.first[persons], "tracks"
    )


def start_velocity(scene: SceneTracks, cases: Cases) -> np.ndarray:
    """(n, 2) the velocity a case starts with, m/s: the observed one (start - 1 -> start) for a
    window, the first segment's (start -> start + 1) at an entry."""
    g = scene.grid
    if cases.kind == "windows":
        a, b = g[cases.person, cases.start - 1], g[cases.person, cases.start]
    else:
        a, b = g[cases.person, cases.start], g[cases.person, cases.start + 1]
    return (b - a) / scene.dt


def frames_inside(cases: Cases) -> np.ndarray:
    """(n, 1 + max frames) the frames within each case."""
    span = int(cases.frames.max()) + 1 if len(cases) else 1
    return np.arange(span)[None, :] <= cases.frames[:, None]


def truth(scene: SceneTracks, cases: Cases) -> np.ndarray:
    """(n, 1 + max frames, 2) the recorded positions from each start on, NaN past a case's frames."""
    inside = frames_inside(cases)
    idx = cases.start[:, None] + np.arange(inside.shape[1])[None, :]
    pos = scene.grid[cases.person[:, None], np.minimum(idx, scene.grid.shape[1] - 1)]
    return np.where(inside[..., None], pos, np.nan)


def constant_velocity(scene: SceneTracks, cases: Cases) -> np.ndarray:
    """(n, 1 + max frames, 2) the constant-velocity walk from each start (NaN past its frames).

    "cv" is computed from the tracks: the start velocity kept.
    """
    inside = frames_inside(cases)
    p0 = scene.grid[cases.person, cases.start]
    v = start_velocity(scene, cases)
    pos = p0[:, None] + v[:, None] * (np.arange(inside.shape[1]) * scene.dt)[None, :, None]
    return np.where(inside[..., None], pos, np.nan)


def sample_persons(scene: SceneTracks, count: int | None, seed: int) -> np.ndarray:
    """`count` track indices of the scene drawn with `seed` (sorted), or all of them."""
    n = len(scene.first)
    if count is None or count >= n:
        return np.arange(n)
    rng = np.random.default_rng([int(seed), 0x7265616C])  # "real"
    return np.sort(rng.choice(n, size=count, replace=False))


def load_tracks(scene: str, cache: str | None) -> SceneTracks:
    """A scene of the cache, or a track file (PATH or NAME=PATH), as SceneTracks."""
    from socialzoo.data.fetch import load_recording

    return SceneTracks.of(load_recording(scene, cache=cache))
