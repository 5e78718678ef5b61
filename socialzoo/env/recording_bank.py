"""The recordings that a batch's recorded rows play (socialzoo.env.replay), each stored once, and each row's
pointer into them: a reset points a row at its recording instead of copying it into the row."""

from __future__ import annotations

import weakref
from collections.abc import Sequence

import numpy as np

from socialzoo.scenarios.recorded_people import NEVER, RecordedPeople

# A recording's blocks, one per section; every column of a section holds one row per item of it.
POINTS, SLOTS, OCCUPANTS, ROUTE, ROBOT = range(5)
# Segments of the replaced person's path per bounding box (robot_box): a robot's distance to the path
# looks only into the boxes that can hold its nearest point (socialzoo.env.replay_kernels.account_step).
PATH_CHUNK = 8
# The columns of a row's pointer (RecordingBank.pointer).
_POINTER = ("entry_of", "point_at", "people", "frames", "slot_at", "robot_at", "robot_points")
_COLUMNS: tuple[tuple[str, ...], ...] = (
    ("pos", "vel"),
    ("occupants_at", "occupants", "route_at", "route_points", "shared", "follow"),
    ("entry", "exit", "first", "last", "speed"),
    ("route_frame",),
    ("robot", "robot_box"),
)


class RecordingBank:
    """Every recording (RecordedPeople) that B rows play, each stored once, and where each row's is.

    A recording of n slots on T frames is a block of each section, appended when a row first plays it
    (the same object: a family that keeps its scenarios, as recorded scenes do, adds each recording once):

    - points: pos and vel (P, 2), its tracks and their velocities (RecordedPeople.velocities) frame-major,
      frame f's n slots together (a step reads a row's slots on one or two frames), m and m/s, NaN absent;
    - slots (S,): occupants_at and occupants, where each slot's people are in the occupant section and
      how many; route_at and route_points, where its route frames are (RecordedPeople.slot_routes,
      unpadded) and how many; shared, more than one person in it; follow, RecordedPeople.follow;
    - occupants (O,): entry, exit, first, last, speed, each slot's people one after another
      (socialzoo.scenarios.recorded_people.Occupants without its padding);
    - route points (F,): route_frame;
    - robot points: robot (Q, 2), the replaced person's path (RecordedPeople.robot_track), m; robot_box
      (Q, 4), at the first point of every PATH_CHUNK segments of it, their bounding box (min x, min y,
      max x, max y; the other points' rows unused).

    A row's pointer (B,) says where its recording is: entry_of, its entry (-1: none); point_at, its
    frame 0's slot 0; people, n; frames, T; slot_at, its slot 0; robot_at and robot_points, its path's
    first point and their count (a row without a recording: all 0). Slot s of row b is the bank's slot
    slot_at[b] + s, and on frame f at pos[point_at[b] + f * people[b] + s]. Per entry: dt (its frame
    period, s) and time_limit (its robot's budget, s); `recording(entry)` is its recording.

    Forgetting: an entry is named by its recording object, which the bank refers to weakly. An entry
    that no row points at and whose recording nobody holds any more (a family that builds a new
    recording on every reset drops it once no row plays it) can never be drawn again: it is garbage.
    When an addition leaves the garbage holding more bytes than the other entries, the garbage is
    dropped and the others move down in their order (the rows' pointers with them), into arrays of
    their size. So the bank holds at most twice the bytes of the recordings still held (by the rows'
    scenarios, or by a family that keeps them: the recorded scenes keep each track's, and the bank
    then adds each once and never drops it), and a compaction copies fewer bytes than it drops
    (tests/env/test_recorded_people.py checks both over long runs of resets).

    Args:
        batch_size: B.
    """

    def __init__(self, batch_size: int) -> None:
        self.pos = np.zeros((0, 2))
        self.vel = np.zeros((0, 2))
        self.occupants_at = np.zeros(0, dtype=np.int64)
        self.occupants = np.zeros(0, dtype=np.int64)
        self.route_at = np.zeros(0, dtype=np.int64)
        self.route_points = np.zeros(0, dtype=np.int64)
        self.shared = np.zeros(0, dtype=bool)
        self.follow = np.zeros(0, dtype=bool)
        self.entry = np.zeros(0, dtype=np.int64)
        self.exit = np.zeros(0, dtype=np.int64)
        self.first = np.zeros(0, dtype=np.int64)
        self.last = np.zeros(0, dtype=np.int64)
        self.speed = np.zeros(0)
        self.route_frame = np.zeros(0, dtype=np.int64)
        self.robot = np.zeros((0, 2))
        self.robot_box = np.zeros((0, 4))
        # Items in use of each section (its arrays may be longer: they grow by doubling).
        self._size = np.zeros(len(_COLUMNS), dtype=np.int64)
        # Per entry: its recording (a weak reference; the index finds an entry by the recording's id,
        # checked against it), its blocks' starts and sizes, its bytes, the rows pointing at it, and its
        # pointer (a last row of zeros with entry -1: the pointer of no recording, which index -1 picks).
        self._refs: list[weakref.ref[RecordedPeople]] = []
        self._index: dict[int, int] = {}
        self._start = np.zeros((0, len(_COLUMNS)), dtype=np.int64)
        self._items = np.zeros((0, len(_COLUMNS)), dtype=np.int64)
        self._frames: list[int] = []
        self._bytes = np.zeros(0, dtype=np.int64)
        self._rows: list[int] = []
        self._tabulate()
        self.dt = np.zeros(0)
        self.time_limit = np.zeros(0)
        # (B, 7) each row's pointer; its columns are the views entry_of ... robot_points.
        self.pointer = np.repeat(self._pointers[-1:], batch_size, axis=0)
        self._view_columns()

    def __getstate__(self) -> dict[str, object]:
        # A copy (pickled or deep-copied with the env: vector envs' workers) holds its recordings
        # strongly, so that they are the copy's scenarios' own (one pickle, one memo); weak references
        # and ids do not carry over, and the pointer's column views would come back as copies.
        state = {k: v for k, v in self.__dict__.items() if k not in ("_index", *_POINTER)}
        state["_refs"] = [r() for r in self._refs]
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        recordings: list[RecordedPeople | None] = state.pop("_refs")  # type: ignore[assignment]
        self.__dict__.update(state)
        self._refs = [weakref.ref(r) if r is not None else _gone() for r in recordings]
        self._index = {id(r): k for k, r in enumerate(recordings) if r is not None}
        self._view_columns()

    def _view_columns(self) -> None:
        """entry_of ... robot_points: the columns of `pointer`, as views of it."""
        (
            self.entry_of, self.point_at, self.people, self.frames, self.slot_at, self.robot_at, self.robot_points,
        ) = self.pointer.T  # fmt: skip

    # ------------------------------------------------------------------ rows
    def point(self, rows: np.ndarray, recordings: Sequence[RecordedPeople | None]) -> np.ndarray:
        """Point `rows` at `recordings` (one per row; None: no recording), adding those the bank does
        not hold and dropping the garbage once it outweighs the rest (the rule above); returns
        (len(rows),) their entries (-1 for None)."""
        held = len(self._refs)
        entries = [-1 if r is None else self._add(r) for r in recordings]
        for entry in self.entry_of[rows].tolist():
            if entry >= 0:
                self._rows[entry] -= 1
        for entry in entries:
            if entry >= 0:
                self._rows[entry] += 1
        self.pointer[rows] = self._pointers[entries]
        if len(self._refs) > held:
            garbage = self._garbage()
            if garbage.any() and self._bytes[garbage].sum() > self._bytes[~garbage].sum():
                self._compact(np.flatnonzero(~garbage))
        return self.entry_of[rows]

    def release(self, rows: np.ndarray) -> None:
        """Point `rows` at no recording (nothing to do, as on every reset of a task's own cases, if
        none of them points at one)."""
        if (self.entry_of[rows] >= 0).any():
            self.point(rows, [None] * len(rows))

    def recording(self, entry: int) -> RecordedPeople | None:
        """The recording of `entry` (None once nobody holds it)."""
        return self._refs[entry]()

    def _garbage(self) -> np.ndarray:
        """(E,) the entries that no row points at and whose recording nobody holds."""
        return np.array(
            [n == 0 and r() is None for n, r in zip(self._rows, self._refs, strict=True)], dtype=bool
        )

    # ------------------------------------------------------------------ entries
    def _add(self, recording: RecordedPeople) -> int:
        """The entry of `recording`, its blocks appended if the bank does not hold it (no row points
        at a new entry yet)."""
        entry = self._index.get(id(recording))
        if entry is not None and self._refs[entry]() is recording:  # not a dead one's id, reused
            return entry
        occupants = recording.occupants
        held = occupants.entry < NEVER  # each slot's people are its first entries
        counts = held.sum(1)
        lengths = np.array([len(frames) for frames in recording.slot_routes], dtype=np.int64)
        n, t = recording.num_people, recording.num_frames
        blocks: list[dict[str, np.ndarray]] = [
            {
                "pos": recording.tracks.transpose(1, 0, 2).reshape(-1, 2),
                "vel": recording.velocities.transpose(1, 0, 2).reshape(-1, 2),
            },
            {
                "occupants_at": self._size[OCCUPANTS] + np.cumsum(counts) - counts,
                "occupants": counts,
                "route_at": self._size[ROUTE] + np.cumsum(lengths) - lengths,
                "route_points": lengths,
                "shared": occupants.shared,
                "follow": recording.follow,
            },
            {name: getattr(occupants, name)[held] for name in ("entry", "exit", "first", "last", "speed")},
            {"route_frame": np.concatenate(recording.slot_routes) if n else np.zeros(0, dtype=np.int64)},
            {"robot": recording.robot_track, "robot_box": path_boxes(recording.robot_track)},
        ]
        start = self._size.copy()
        for section, block in enumerate(blocks):
            self._append(section, block)
        items = self._size - start
        entry = len(self._refs)
        self._refs.append(weakref.ref(recording))
        self._index[id(recording)] = entry
        self._start = np.concatenate((self._start, start[None]))
        self._items = np.concatenate((self._items, items[None]))
        self._bytes = np.append(self._bytes, (items * self._item_bytes()).sum())
        self._rows.append(0)
        self._frames.append(t)
        self._tabulate()
        self.dt = np.append(self.dt, recording.dt)
        self.time_limit = np.append(self.time_limit, recording.time_limit)
        return entry

    def _tabulate(self) -> None:
        """Each entry's pointer (_POINTER's columns) from its blocks, and the pointer of none last."""
        start, items = self._start, self._items
        columns = (np.arange(len(start)), start[:, POINTS], items[:, SLOTS], self._frames, start[:, SLOTS],
                   start[:, ROBOT], items[:, ROBOT])  # fmt: skip
        none = np.zeros((1, len(_POINTER)), dtype=np.int64)
        none[0, _POINTER.index("entry_of")] = -1
        self._pointers = np.concatenate(
            (np.stack(columns, 1).astype(np.int64).reshape(-1, len(_POINTER)), none)
        )

    def _item_bytes(self) -> np.ndarray:
        """(5,) bytes of one item of each section (its row of every column)."""
        return np.array(
            [sum(getattr(self, name).itemsize * int(np.prod(getattr(self, name).shape[1:])) for name in names)
             for names in _COLUMNS],
            dtype=np.int64,
        )  # fmt: skip

    def _append(self, section: int, block: dict[str, np.ndarray]) -> None:
        """Append one block of `section` (a value per column), growing its arrays by doubling."""
        size = int(self._size[section])
        count = len(block[_COLUMNS[section][0]])
        for name in _COLUMNS[section]:
            array = getattr(self, name)
            if size + count > len(array):
                grown = np.zeros((max(size + count, 2 * len(array)),) + array.shape[1:], dtype=array.dtype)
                grown[:size] = array[:size]
                setattr(self, name, array := grown)
            array[size : size + count] = block[name]
        self._size[section] = size + count

    def _compact(self, keep: np.ndarray) -> None:
        """Keep only the entries `keep` (increasing; every entry a row points at among them): they move
        down in their order, with their rows' pointers and their slots' indices into the occupant and
        route sections."""
        renumber = np.full(len(self._refs) + 1, -1, dtype=np.int64)  # old entry -> new; the last: none
        renumber[keep] = np.arange(len(keep))
        start, items = self._start[keep], self._items[keep]
        moved = np.cumsum(items, axis=0) - items
        for section, names in enumerate(_COLUMNS):
            lengths = items[:, section]
            take = np.repeat(start[:, section] - moved[:, section], lengths) + np.arange(lengths.sum())
            for name in names:
                setattr(self, name, getattr(self, name)[take])
        self._size = items.sum(0)
        slots = items[:, SLOTS]
        self.occupants_at -= np.repeat(start[:, OCCUPANTS] - moved[:, OCCUPANTS], slots)
        self.route_at -= np.repeat(start[:, ROUTE] - moved[:, ROUTE], slots)
        kept = keep.tolist()
        self._refs = [self._refs[k] for k in kept]
        self._index = {id(r()): k for k, r in enumerate(self._refs) if r() is not None}
        self._bytes = self._bytes[keep]
        self._rows = [self._rows[k] for k in kept]
        self._start, self._items = moved, items
        self._frames = [self._frames[k] for k in kept]
        self._tabulate()
        self.dt, self.time_limit = self.dt[keep], self.time_limit[keep]
        self.pointer[:] = self._pointers[renumber[self.entry_of]]

    # ------------------------------------------------------------------ sizes
    @property
    def nbytes(self) -> int:
        """Bytes of the bank's arrays: its sections as allocated, its entries' tables and the rows' pointers."""
        names = [n for section in _COLUMNS for n in section]
        names += ["_start", "_items", "_pointers", "dt", "time_limit", "pointer"]
        return int(sum(getattr(self, n).nbytes for n in names))

    @property
    def entries(self) -> int:
        """The recordings the bank holds (garbage included until it is dropped)."""
        return len(self._refs)

    @property
    def used_bytes(self) -> tuple[int, int]:
        """(bytes of the entries kept, bytes of the garbage) in the sections (the rule above)."""
        garbage = self._garbage()
        return int(self._bytes[~garbage].sum()), int(self._bytes[garbage].sum())


class _Gone:
    """An object that nobody holds (_gone)."""


def _gone() -> weakref.ref[RecordedPeople]:
    """A dead weak reference: a copied entry whose recording nobody held any more."""
    return weakref.ref(_Gone())  # type: ignore[arg-type]


def path_boxes(path: np.ndarray) -> np.ndarray:
    """(Q, 4) for a path of Q points (Q, 2): at point c * PATH_CHUNK, the bounding box (min x, min y,
    max x, max y) of the segments from there to the next such point (PATH_CHUNK + 1 points, fewer at
    the path's end); zeros elsewhere."""
    boxes = np.zeros((len(path), 4))
    if len(path) < 2:
        return boxes
    starts = np.arange(0, len(path) - 1, PATH_CHUNK)
    ends = np.minimum(starts + PATH_CHUNK, len(path) - 1)  # each chunk's last point, shared with the next
    boxes[starts, :2] = np.minimum(np.minimum.reduceat(path[:-1], starts), path[ends])
    boxes[starts, 2:] = np.maximum(np.maximum.reduceat(path[:-1], starts), path[ends])
    return boxes
