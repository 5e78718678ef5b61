"""Pedestrian track files (ETH/UCY) read onto one frame grid: a Recording of per-person Tracks."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

LAYOUTS = ("auto", "trajectron", "obsmat")
# Layout -> the names of its columns.
COLUMNS: dict[str, tuple[str, ...]] = {
    "trajectron": ("frame", "person", "x", "y"),
    "obsmat": ("frame", "person", "pos_x", "pos_z", "pos_y", "v_x", "v_z", "v_y"),
}
# Layout -> the columns of x and y (metres).
XY_COLUMNS: dict[str, tuple[int, int]] = {"trajectron": (2, 3), "obsmat": (2, 4)}
# Seconds per grid step when `dt` is not given: ETH/UCY are annotated at 2.5 Hz.
DEFAULT_DT = 0.4
# The longest run of a person's missing frames that is interpolated; a longer one splits the track.
MAX_GAP_FRAMES = 2
# Frame and person numbers are read as floats, which hold every whole number below this one only.
MAX_WHOLE = 2**53


class TrackFileError(ValueError):
    """A track file that cannot be read: names the file, the line (when there is one) and what is wrong.

    Args:
        path: the file.
        line: the line number (from 1), or None when the fault is not on one line (an empty file).
        what: what is wrong.
    """

    def __init__(self, path: str | Path, line: int | None, what: str):
        self.path = str(path)
        self.line = line
        self.what = what
        where = self.path if line is None else f"{self.path}, line {line}"
        super().__init__(f"{where}: {what}")

    def __reduce__(self) -> tuple[type[TrackFileError], tuple[str, int | None, str]]:
        return type(self), (self.path, self.line, self.what)


@dataclass(frozen=True, eq=False)
class Track:
    """One person's positions on consecutive frames of a recording's grid.

    Args:
        person: the person id in the file (made unique across the files of one scene by `join`).
        first_frame: the index on the recording's frame grid of its first position (0 = the
            recording's first frame).
        positions: (T, 2) float64 world positions in metres, one per frame from first_frame on,
            T >= 1; stored as a read-only copy.

    Raises:
        ValueError: a first frame below 0, positions not of shape (T, 2) with T >= 1, or not finite.
    """

    person: int
    first_frame: int
    positions: np.ndarray

    def __post_init__(self) -> None:
        if not isinstance(self.first_frame, (int, np.integer)) or self.first_frame < 0:
            raise ValueError(f"Track.first_frame must be an int >= 0, got {self.first_frame!r}")
        positions = np.array(self.positions, dtype=np.float64)
        if positions.ndim != 2 or positions.shape[1] != 2 or len(positions) < 1:
            raise ValueError(f"Track.positions must have shape (T, 2) with T >= 1, got {positions.shape}")
        if not np.isfinite(positions).all():
            raise ValueError(f"Track.positions of person {self.person} must be finite")
        positions.flags.writeable = False
        object.__setattr__(self, "person", int(self.person))
        object.__setattr__(self, "first_frame", int(self.first_frame))
        object.__setattr__(self, "positions", positions)

    @property
    def last_frame(self) -> int:
        """The grid index of its last position: first_frame + T - 1."""
        return self.first_frame + len(self.positions) - 1


@dataclass(frozen=True, eq=False)
class Recording:
    """A recorded scene: people's tracks on one frame grid.

    Args:
        name: the scene name, e.g. "eth".
        dt: seconds between frames of the grid (0.4 for ETH/UCY: 2.5 Hz).
        num_frames: frames on the grid (the last frame index + 1).
        tracks: the tracks, stored sorted by (first_frame, person).
        source: the file or files it came from, for messages.

    Raises:
        ValueError: dt not a positive finite number, num_frames below 1, or a track ending past
            the grid.
    """

    name: str
    dt: float
    num_frames: int
    tracks: tuple[Track, ...]
    source: str

    def __post_init__(self) -> None:
        if not (isinstance(self.dt, (int, float)) and math.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"Recording.dt must be a positive number of seconds, got {self.dt!r}")
        if not isinstance(self.num_frames, (int, np.integer)) or self.num_frames < 1:
            raise ValueError(f"Recording.num_frames must be an int >= 1, got {self.num_frames!r}")
        tracks = tuple(sorted(self.tracks, key=lambda t: (t.first_frame, t.person)))
        for track in tracks:
            if track.last_frame >= self.num_frames:
                raise ValueError(
                    f"recording {self.name!r}: person {track.person} ends on frame {track.last_frame}, "
                    f"past the grid's {self.num_frames} frames"
                )
        object.__setattr__(self, "dt", float(self.dt))
        object.__setattr__(self, "num_frames", int(self.num_frames))
        object.__setattr__(self, "tracks", tracks)

    @cached_property
    def spans(self) -> np.ndarray:
        """(N, 2) int64 each track's first and last frame, in the order of `tracks` (read-only)."""
        spans = np.array([(t.first_frame, t.last_frame) for t in self.tracks], dtype=np.int64).reshape(-1, 2)
        spans.flags.writeable = False
        return spans

    @cached_property
    def persons(self) -> np.ndarray:
        """(N,) int64 each track's person id, in the order of `tracks` (read-only): a person whose track a
        gap split (MAX_GAP_FRAMES) has several tracks with one id."""
        persons = np.array([t.person for t in self.tracks], dtype=np.int64)
        persons.flags.writeable = False
        return persons

    def grid(
        self, tracks: Sequence[int] | None = None, first: int = 0, last: int | None = None
    ) -> np.ndarray:
        """(n, last - first + 1, 2) world positions in metres of the chosen tracks on frames first..last,
        NaN where a person is absent.

        Args:
            tracks: indices into self.tracks, n of them (default: all, in order).
            first: the first grid frame.
            last: the last grid frame, included (default: the recording's last).

        Raises:
            ValueError: frames outside 0..num_frames - 1 or last before first.
            IndexError: a track index outside self.tracks.
        """
        last = self.num_frames - 1 if last is None else last
        if not 0 <= first <= last < self.num_frames:
            raise ValueError(
                f"frames {first}..{last} are not a range of recording {self.name!r}'s frames "
                f"0..{self.num_frames - 1}"
            )
        chosen = list(range(len(self.tracks))) if tracks is None else [int(k) for k in tracks]
        for k in chosen:
            if not 0 <= k < len(self.tracks):
                raise IndexError(f"track index {k} is outside recording {self.name!r}'s {len(self.tracks)}")
        out = np.full((len(chosen), last - first + 1, 2), np.nan)
        for row, k in enumerate(chosen):
            track = self.tracks[k]
            lo, hi = max(first, track.first_frame), min(last, track.last_frame)
            if lo <= hi:
                out[row, lo - first : hi - first + 1] = track.positions[
                    lo - track.first_frame : hi - track.first_frame + 1
                ]
        return out


def read_tracks(
    path: str | Path, *, layout: str = "auto", dt: float | None = None, name: str | None = None
) -> Recording:
    """Read a track file onto its frame grid (the layouts and the grid below).

    Two layouts of whitespace-separated numbers, one row per person and frame:

    - "trajectron": `frame person x y`, as distributed with Trajectron++ and Social GAN (tab separated;
      frame numbers step 10 per 0.4 s).
    - "obsmat": the ETH `obsmat.txt` of OpenTraj, 8 columns `frame person pos_x pos_z pos_y v_x v_z
      v_y`; x and y are columns 2 and 4 (from 0), the height and the velocities are not used.

    The frame grid: frame numbers step by the grid period, the step a person's rows take most often,
    and frame index 0 is the file's first frame. After a pause longer than one period in which nobody
    is annotated, the frame numbers may go on off that grid (ETH's seq_eth obsmat.txt does): such a
    stretch starts at the nearest grid index. Each grid step is `dt` seconds: 0.4 s (2.5 Hz, the
    ETH/UCY annotation rate) unless `dt=` says otherwise, in both layouts.

    A person's missing frames are filled by linear interpolation over gaps of up to MAX_GAP_FRAMES
    frames; a longer gap splits the person into two tracks (with the same person id).

    Blank lines and lines starting with "#" are skipped.

    Args:
        path: the file.
        layout: "trajectron", "obsmat", or "auto" (4 columns: trajectron, 8: obsmat).
        dt: seconds per grid step (default DEFAULT_DT, 0.4 s).
        name: the scene name (default: the file name without its suffix).

    Raises:
        TrackFileError: a file that is empty, not text, has the wrong number of columns, a value
            that is not a finite number, a frame or person number that is not whole or not below
            2**53 (MAX_WHOLE: larger ones are not all read exactly, so two people could read as one),
            a person twice in one frame (an identical row twice included), or a frame off the grid.
        ValueError: an unknown layout or a dt that is not a positive number.
        OSError: the file cannot be read.
    """
    if layout not in LAYOUTS:
        raise ValueError(f"unknown track file layout {layout!r}; known: {LAYOUTS}")
    if dt is not None and not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
    path = Path(path)
    lines, values = _parse(path, layout)
    frame, person = values[:, 0].astype(np.int64), values[:, 1].astype(np.int64)
    used = "trajectron" if values.shape[1] == len(COLUMNS["trajectron"]) else "obsmat"
    xy = values[:, list(XY_COLUMNS[used])]
    order = np.lexsort((frame, person))  # by person, then frame; equal rows keep their file order
    _refuse_repeats(path, lines[order], person[order], frame[order], values[order])
    index = _grid_index(path, lines, frame, person[order], frame[order])
    tracks = _tracks(person[order], index[order], xy[order])
    return Recording(
        name=path.stem if name is None else name,
        dt=DEFAULT_DT if dt is None else float(dt),
        num_frames=int(index.max()) + 1,
        tracks=tuple(tracks),
        source=str(path),
    )


def join(recordings: Sequence[Recording], name: str, gap_frames: int = 10) -> Recording:
    """One scene from several recordings of it (univ = students001 + students003), one after another.

    A later recording's frames are shifted past the end of the earlier ones plus `gap_frames` empty
    frames. Its person ids are kept when all are above the earlier ones' ids, else shifted by one
    constant so that they start just above the largest earlier id.

    Args:
        recordings: the recordings, in order; all with the same dt.
        name: the joined scene's name.
        gap_frames: empty frames between one recording's end and the next one's start.

    Raises:
        ValueError: no recordings, different dt, or gap_frames below 0.
    """
    recordings = list(recordings)
    if not recordings:
        raise ValueError(f"join needs at least one recording to make scene {name!r}")
    if not isinstance(gap_frames, (int, np.integer)) or gap_frames < 0:
        raise ValueError(f"gap_frames must be an int >= 0, got {gap_frames!r}")
    dts = {r.dt for r in recordings}
    if len(dts) > 1:
        raise ValueError(
            "join needs recordings with one dt; got " + ", ".join(f"{r.source}: {r.dt} s" for r in recordings)
        )
    tracks: list[Track] = []
    offset, end, top = 0, 0, None
    for rec in recordings:
        persons = [t.person for t in rec.tracks]
        shift = 0
        if top is not None and persons and min(persons) <= top:
            shift = top + 1 - min(persons)
        tracks += [Track(t.person + shift, t.first_frame + offset, t.positions) for t in rec.tracks]
        if persons:
            top = max(persons) + shift if top is None else max(top, max(persons) + shift)
        end = offset + rec.num_frames
        offset = end + int(gap_frames)
    return Recording(
        name=name,
        dt=recordings[0].dt,
        num_frames=end,
        tracks=tuple(tracks),
        source=" + ".join(r.source for r in recordings),
    )


def _parse(path: Path, layout: str) -> tuple[np.ndarray, np.ndarray]:
    """(line numbers (N,), values (N, C)) of the data rows of a track file, checked row by row."""
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark (Windows editors) is not data
    except UnicodeDecodeError as exc:
        raise TrackFileError(
            path, raw.count(b"\n", 0, exc.start) + 1, "not a text file (not UTF-8)"
        ) from None
    columns = COLUMNS.get(layout)
    numbers: list[list[float]] = []
    lines: list[int] = []
    for line_number, line in enumerate(text.splitlines(), start=1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        # Commas are not separators: say so rather than count a CSV line as one column.
        commas = "; columns are separated by whitespace, not commas" if "," in line else ""
        if columns is None:
            columns = next((c for c in COLUMNS.values() if len(c) == len(fields)), None)
            if columns is None:
                raise TrackFileError(
                    path,
                    line_number,
                    f"{len(fields)} columns; expected 4 (trajectron: frame person x y) or 8 "
                    f"(obsmat: frame person pos_x pos_z pos_y v_x v_z v_y){commas}",
                )
        if len(fields) != len(columns):
            used = next(k for k, c in COLUMNS.items() if c is columns)
            raise TrackFileError(
                path,
                line_number,
                f"{len(fields)} columns; the {used} layout has {len(columns)} ({' '.join(columns)}){commas}",
            )
        row = []
        for column, field in zip(columns, fields, strict=True):
            try:
                value = float(field)
            except ValueError:
                header = " (a header line? start it with #)" if not numbers else ""
                raise TrackFileError(
                    path, line_number, f"{column} is not a number: {field!r}{header}"
                ) from None
            if not math.isfinite(value):
                raise TrackFileError(path, line_number, f"{column} must be a finite number, got {field!r}")
            if column in ("frame", "person") and value != round(value):
                raise TrackFileError(path, line_number, f"{column} must be a whole number, got {field!r}")
            if column in ("frame", "person") and abs(value) >= MAX_WHOLE:
                raise TrackFileError(
                    path,
                    line_number,
                    f"{column} must be a whole number below 2**53 ({MAX_WHOLE}), got {field!r}",
                )
            row.append(value)
        numbers.append(row)
        lines.append(line_number)
    if not numbers:
        raise TrackFileError(path, None, "no data rows (an empty file)")
    return np.asarray(lines, dtype=np.int64), np.asarray(numbers, dtype=np.float64)


def _refuse_repeats(
    path: Path, lines: np.ndarray, person: np.ndarray, frame: np.ndarray, values: np.ndarray
) -> None:
    """Raise for the first row (in file order) of a person already seen in its frame; rows sorted by
    (person, frame), equal keys in file order."""
    repeated = np.flatnonzero((person[1:] == person[:-1]) & (frame[1:] == frame[:-1])) + 1
    if len(repeated) == 0:
        return
    k = repeated[np.argmin(lines[repeated])]
    first = k - 1
    while first > 0 and person[first - 1] == person[k] and frame[first - 1] == frame[k]:
        first -= 1
    if np.array_equal(values[first], values[k]):
        what = f"a duplicate of line {lines[first]} (person {person[k]} in frame {frame[k]})"
    else:
        what = f"person {person[k]} is twice in frame {frame[k]} (also on line {lines[first]})"
    raise TrackFileError(path, int(lines[k]), what)


def _grid_index(
    path: Path, lines: np.ndarray, frame: np.ndarray, sorted_person: np.ndarray, sorted_frame: np.ndarray
) -> np.ndarray:
    """The grid index of each row's frame (file order); raise for the first row off the grid.

    The period is the step between a person's consecutive rows taken most often (the smallest
    frame-number difference when nobody has two rows). A stretch of annotation is a run of frame
    numbers without a pause longer than one period; its grid is the frame numbers with the remainder
    modulo the period that most of its rows have, and it starts at the grid index nearest its first
    frame's (frame index 0: the file's first frame). A stretch after a pause may be on another
    remainder (ETH's seq_eth obsmat.txt has stretches on 0, 3 and 5 modulo 6): it moves by at most
    half a period, while nobody is annotated.
    """
    same = sorted_person[1:] == sorted_person[:-1]
    steps = (sorted_frame[1:] - sorted_frame[:-1])[same]
    distinct = np.unique(frame)
    if len(steps):
        values, counts = np.unique(steps, return_counts=True)
        period = int(values[np.argmax(counts)])
    elif len(distinct) > 1:
        period = int(np.diff(distinct).min())
    else:
        period = 1
    starts = np.concatenate(([True], np.diff(distinct) > period))
    stretch = (np.cumsum(starts) - 1)[np.searchsorted(distinct, frame)]  # each row's stretch
    remainder = frame % period
    rows = np.zeros((stretch.max() + 1, period), dtype=np.int64)
    np.add.at(rows, (stretch, remainder), 1)
    off = remainder != rows.argmax(1)[stretch]
    first = np.full(len(rows), np.iinfo(np.int64).max)
    np.minimum.at(first, stretch[~off], frame[~off])  # each stretch's first frame on its grid
    if off.any():
        k = int(np.argmax(off))
        raise TrackFileError(
            path,
            int(lines[k]),
            f"frame {frame[k]} is off the frame grid: frames {first[stretch[k]]} + k * {period} "
            f"(a person's rows step {period} frame numbers most often)",
        )
    start = (2 * (first - distinct[0]) + period) // (2 * period)  # the nearest grid index (halves up)
    return start[stretch] + (frame - first[stretch]) // period


def _tracks(person: np.ndarray, index: np.ndarray, xy: np.ndarray) -> list[Track]:
    """The tracks of rows sorted by (person, grid index): gaps of up to MAX_GAP_FRAMES missing frames
    interpolated linearly, longer ones split."""
    tracks = []
    starts = np.flatnonzero(np.r_[True, person[1:] != person[:-1]])
    for start, stop in zip(starts, np.r_[starts[1:], len(person)], strict=True):
        frames, positions = index[start:stop], xy[start:stop]
        cuts = np.flatnonzero(np.diff(frames) > MAX_GAP_FRAMES + 1) + 1
        for seg_frames, seg_positions in zip(np.split(frames, cuts), np.split(positions, cuts), strict=True):
            full = np.arange(seg_frames[0], seg_frames[-1] + 1)
            filled = np.stack([np.interp(full, seg_frames, seg_positions[:, c]) for c in range(2)], axis=1)
            tracks.append(Track(int(person[start]), int(seg_frames[0]), filled))
    return tracks
