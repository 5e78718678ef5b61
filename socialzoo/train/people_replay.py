"""The replay people-bc learns from and is measured on: a recording's time windows as scenarios
of the batched core, everyone following its track and a robot parked far away."""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from socialzoo.core.config import WorldConfig
    from socialzoo.data.tracks import Recording
    from socialzoo.scenarios.scenario import Scenario

# The world step of the replay, s (4 steps per 0.4 s frame).
WORLD_DT = 0.1
# The parked robot's distance from the scene, m.
_PARKED = 1.0e4


def replay_world(
    dt: float = WORLD_DT, learned_forces: bool = False, relaxation_time: float | None = None
) -> WorldConfig:
    """The world of the replay: the default people at `dt` s per step, the forces acting on learned
    people or not (HumanConfig.learned_forces), their relaxation time (None: the people's)."""
    from socialzoo.core.config import HumanConfig, WorldConfig

    return WorldConfig(
        dt=dt, human=HumanConfig(learned_forces=learned_forces, learned_relaxation_time=relaxation_time)
    )


def frame_steps(recording: Recording, world: WorldConfig) -> int:
    """World steps per recorded frame; ValueError if the world step does not divide the frame period."""
    steps = round(recording.dt / world.dt)
    if steps < 1 or not math.isclose(steps * world.dt, recording.dt, rel_tol=1e-9):
        raise ValueError(f"the world step {world.dt} s does not divide the frame period {recording.dt} s")
    return steps


# ---------------------------------------------------------------------------- scenes
def mean_speeds(recording: Recording) -> np.ndarray:
    """(N,) each track's mean recorded speed, at least MIN_SPEED, m/s (as a recorded scene's people
    walk: socialzoo.scenarios.recorded_people)."""
    from socialzoo.scenarios.recorded_people import mean_speed

    return np.array([mean_speed(t.positions, recording.dt) for t in recording.tracks])


def window_scenario(
    recording: Recording, first: int, last: int, speeds: np.ndarray, *, subject: int | None = None
) -> tuple[Scenario, np.ndarray]:
    """The scenario of frames first..last of a recording: everyone seen on them follows its track
    (but `subject`, in slot 0, whom a model walks), each one's route its entry and its recorded exit,
    its speed its mean recorded speed; a robot parked far away. Returns it and the slots' tracks."""
    from socialzoo.scenarios.recorded import people_scenario
    from socialzoo.scenarios.recorded_people import RecordedPeople

    seen = [k for k, t in enumerate(recording.tracks) if t.first_frame <= last and t.last_frame >= first]
    if subject is not None:
        seen = [subject] + [k for k in seen if k != subject]
    order = np.array(seen, dtype=np.int64)
    grid = recording.grid(seen, first, last)
    follow = np.ones(len(order), dtype=bool)
    if subject is not None:
        follow[0] = False
    recorded = RecordedPeople(
        dt=recording.dt, tracks=grid, follow=follow, scene=recording.name, first_frame=first, persons=order
    )
    robot = np.array([[_PARKED, _PARKED, 0.0]])
    scenario = people_scenario(
        recorded, robot, robot + [[1.0, 0.0, 0.0]], seed=0, family=f"people_bc_{recording.name}"
    )
    # The exit repeated to the length of the recorded route (the replay sizes its route frames by it).
    routes = tuple(
        np.concatenate((route[:1], np.repeat(recording.tracks[k].positions[-1:], max(len(route) - 1, 1), 0)))
        for route, k in zip(scenario.human_routes, seen, strict=True)
    )
    return dataclasses.replace(scenario, human_routes=routes, human_speed=speeds[order]), order


def windows(num_frames: int, window: int, ahead: int = 1) -> list[tuple[int, int]]:
    """The replay's rows: frames (first, last) with first = start - 1 (the frame before the first
    demonstrated one) and last = start + window + ahead - 1 (`ahead` frames after the last
    demonstrated one: the frames its label reaches), starts every `window`."""
    return [
        (max(s - 1, 0), min(s + window + ahead - 1, num_frames - 1)) for s in range(0, num_frames - 1, window)
    ]
