"""Recorded people in scenarios: a recorded scene's episodes, in which the robot takes one recorded person's place
and everyone else walks as recorded (the rules, budgets and splits: docs/recorded.md)."""

from __future__ import annotations

import contextlib
import heapq
import logging
import math
import zlib
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.scenarios.catalogue import ScenarioFamily, SeedSplit
from socialzoo.scenarios.recorded_people import RecordedPeople, frames_in, path_length
from socialzoo.scenarios.scenario import Scenario

if TYPE_CHECKING:
    from pathlib import Path

    from socialzoo.data.tracks import Recording
    from socialzoo.maps.map_file import Map

logger = logging.getLogger(__name__)

# The robot's time budget: this many times the replaced person's time (or its path at
# REFERENCE_SPEED, if longer), and at least MIN_TIME_LIMIT s.
TIME_FACTOR = 2.0
REFERENCE_SPEED = 1.0
MIN_TIME_LIMIT = 10.0
# A track is eligible only if nobody stands this near its entry when it enters, m.
START_CLEARANCE = 0.7
# Eligible tracks for the robot to take the place of.
MIN_DURATION = 4.0
MIN_DISTANCE = 2.0
# The split of a scene's eligible tracks (seeds: val 0.., test 100.., train 1000..).
VAL_TRACKS = 50
TEST_TRACKS = 100
TEST_FIRST = 100
TRAIN_FIRST = 1000
# A person slot takes a new person this many seconds after its last one left (25 frames at 2.5 Hz;
# frames_in): a person a model walks (hybrid, after reacting) has that long to finish before the
# slot's next person enters.
SLOT_REST_TIME = 10.0
# Mixed with the scene's name for the permutation of its tracks.
_SPLIT_STREAM = 0x7265636F7264  # "record"
# The open area of a scene as a map (for tasks that need one): its walls stand this far beyond
# every recorded position, its graph is a grid of this spacing, m.
OPEN_MARGIN = 3.0
OPEN_SPACING = 2.0
# The open area's graph has at most this many nodes: a larger area gets a wider spacing, as the
# navigator's all-pairs table (socialzoo.nav.path_table) costs N^3 (2 s for 600 nodes, 15 s for
# 1,100: a 60 m square; minutes for a 100 m one). The five scenes need 70 to 154.
MAX_OPEN_NODES = 600
# The robot's start heading points at its track's first point this far from the start, m.
_HEADING_REACH = 1.0


# ---------------------------------------------------------------------------- episodes of a scene
def heading_along(points: np.ndarray, reach: float = _HEADING_REACH) -> float:
    """The heading from a path's first point to its first point at least `reach` away (its last
    point if none is), rad."""
    away = np.flatnonzero(np.hypot(*(points - points[0]).T) >= reach)
    target = points[away[0]] if len(away) else points[-1]
    d = target - points[0]
    return float(math.atan2(d[1], d[0]))


def time_budget(positions: np.ndarray, dt: float) -> float:
    """The robot's time budget in the place of a person with these positions (T, 2) every dt s:
    TIME_FACTOR times the longer of the person's time and its path at REFERENCE_SPEED, at least
    MIN_TIME_LIMIT (people of the scenes often walk faster than a robot's 1 m/s)."""
    need = max((len(positions) - 1) * dt, path_length(positions) / REFERENCE_SPEED)
    return max(TIME_FACTOR * need, MIN_TIME_LIMIT)


def eligible_tracks(recording: Recording) -> np.ndarray:
    """Indices of the tracks a robot may take the place of: at least MIN_DURATION s and
    MIN_DISTANCE m from entry to exit, and nobody within START_CLEARANCE of the entry when the
    person enters (the robot would start inside a walking companion)."""
    first, last = recording.spans.T
    keep = []
    for k, t in enumerate(recording.tracks):
        if (len(t.positions) - 1) * recording.dt < MIN_DURATION:
            continue
        if float(np.hypot(*(t.positions[-1] - t.positions[0]))) < MIN_DISTANCE:
            continue
        there = np.flatnonzero((first <= t.first_frame) & (last >= t.first_frame))
        others = [recording.tracks[j].positions[t.first_frame - first[j]] for j in there.tolist() if j != k]
        if others and float(np.hypot(*(np.array(others) - t.positions[0]).T).min()) < START_CLEARANCE:
            continue
        keep.append(k)
    return np.array(keep, dtype=np.int64)


def split_tracks(recording: Recording) -> dict[str, np.ndarray]:
    """The scene's eligible tracks split into "test", "val" and "train" (docs/recorded.md gives the rule).

    A person whose track a gap split in several (socialzoo.data.tracks.MAX_GAP_FRAMES) has all of them in
    the split of its first one in the permutation, so no person is in two splits."""
    eligible = eligible_tracks(recording)
    rng = np.random.default_rng([zlib.crc32(recording.name.encode()), _SPLIT_STREAM])
    order = eligible[rng.permutation(len(eligible))]
    test = min(TEST_TRACKS, len(order) // 2)
    val = min(VAL_TRACKS, (len(order) * 3) // 20)
    splits: dict[str, list[int]] = {"test": [], "val": [], "train": []}
    placed: dict[int, str] = {}
    for k in order.tolist():
        person = recording.tracks[k].person
        if person not in placed:
            filled = len(splits["test"]) >= test
            placed[person] = "train" if filled and len(splits["val"]) >= val else "val" if filled else "test"
        splits[placed[person]].append(k)
    return {name: np.array(tracks, dtype=np.int64) for name, tracks in splits.items()}


def replaced_scenario(
    recording: Recording,
    track: int,
    *,
    seed: int,
    family: str,
    map_name: str = "arena",
) -> Scenario:
    """The episode in which the robot takes the place of track `track` of `recording` (its start,
    goal and budget: docs/recorded.md): the others seen during the robot's budget are the scenario's people."""
    me = recording.tracks[track]
    limit = time_budget(me.positions, recording.dt)
    first = me.first_frame
    last = min(recording.num_frames - 1, first + math.ceil(limit / recording.dt))
    spans = recording.spans
    # Everyone else: not the replaced person's own other tracks (a gap split it), whose place the robot
    # takes too (it would meet itself on its way, or at its goal).
    seen = (spans[:, 0] <= last) & (spans[:, 1] >= first) & (recording.persons != me.person)
    others = np.flatnonzero(seen).tolist()
    grid = recording.grid(others, first, last) if others else np.zeros((0, last - first + 1, 2))
    # People who are never there at once share a person slot (pack_slots): fewer, fuller slots.
    begin = spans[others, 0] - first
    end = spans[others, 1] - first
    slot = pack_slots(begin, end, frames_in(SLOT_REST_TIME, recording.dt))
    slots = np.full((int(slot.max(initial=-1)) + 1, grid.shape[1], 2), np.nan)
    for k, s in enumerate(slot.tolist()):
        on = ~np.isnan(grid[k, :, 0])
        slots[s, on] = grid[k, on]
    persons = [recording.tracks[others[k]].person for k in np.lexsort((begin, slot)).tolist()]
    start, goal = me.positions[0], me.positions[-1]
    starts = np.array([[start[0], start[1], heading_along(me.positions)]])
    goals = np.array([[goal[0], goal[1], heading_along(me.positions[::-1]) + math.pi]])
    recorded = RecordedPeople(
        dt=recording.dt,
        tracks=slots,
        time_limit=limit,
        robot_track=me.positions,
        scene=recording.name,
        first_frame=first,
        persons=np.array(persons, dtype=np.int64),
    )
    return people_scenario(recorded, starts, goals, seed=seed, family=family, map_name=map_name)


def people_scenario(
    recorded: RecordedPeople,
    robot_starts: np.ndarray,
    robot_goals: np.ndarray,
    *,
    seed: int,
    family: str,
    map_name: str = "arena",
) -> Scenario:
    """A scenario of recorded people, one person slot per track of `recorded`: each slot spawns at
    its first recorded position, its route is its people's route points one after another
    (RecordedPeople.slot_routes), its speed its first person's mean recorded speed (the world takes each later
    person's own when it enters: socialzoo.env.replay)."""
    routes = [track[frames] for track, frames in zip(recorded.tracks, recorded.slot_routes, strict=True)]
    n = recorded.num_people
    return Scenario(
        map_name=map_name,
        seed=seed,
        family=family,
        robot_starts=robot_starts,
        robot_goals=robot_goals,
        human_spawn=np.array([points[0] for points in routes]).reshape(n, 2),
        human_start_index=np.full(n, -1),
        human_goal_index=np.full(n, -1),
        human_routes=tuple(routes),
        human_speed=recorded.occupants.speed[:, 0].copy() if n else np.zeros(0),
        recorded=recorded,
    )


def pack_slots(first: np.ndarray, last: np.ndarray, rest: int) -> np.ndarray:
    """(n,) a person slot for each of n people present on frames first..last, reusing a slot once
    its person left `rest` frames (frames_in(SLOT_REST_TIME, dt)) before the next one enters (the
    earliest-free slot, people in order of entry)."""
    order = np.lexsort((last, first))
    # (the first frame a slot may take a new person, slot): the heap's top is the earliest-free
    # slot, the lowest-numbered among equals.
    free: list[tuple[int, int]] = []
    slot = np.zeros(len(first), dtype=np.int64)
    begins, ends = first.tolist(), last.tolist()
    for k in order.tolist():
        if free and free[0][0] <= begins[k]:
            s = heapq.heappop(free)[1]
        else:
            s = len(free)  # every slot is in the heap: a new one
        slot[k] = s
        heapq.heappush(free, (int(ends[k]) + rest + 1, s))
    return slot


class RecordedScene(ScenarioFamily):
    """The episodes of one recording (docs/recorded.md): case k of a split is the robot in
    the place of that split's k-th track.

    Args:
        recording: the scene, or None to load `scene` from the data cache on first use
            (socialzoo.data.fetch.load_scene: `socialzoo data fetch eth-ucy` first).
        name: the family's registry name (default "recorded_<scene>").
        map_name: "arena" (open space: the recordings' own) or a map file in the scene's frame.
    """

    scene: str = ""
    map_name = "arena"
    max_robots = 1  # the robot takes one recorded person's place

    def __init__(
        self, recording: Recording | None = None, name: str | None = None, map_name: str = "arena"
    ) -> None:
        self._recording = recording
        self._made: dict[tuple[int, str], Scenario] = {}
        if recording is not None:
            self.scene = recording.name
        self.name = name or f"recorded_{self.scene}"
        self.map_name = map_name
        self.description = (
            f"the robot in the place of a recorded person of the {self.scene} scene, the others as recorded"
        )

    @cached_property
    def recording(self) -> Recording:
        """The scene's recording (loaded on first use)."""
        if self._recording is None:
            from socialzoo.data.fetch import load_scene

            self._recording = load_scene(self.scene)
        return self._recording

    @cached_property
    def track_splits(self) -> dict[str, np.ndarray]:
        """The scene's tracks of each split (split_tracks)."""
        return split_tracks(self.recording)

    @cached_property
    def splits(self) -> dict[str, SeedSplit]:  # type: ignore[override]
        """The seeds of the scene's splits: val 0.., test TEST_FIRST.., train TRAIN_FIRST.. (no end);
        kept, as track_splits is (every training reset draws from the train split)."""
        sizes = {k: len(v) for k, v in self.track_splits.items()}
        return {
            "val": SeedSplit(0, sizes["val"]),
            "test": SeedSplit(TEST_FIRST, sizes["test"]),
            "train": SeedSplit(TRAIN_FIRST),
        }

    @cached_property
    def max_people(self) -> int:
        """The most person slots of any episode of the scene (pack_slots)."""
        rec = self.recording
        first, last = rec.spans.T
        most, rest = 0, frames_in(SLOT_REST_TIME, rec.dt)
        for k in eligible_tracks(rec).tolist():
            end = min(
                rec.num_frames - 1,
                first[k] + math.ceil(time_budget(rec.tracks[k].positions, rec.dt) / rec.dt),
            )
            seen = (first <= end) & (last >= first[k]) & (rec.persons != rec.persons[k])
            if seen.any():
                most = max(most, int(pack_slots(first[seen], last[seen], rest).max()) + 1)
        return most

    def track_of(self, seed: int) -> int:
        """The track the robot replaces in the episode of `seed`."""
        splits = self.track_splits
        if seed >= TRAIN_FIRST:
            pool, k = splits["train"], seed - TRAIN_FIRST
            if len(pool) == 0:
                raise ValueError(f"{self.name}: the scene has no training tracks")
            return int(pool[k % len(pool)])
        pool, k = (splits["test"], seed - TEST_FIRST) if seed >= TEST_FIRST else (splits["val"], seed)
        if k >= len(pool):
            raise ValueError(f"{self.name}: seed {seed} names no track (the split holds {len(pool)})")
        return int(pool[k])

    def open_map(self) -> str:
        """The path of the scene's open area as a map file (open_area_map) in the data cache
        (socialzoo.data.fetch.data_dir), beside the recordings. The file is named after the family,
        so it is rewritten whenever it does not hold this recording's area: another recording
        registered under the same name, or the same file edited since, gets its own walls.

        A file that holds it already is only read, so a read-only cache (a shared folder) serves once
        the map is in it. A cache that cannot be written gets no map: it goes to the user's own cache
        folder (socialzoo.data.fetch.user_cache, maps/), rewritten there by the same rule.

        Raises:
            OSError: neither folder can be written (the message names both).
        """
        from socialzoo.core.files import write_text_atomic
        from socialzoo.data.fetch import data_dir, user_cache

        text = open_area_map(self.recording, self.name).to_text()
        name = f"{self.name}.json"
        shared, own = data_dir() / "maps" / name, user_cache() / "maps" / name

        def holds(path: Path) -> bool:
            with contextlib.suppress(OSError):  # none there yet, or not readable
                return path.read_text(encoding="utf-8") == text
            return False

        if holds(shared):
            return str(shared)
        try:
            # Written whole and renamed over it: another process reading or writing the same family's
            # map never sees half a file.
            return str(write_text_atomic(shared, text))
        except OSError as first:
            if holds(own):
                return str(own)
            try:
                written = write_text_atomic(own, text)
            except OSError as second:
                raise OSError(
                    f"{self.name}: cannot write its open-area map into the data cache ({shared}: {first}) "
                    f"nor into the user's cache ({own}: {second}); give the task map=PATH"
                ) from second
            logger.info(
                "%s: the data cache cannot be written (%s); its open-area map is %s", self.name, first, own
            )
            return str(written)

    def make(self, seed: int, num_robots: int = 1, m: Map | None = None) -> Scenario:
        """The episode of `seed`: the robot in the place of track_of(seed) (each track's episode is
        made once and kept; a seed only renames it)."""
        if num_robots != 1:
            raise ValueError(f"{self.name}: a recorded scene's episode has one robot, {num_robots} asked")
        map_name = self.map_name if m is None else m.name
        track = self.track_of(seed)
        key = (track, map_name)
        if key not in self._made:
            self._made[key] = replaced_scenario(
                self.recording, track, seed=seed, family=self.name, map_name=map_name
            )
        # The kept scenario under this seed: the seed keys the row's noise and people's models, and
        # the kept one (held by the rows that play it) keeps its own.
        return self._made[key].with_seed(seed)


def open_area_map(recording: Recording, name: str) -> Map:
    """The scene's open area as a map: four walls OPEN_MARGIN beyond every recorded position, a
    grid graph (8-neighbour) of OPEN_SPACING inside them (wider where that would make more than
    MAX_OPEN_NODES nodes), and its nodes as legal poses. The recordings have no walls of their own; a
    task that plans on a map's graph (the action-selection task's sub-policies) plans straight lines
    here."""
    from socialzoo.maps.map_file import Map

    points = np.concatenate([t.positions for t in recording.tracks])
    low, high = points.min(0) - OPEN_MARGIN, points.max(0) + OPEN_MARGIN
    x0, y0, x1, y1 = float(low[0]), float(low[1]), float(high[0]), float(high[1])
    walls = np.array([[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]])
    spacing = max(OPEN_SPACING, math.sqrt((x1 - x0) * (y1 - y0) / MAX_OPEN_NODES))
    while True:
        xs = np.arange(x0 + spacing / 2, x1 - spacing / 4, spacing)
        ys = np.arange(y0 + spacing / 2, y1 - spacing / 4, spacing)
        if len(xs) * len(ys) <= MAX_OPEN_NODES:
            break
        spacing *= 1.05
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    nodes = np.stack((gx.ravel(), gy.ravel()), -1)
    index = np.arange(len(nodes)).reshape(len(xs), len(ys))
    ii, jj = np.meshgrid(np.arange(len(xs)), np.arange(len(ys)), indexing="ij")
    pairs = []
    for dx, dy in ((1, 0), (0, 1), (1, 1), (1, -1)):
        ok = (ii + dx < len(xs)) & (jj + dy >= 0) & (jj + dy < len(ys))
        pairs.append(np.stack((index[ii[ok], jj[ok]], index[ii[ok] + dx, jj[ok] + dy]), -1))
    edges = np.concatenate(pairs)
    poses = np.concatenate((nodes, np.zeros((len(nodes), 1))), 1)
    return Map(
        name=name,
        walls=walls,
        nodes=nodes,
        edges=edges,
        legal_poses=poses,
        source=f"the open area of the recorded scene {recording.name} ({recording.source})",
        licence="derived from the recording's positions; no walls of its own",
    )


def _scene_family(scene: str) -> type[RecordedScene]:
    return type(f"Recorded{scene.capitalize()}", (RecordedScene,), {"scene": scene})


RecordedEth = _scene_family("eth")
RecordedHotel = _scene_family("hotel")
RecordedUniv = _scene_family("univ")
RecordedZara1 = _scene_family("zara1")
RecordedZara2 = _scene_family("zara2")
