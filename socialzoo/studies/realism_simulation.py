"""The crowd models of the realism study and how they walk its cases: each case's subject walked by a model
among the recorded others replayed, one batch row per case ("cv" aside: realism_cases.constant_velocity)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from socialzoo.core.config import HumanConfig, OrcaConfig, RobotConfig, WorldConfig
from socialzoo.scenarios.recorded_people import COMPANION_DISTANCE, COMPANION_SPEED, exit_route
from socialzoo.studies.realism_cases import Cases, SceneTracks, frames_inside, start_velocity

# The world step, s, and world steps per recorded frame (0.4 s at 2.5 Hz).
REALISM_DT = 0.1
# People's radius, m (CrowdNav's, socialzoo.env.crowd_config).
HUMAN_RADIUS = 0.3
# A recorded companion of a "groups" subject: within this distance at the start, m, and with a
# velocity within GROUP_SPEED of the subject's, m/s (the recorded scenes' companions' rule).
GROUP_DISTANCE = COMPANION_DISTANCE
GROUP_SPEED = COMPANION_SPEED
# Batch rows per core.
BATCH_ROWS = 512
# The robot every row must have, parked far away, invisible, still.
_PARKED = 1.0e4
BASE_MODELS = ("cv", "sf", "orca", "groups")


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
            human=dataclasses.replace(base.human, **dict[str, Any](self.human)),
            orca=dataclasses.replace(base.orca, **dict[str, Any](self.orca)),
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


def _row_scenario(
    scene: SceneTracks, k: int, start: int, frames: int, groups: bool, v0: np.ndarray, reach: float
) -> Any:
    """The Scenario of one case: the subject in slot 0 (a model walks it), its companions next when
    `groups` (returned as their count), everyone else present replaying; the modelled people's routes
    end `reach` m beyond their exits (exit_route)."""
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
        routes[slot] = exit_route(g[person, start], g[person, scene.last[person]], reach)
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
    scene: SceneTracks, cases: Cases, groups: bool, batch_rows: int = BATCH_ROWS, reach: float | None = None
) -> list[Batch]:
    """The scenarios of the cases in batches of up to `batch_rows`, cases of similar length together;
    `reach`: the world's waypoint radius, m (default realism_world()'s)."""
    reach = realism_world().human.waypoint_radius if reach is None else reach
    v0 = start_velocity(scene, cases)
    order = np.argsort(cases.frames, kind="stable")
    out = []
    for lo in range(0, len(cases), batch_rows):
        idx = order[lo : lo + batch_rows]
        built = [
            _row_scenario(
                scene, int(cases.person[i]), int(cases.start[i]), int(cases.frames[i]), groups, v0[i], reach
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
    inside = frames_inside(cases)
    pos = np.full((*inside.shape, 2), np.nan)
    present = np.zeros(inside.shape, dtype=bool)
    nearest = np.full(inside.shape, np.inf)
    v0 = start_velocity(scene, cases)
    walls = WallIndex(np.zeros((0, 4)))
    people = PeopleConfig(models=model.people)
    if batches is None:
        batches = prepare_batches(scene, cases, model.groups, batch_rows, world.human.waypoint_radius)
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
