"""Which crowd model walks most like real people: each recorded ETH/UCY person walked by a model among the others
replayed, against its own track (issue 37, item 4; protocol: docs/humans.md, "Realism against recorded people")."""

from __future__ import annotations

import dataclasses
import json
import math
import platform
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.progress import progress_bar
from socialzoo.bench.tables import markdown_table as table_lines
from socialzoo.bench.tables import write_csv
from socialzoo.core.config import HumanConfig, OrcaConfig, RobotConfig, WorldConfig

# The world step, s, and world steps per recorded frame (0.4 s at 2.5 Hz).
REALISM_DT = 0.1
# The prediction literature's protocol: 8 observed frames (3.2 s), 12 predicted (4.8 s).
OBS_FRAMES = 8
PRED_FRAMES = 12
# People's radius, m (CrowdNav's, socialzoo.env.crowd_config): two people nearer than twice it touch.
HUMAN_RADIUS = 0.3
COLLISION_DISTANCE = 2 * HUMAN_RADIUS
# A recorded companion of a "groups" subject: within this distance at the start, m, and with a
# velocity within GROUP_SPEED of the subject's, m/s.
GROUP_DISTANCE = 1.2
GROUP_SPEED = 0.5
# Batch rows per core.
BATCH_ROWS = 512
# The robot every row must have, parked far away, invisible, still.
_PARKED = 1.0e4
BASE_MODELS = ("cv", "sf", "orca", "groups")
SCENES = ("eth", "hotel", "univ", "zara1", "zara2")


# ---------------------------------------------------------------------------- models
def realism_world(dt: float = REALISM_DT) -> WorldConfig:
    """The world of the study: CrowdNav's people (socialzoo.env.crowd_config.CrowdNavConfig.world:
    radius 0.3 m, ORCA with CrowdNav's parameters) at each person's own preferred speed."""
    return WorldConfig(
        dt=dt,
        robot=RobotConfig(kinematics="holonomic", radius=0.3, max_speed=1.0),
        human=HumanConfig(radius=HUMAN_RADIUS),
        human_collision_distance=0.3 + HUMAN_RADIUS,
        orca=dataclasses.replace(
            OrcaConfig.preset("crowdnav"), radius=HUMAN_RADIUS, max_speed=None, robot_visible=False
        ),
    )


@dataclass(frozen=True)
class ModelSpec:
    """A model of the study.

    "groups": the subject and its recorded companions (GROUP_DISTANCE, GROUP_SPEED at the start) walk by the
    social force with the group forces, the rest replay; without companions it is "sf". Presets (the fitted
    parameter sets of socialzoo.studies.calibration) are WorldConfig overrides of a model.

    Attributes:
        name: as the command line names it ("cv", "sf", "orca", "groups", "learned:PATH", a preset).
        people: the people spec that walks the subject (socialzoo.humans.models); "" for cv.
        human: HumanConfig overrides (social force parameters).
        orca: OrcaConfig overrides.
        groups: the subject walks with its recorded companions (the "groups" model).
    """

    name: str
    people: str
    human: Mapping[str, float] = field(default_factory=dict)
    orca: Mapping[str, float] = field(default_factory=dict)
    groups: bool = False

    def world(self, base: WorldConfig) -> WorldConfig:
        """`base` with this model's overrides."""
        return dataclasses.replace(
            base,
            human=dataclasses.replace(base.human, **dict(self.human)),
            orca=dataclasses.replace(base.orca, **dict(self.orca)),
        )


def model_spec(name: str) -> ModelSpec:
    """The model of a command-line name: cv, sf, orca, groups, learned:PATH, or a fitted preset
    (socialzoo.humans.presets.PRESETS: sf-eth-ucy, orca-eth-ucy).

    Raises:
        ValueError: an unknown name, listing the known ones.
    """
    from socialzoo.humans.presets import PRESETS

    name = name.strip()
    if name == "cv":
        return ModelSpec("cv", "")
    if name in ("sf", "orca"):
        return ModelSpec(name, name)
    if name == "groups":
        return ModelSpec(name, "sf", groups=True)
    if name.startswith("learned:") and len(name) > len("learned:"):
        return ModelSpec(name, name)
    if name in PRESETS:
        preset = PRESETS[name]
        return ModelSpec(name, preset["model"], human=preset.get("human", {}), orca=preset.get("orca", {}))
    known = ", ".join((*BASE_MODELS, "learned:PATH", *PRESETS))
    raise ValueError(f"unknown realism model {name!r}; known: {known}")


# ---------------------------------------------------------------------------- cases
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


def _inside(cases: Cases) -> np.ndarray:
    """(n, 1 + max frames) the frames within each case."""
    span = int(cases.frames.max()) + 1 if len(cases) else 1
    return np.arange(span)[None, :] <= cases.frames[:, None]


def truth(scene: SceneTracks, cases: Cases) -> np.ndarray:
    """(n, 1 + max frames, 2) the recorded positions from each start on, NaN past a case's frames."""
    inside = _inside(cases)
    idx = cases.start[:, None] + np.arange(inside.shape[1])[None, :]
    pos = scene.grid[cases.person[:, None], np.minimum(idx, scene.grid.shape[1] - 1)]
    return np.where(inside[..., None], pos, np.nan)


def constant_velocity(scene: SceneTracks, cases: Cases) -> np.ndarray:
    """(n, 1 + max frames, 2) the constant-velocity walk from each start (NaN past its frames).

    "cv" is computed from the tracks: the start velocity kept.
    """
    inside = _inside(cases)
    p0 = scene.grid[cases.person, cases.start]
    v = start_velocity(scene, cases)
    pos = p0[:, None] + v[:, None] * (np.arange(inside.shape[1]) * scene.dt)[None, :, None]
    return np.where(inside[..., None], pos, np.nan)


# ---------------------------------------------------------------------------- simulation
@dataclass
class Rollout:
    """A model's walk of the subjects of some cases.

    Attributes:
        pos: (n, 1 + max frames, 2) the subject's position on each frame from the start, m (held
            where it left, NaN past a case's frames).
        present: (n, 1 + max frames) the subject still on the scene.
        others: (n, 1 + max frames) distance to the nearest other present person, m (inf: nobody).
    """

    pos: np.ndarray
    present: np.ndarray
    others: np.ndarray


def _row_scenario(scene: SceneTracks, k: int, start: int, frames: int, groups: bool, v0: np.ndarray) -> Any:
    """The Scenario of one case: the subject in slot 0 (a model walks it), its companions next when
    `groups` (returned as their count), everyone else present replaying."""
    from socialzoo.scenarios.recorded import people_scenario
    from socialzoo.scenarios.recorded_people import RecordedPeople

    end = start + frames
    g = scene.grid
    seen = (~np.isnan(g[:, start : end + 1, 0])).any(1)  # present on any frame of the case
    seen[k] = False
    others = np.flatnonzero(seen)
    companions = np.zeros(0, dtype=np.int64)
    if groups and len(others):
        here = ~np.isnan(g[others, start, 0]) & ~np.isnan(g[others, max(start - 1, 0), 0])
        cand = others[here]
        if len(cand) and start > 0:
            d = np.hypot(*(g[cand, start] - g[k, start]).T)
            v = (g[cand, start] - g[cand, start - 1]) / scene.dt
            close = (d <= GROUP_DISTANCE) & (np.hypot(*(v - v0).T) <= GROUP_SPEED)
            companions = cand[close]
        others = np.concatenate((companions, np.setdiff1d(others, companions)))
    order = np.concatenate(([k], others)).astype(np.int64)
    tracks = g[order, start : end + 1].copy()
    # A modelled person's track is only its start (it enters there; its route is set below).
    tracks[: 1 + len(companions), 1:] = np.nan
    follow = np.ones(len(order), dtype=bool)
    follow[: 1 + len(companions)] = False
    recorded = RecordedPeople(dt=scene.dt, tracks=tracks, follow=follow, scene=scene.name, first_frame=start)
    robot = np.array([[_PARKED, _PARKED, 0.0]])
    scenario = people_scenario(
        recorded, robot, robot + [[1.0, 0.0, 0.0]], seed=0, family=f"realism_{scene.name}"
    )
    routes = list(scenario.human_routes)
    speed = np.array(scenario.human_speed)
    for slot, person in enumerate(order[: 1 + len(companions)].tolist()):
        routes[slot] = np.stack((g[person, start], g[person, scene.last[person]]))
        speed[slot] = scene.mean_speed(person)
    spawn = np.array(scenario.human_spawn)
    spawn[0] = g[k, start]
    return (
        dataclasses.replace(scenario, human_routes=tuple(routes), human_speed=speed, human_spawn=spawn),
        order[1 : 1 + len(companions)],
    )


# A batch: the cases' indices and each one's (scenario, group companions).
Batch = tuple[np.ndarray, list[tuple[Any, np.ndarray]]]


def prepare_batches(
    scene: SceneTracks, cases: Cases, groups: bool, batch_rows: int = BATCH_ROWS
) -> list[Batch]:
    """The scenarios of the cases in batches of up to `batch_rows`, cases of similar length together."""
    v0 = start_velocity(scene, cases)
    order = np.argsort(cases.frames, kind="stable")
    out = []
    for lo in range(0, len(cases), batch_rows):
        idx = order[lo : lo + batch_rows]
        built = [
            _row_scenario(
                scene, int(cases.person[i]), int(cases.start[i]), int(cases.frames[i]), groups, v0[i]
            )
            for i in idx
        ]
        out.append((idx, built))
    return out


def simulate(
    scene: SceneTracks,
    cases: Cases,
    model: ModelSpec,
    base: WorldConfig | None = None,
    *,
    batch_rows: int = BATCH_ROWS,
    progress: Callable[[int], None] | None = None,
    batches: list[Batch] | None = None,
) -> Rollout:
    """Walk each case's subject by `model` among the replayed others, batched:
    one row per case, cases of similar length in one core.

    One subject person per batch row, its model started from its recorded state, everyone else present in the
    row replaying its track (RecordedPeople.follow), the world in the open at REALISM_DT s per step
    (FRAME_STEPS steps per 0.4 s frame). The cases are the same for every model.

    Args:
        scene: the scene.
        cases: its cases.
        model: not "cv" (constant_velocity computes that).
        base: the world before the model's overrides (default realism_world()).
        batch_rows: rows per core.
        progress: called with the number of cases done after each batch.
        batches: prepare_batches(scene, cases, model.groups), made once for many models (the
            scenarios do not depend on a model's parameters).
    """
    from socialzoo.core.walls import WallIndex
    from socialzoo.env.core import BatchedCore
    from socialzoo.humans.models import PeopleConfig

    world = model.world(base or realism_world())
    steps_per_frame = round(scene.dt / world.dt)
    if not math.isclose(steps_per_frame * world.dt, scene.dt, rel_tol=1e-9):
        raise ValueError(f"the world step {world.dt} s does not divide the frame period {scene.dt} s")
    inside = _inside(cases)
    pos = np.full((*inside.shape, 2), np.nan)
    present = np.zeros(inside.shape, dtype=bool)
    nearest = np.full(inside.shape, np.inf)
    v0 = start_velocity(scene, cases)
    walls = WallIndex(np.zeros((0, 4)))
    people = PeopleConfig(models=model.people)
    if batches is None:
        batches = prepare_batches(scene, cases, model.groups, batch_rows)
    for idx, built in batches:
        scenarios = [b[0] for b in built]
        slots = max(s.num_humans for s in scenarios)
        core = BatchedCore(len(idx), 1, slots, world, walls, people=people, robot_visible=False)
        core.reset_rows(np.arange(len(idx)), scenarios)
        state = core.state
        assert state is not None
        state.human_vel[:, 0] = v0[idx]
        for row, (_, mates) in enumerate(built):
            if len(mates):
                # The companions walk as a group with the subject (the group's id: its first slot).
                state.human_group[row, : 1 + len(mates)] = 0
                state.human_vel[row, 1 : 1 + len(mates)] = (
                    scene.grid[mates, cases.start[idx[row]]] - scene.grid[mates, cases.start[idx[row]] - 1]
                ) / scene.dt
        frames = int(cases.frames[idx].max())
        command = np.zeros((len(idx), 1, 2))
        _record(core.state, idx, 0, pos, present, nearest)
        for f in range(1, frames + 1):
            for _ in range(steps_per_frame):
                core.step(command)
            _record(core.state, idx, f, pos, present, nearest)
        if progress is not None:
            progress(len(idx))
    pos = np.where(inside[..., None], pos, np.nan)
    return Rollout(pos=pos, present=present & inside, others=np.where(inside, nearest, np.inf))


def _record(
    state: Any, idx: np.ndarray, f: int, pos: np.ndarray, present: np.ndarray, nearest: np.ndarray
) -> None:
    """Write frame f of the subjects (slot 0) of rows idx: positions (held once gone), presence and
    the nearest other present person."""
    here = state.human_mask[:, 0]
    now = state.human_pos[:, 0]
    held = pos[idx, f - 1] if f > 0 else now
    pos[idx, f] = np.where(here[:, None], now, held)
    present[idx, f] = here
    d = np.hypot(*(state.human_pos[:, 1:] - now[:, None]).transpose(2, 0, 1))
    d = np.where(state.human_mask[:, 1:], d, np.inf)
    nearest[idx, f] = d.min(1) if d.shape[1] else np.inf


def nearest_other(scene: SceneTracks, cases: Cases, pred: np.ndarray) -> np.ndarray:
    """(n, 1 + max frames) the distance of a subject walked along `pred` (n, 1 + max frames, 2) to
    the nearest other recorded person present, m (inf: nobody)."""
    out = np.full(pred.shape[:2], np.inf)
    g = scene.grid
    for i, (k, s, t) in enumerate(
        zip(cases.person.tolist(), cases.start.tolist(), cases.frames.tolist(), strict=True)
    ):
        block = g[:, s : s + t + 1]
        d = np.hypot(*(block - pred[i, : t + 1][None]).transpose(2, 0, 1))
        d[k] = np.inf
        out[i, : t + 1] = np.where(np.isnan(d), np.inf, d).min(0)
    return out


# ---------------------------------------------------------------------------- metrics
def displacement(pred: np.ndarray, true: np.ndarray, use: np.ndarray | None = None) -> tuple[float, float]:
    """(ADE, FDE), m: the mean over cases of the mean distance over frames 1.. (those `use` marks,
    (n, F)), and of the distance at each case's last frame."""
    d = np.hypot(*(pred - true).transpose(2, 0, 1))[:, 1:]
    valid = ~np.isnan(d) if use is None else ~np.isnan(d) & use[:, 1:]
    if not len(d):
        return math.nan, math.nan
    per = np.where(valid, d, 0.0).sum(1) / np.maximum(valid.sum(1), 1)
    last = (~np.isnan(d)).sum(1) - 1
    final = d[np.arange(len(d)), np.maximum(last, 0)]
    ok = valid.any(1)
    return float(per[ok].mean()) if ok.any() else math.nan, float(np.nanmean(final))


def frame_speeds(pos: np.ndarray, dt: float, use: np.ndarray | None = None) -> np.ndarray:
    """The speeds between consecutive frames (both marked by `use` and recorded), m/s, flat."""
    step = np.hypot(*np.diff(pos, axis=1).transpose(2, 0, 1)) / dt
    ok = ~np.isnan(step)
    if use is not None:
        ok &= use[:, 1:] & use[:, :-1]
    return step[ok]


def wasserstein(a: np.ndarray, b: np.ndarray) -> float:
    """The first Wasserstein distance between two samples (nan if either is empty)."""
    from scipy.stats import wasserstein_distance

    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    return float(wasserstein_distance(a, b)) if len(a) and len(b) else math.nan


def contact_rate(nearest: np.ndarray, use: np.ndarray) -> float:
    """The share of cases with a frame (of `use`) within COLLISION_DISTANCE of someone."""
    hit = ((nearest < COLLISION_DISTANCE) & use).any(1)
    return float(hit.mean()) if len(hit) else math.nan


@dataclass
class SceneResult:
    """A model's numbers on one scene (see METRICS), with the raw speeds for the figures."""

    scene: str
    model: str
    metrics: dict[str, float]
    speeds: np.ndarray


# name, heading, digits
METRICS: tuple[tuple[str, str, int], ...] = (
    ("ade", "ADE 4.8 s (m)", 3),
    ("fde", "FDE 4.8 s (m)", 3),
    ("track_ade", "track ADE (m)", 3),
    ("track_fde", "track FDE (m)", 3),
    ("speed_w1", "speed W1 (m/s)", 3),
    ("nn_w1", "NN dist W1 (m)", 3),
    ("contact_rate", "contacts (share of people)", 3),
    ("windows", "windows", 0),
    ("people", "people", 0),
)


def evaluate_model(
    scene: SceneTracks,
    windows: Cases,
    tracks: Cases,
    model: ModelSpec,
    base: WorldConfig | None = None,
    progress: Callable[[int], None] | None = None,
) -> SceneResult:
    """Every metric of `model` on a scene's cases (docs/humans.md, "Realism against recorded people")."""
    true_w, true_t = truth(scene, windows), truth(scene, tracks)
    if model.name == "cv":
        pred_w = constant_velocity(scene, windows)
        pred_t = constant_velocity(scene, tracks)
        use_t = ~np.isnan(pred_t[..., 0])
        near_t = nearest_other(scene, tracks, pred_t)
        if progress is not None:
            progress(len(windows) + len(tracks))
    else:
        pred_w = simulate(scene, windows, model, base, progress=progress).pos
        rollout = simulate(scene, tracks, model, base, progress=progress)
        pred_t, use_t, near_t = rollout.pos, rollout.present, rollout.others
    ade, fde = displacement(pred_w, true_w)
    track_ade, track_fde = displacement(pred_t, true_t, use_t)
    rec_use = ~np.isnan(true_t[..., 0])
    speeds = frame_speeds(pred_t, scene.dt, use_t)
    rec_speeds = frame_speeds(true_t, scene.dt, rec_use)
    rec_near = nearest_other(scene, tracks, true_t)
    metrics = {
        "ade": ade,
        "fde": fde,
        "track_ade": track_ade,
        "track_fde": track_fde,
        "speed_w1": wasserstein(speeds, rec_speeds),
        "nn_w1": wasserstein(near_t[use_t], rec_near[rec_use]),
        "contact_rate": contact_rate(near_t, use_t),
        "windows": float(len(windows)),
        "people": float(len(tracks)),
    }
    return SceneResult(scene.name, model.name, metrics, speeds)


def recorded_reference(scene: SceneTracks, tracks: Cases) -> SceneResult:
    """The recorded people themselves (zero errors): their speeds and contact rate, for reference."""
    true_t = truth(scene, tracks)
    use = ~np.isnan(true_t[..., 0])
    near = nearest_other(scene, tracks, true_t)
    metrics = {name: 0.0 for name, _, _ in METRICS}
    metrics.update(contact_rate=contact_rate(near, use), windows=math.nan, people=float(len(tracks)))
    return SceneResult(scene.name, "recorded", metrics, frame_speeds(true_t, scene.dt, use))


# ---------------------------------------------------------------------------- the study
@dataclass(frozen=True, kw_only=True)
class RealismConfig:
    """One realism run.

    Attributes:
        scenes: ETH/UCY scene names or track files (PATH or NAME=PATH: socialzoo.data.fetch.load_recording).
        models: model names (model_spec).
        tracks: persons per scene (a seeded sample), None for all.
        seed: the sample's seed.
        cache: the scenes' cache folder (None: socialzoo.data.fetch.data_dir()).
    """

    scenes: tuple[str, ...] = SCENES
    models: tuple[str, ...] = BASE_MODELS
    tracks: int | None = None
    seed: int = 0
    cache: str | None = None

    def __post_init__(self) -> None:
        if not self.scenes:
            raise ValueError("RealismConfig.scenes must name at least one scene")
        if not self.models:
            raise ValueError("RealismConfig.models must name at least one model")
        for name in self.models:
            model_spec(name)
        if self.tracks is not None and (not isinstance(self.tracks, int) or self.tracks < 1):
            raise ValueError(f"RealismConfig.tracks must be None or an int >= 1, got {self.tracks!r}")


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


def run_realism(
    config: RealismConfig,
    out: Path,
    *,
    progress: bool = True,
    figures: bool = True,
    argv: Sequence[str] | None = None,
) -> list[SceneResult]:
    """Run the study and write out/realism.csv, realism.md, realism.json (the run record) and the
    figures (ade.png, speeds.png); returns every scene's and model's result."""
    out.mkdir(parents=True, exist_ok=True)
    specs = [model_spec(m) for m in config.models]
    scenes = [load_tracks(s, config.cache) for s in config.scenes]
    plan = []
    for scene in scenes:
        persons = sample_persons(scene, config.tracks, config.seed)
        plan.append((scene, window_cases(scene, persons), track_cases(scene, persons)))
    total = sum((len(w) + len(t)) * len(specs) for _, w, t in plan)
    bar = progress_bar(total, "realism", enabled=progress, unit="case")
    results: list[SceneResult] = []
    started = time.perf_counter()
    for scene, windows, tracks in plan:
        results.append(recorded_reference(scene, tracks))
        for spec in specs:
            bar.set_postfix_str(f"{scene.name} {spec.name}")
            results.append(evaluate_model(scene, windows, tracks, spec, progress=bar.update))
    bar.close()
    results.extend(overall(results, [p[0].name for p in plan]))
    write_tables(results, out)
    if figures:
        write_figures(results, out)
    record = {
        "command": " ".join(["socialzoo", *(sys.argv[1:] if argv is None else argv)]),
        "config": dataclasses.asdict(config),
        "seed": config.seed,
        "world": dataclasses.asdict(realism_world()),
        "protocol": {
            "obs_frames": OBS_FRAMES,
            "pred_frames": PRED_FRAMES,
            "world_dt": REALISM_DT,
            "collision_distance": COLLISION_DISTANCE,
            "group_distance": GROUP_DISTANCE,
            "group_speed": GROUP_SPEED,
        },
        "models": {s.name: dataclasses.asdict(s) for s in specs},
        "versions": versions(),
        "seconds": round(time.perf_counter() - started, 1),
    }
    (out / "realism.json").write_text(json.dumps(record, indent=2, default=str) + "\n")
    return results


def versions() -> dict[str, str]:
    """The versions of python, socialzoo, numpy, numba and scipy."""
    import importlib.metadata as md

    out = {"python": platform.python_version()}
    for pkg in ("socialzoo", "numpy", "numba", "scipy"):
        try:
            out[pkg] = md.version(pkg)
        except md.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def overall(results: Sequence[SceneResult], scenes: Sequence[str]) -> list[SceneResult]:
    """Per model, the mean over scenes of each metric (counts summed)."""
    out = []
    for model in dict.fromkeys(r.model for r in results):
        mine = [r for r in results if r.model == model and r.scene in scenes]
        metrics = {}
        for name, _, _ in METRICS:
            vals = np.array([r.metrics[name] for r in mine], dtype=float)
            total = np.nansum if name in ("windows", "people") else np.nanmean
            metrics[name] = float(total(vals)) if np.isfinite(vals).any() else math.nan
        out.append(SceneResult("overall", model, metrics, np.concatenate([r.speeds for r in mine])))
    return out


def markdown_table(results: Sequence[SceneResult]) -> str:
    """One Markdown table: a row per scene and model (the overall rows last)."""
    header = ["scene", "model", *(h for _, h, _ in METRICS)]
    rows = [
        [r.scene, r.model]
        + [
            "" if not math.isfinite(r.metrics[name]) else f"{r.metrics[name]:.{digits}f}"
            for name, _, digits in METRICS
        ]
        for r in results
    ]
    return "\n".join(table_lines(header, rows)) + "\n"


def write_tables(results: Sequence[SceneResult], out: Path) -> None:
    """out/realism.csv and out/realism.md (a table per scene and the overall one)."""
    write_csv(
        ({"scene": r.scene, "model": r.model, **r.metrics} for r in results),
        out / "realism.csv",
        ["scene", "model", *(n for n, _, _ in METRICS)],
        blank_nan=False,
    )
    parts = ["# Realism against the recorded people\n"]
    for scene in dict.fromkeys(r.scene for r in results):
        parts.append(f"\n## {scene}\n\n" + markdown_table([r for r in results if r.scene == scene]))
    parts.append("\n## all scenes\n\n" + markdown_table(results))
    (out / "realism.md").write_text("".join(parts))


def write_figures(results: Sequence[SceneResult], out: Path) -> None:
    """out/ade.png (4.8 s ADE per model per scene) and out/speeds.png (speed histograms)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r.scene for r in results))
    models = [m for m in dict.fromkeys(r.model for r in results) if m != "recorded"]
    fig, ax = plt.subplots(figsize=(1.5 + 1.2 * len(scenes), 3.5))
    width = 0.8 / max(len(models), 1)
    for j, model in enumerate(models):
        vals = [
            next((r.metrics["ade"] for r in results if r.scene == s and r.model == model), math.nan)
            for s in scenes
        ]
        ax.bar(np.arange(len(scenes)) + j * width, vals, width, label=model)
    ax.set_xticks(np.arange(len(scenes)) + 0.4 - width / 2, scenes)
    ax.set_ylabel("ADE over 4.8 s (m)")
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(out / "ade.png", dpi=120)
    plt.close(fig)
    fig, axes = plt.subplots(1, len(scenes), figsize=(3.0 * len(scenes), 2.8), squeeze=False)
    bins = np.linspace(0.0, 3.0, 31)
    for ax, scene in zip(axes[0], scenes, strict=True):
        for r in results:
            if r.scene == scene and len(r.speeds):
                style = {"color": "k", "lw": 2.0} if r.model == "recorded" else {}
                ax.hist(r.speeds, bins=bins, density=True, histtype="step", label=r.model, **style)
        ax.set_title(scene)
        ax.set_xlabel("speed (m/s)")
    axes[0][0].legend(fontsize="x-small")
    fig.tight_layout()
    fig.savefig(out / "speeds.png", dpi=120)
    plt.close(fig)
