"""The closed-loop measure of people-bc: how far a learned human policy, walking a recorded person from
its recorded position and velocity while everyone else replays, strays from its recorded positions."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.scenarios.recorded_people import exit_route
from socialzoo.train.people_replay import frame_steps, mean_speeds, replay_world, window_scenario

if TYPE_CHECKING:
    from socialzoo.core.config import WorldConfig
    from socialzoo.data.tracks import Recording
    from socialzoo.scenarios.scenario import Scenario

# Frames a person walks closed-loop in the held-out measure (4.8 s, the realism study's horizon).
HORIZON = 12


def subject_cases(recording: Recording, first: int, last: int, horizon: int = HORIZON) -> np.ndarray:
    """(n, 2) cases (person, start frame) of closed-loop walks within frames first..last: each
    person's starts every `horizon` frames from its second frame (it walks in with the velocity of
    frames start - 1 to start), each with its next `horizon` frames recorded."""
    cases = [
        (k, s)
        for k, t in enumerate(recording.tracks)
        for s in range(max(t.first_frame + 1, first + 1), min(t.last_frame, last) - horizon + 1, horizon)
    ]
    return np.array(cases, dtype=np.int64).reshape(-1, 2)


def closed_loop_ade(
    recording: Recording,
    cases: np.ndarray,
    policy: Path,
    *,
    horizon: int = HORIZON,
    world: WorldConfig | None = None,
    rows: int = 256,
) -> np.ndarray:
    """(n,) each case's mean distance, m, to its recorded positions over `horizon` frames when the
    learned human policy file `policy` walks its person from its recorded position and velocity,
    everyone else on the scene replaying (window_scenario): one batch row per case, `rows` rows per
    core. As in the realism study (socialzoo.studies.realism_simulation), the person's route ends the
    waypoint radius beyond its exit (exit_route), so one walking towards it leaves at its exit, not
    the radius short of it, and is held where it left.

    Raises:
        ValueError: a world step that does not divide the recording's frame period.
    """
    from socialzoo.core.walls import WallIndex
    from socialzoo.env.core import BatchedCore
    from socialzoo.humans.models import PeopleConfig

    world = world or replay_world()
    steps = frame_steps(recording, world)
    speeds = mean_speeds(recording)
    walls = WallIndex(np.zeros((0, 4)))
    reach = world.human.waypoint_radius
    people = PeopleConfig(models=f"learned:{policy}")
    ade = np.zeros(len(cases))
    for lo in range(0, len(cases), rows):
        batch = [(int(k), int(s)) for k, s in cases[lo : lo + rows]]
        scenarios = [
            leaving_at_exit(window_scenario(recording, s, s + horizon, speeds, subject=k)[0], reach)
            for k, s in batch
        ]
        truth = np.stack([recording.grid([k], s - 1, s + horizon)[0] for k, s in batch])
        core = BatchedCore(
            len(batch), 1, max(sc.num_humans for sc in scenarios), world, walls, people=people, robot_visible=False
        )  # fmt: skip
        core.reset_rows(np.arange(len(batch)), scenarios)
        assert core.state is not None
        core.state.human_vel[:, 0] = (truth[:, 1] - truth[:, 0]) / recording.dt
        command = np.zeros((len(batch), 1, 2))
        held = truth[:, 1].copy()
        for f in range(1, horizon + 1):
            for _ in range(steps):
                core.step(command)
            state = core.state
            held = np.where(state.human_mask[:, :1], state.human_pos[:, 0], held)
            ade[lo : lo + len(batch)] += np.hypot(*(held - truth[:, f + 1]).T) / horizon
    return ade


def leaving_at_exit(scenario: Scenario, reach: float) -> Scenario:
    """window_scenario's `scenario` with its subject's (slot 0) route points after its entry moved `reach` m
    beyond its exit (exit_route), so that it leaves at its exit; window_scenario itself, which people_demos
    builds the demonstrations from, keeps the exit."""
    route = scenario.human_routes[0]
    end = exit_route(route[0], route[-1], reach)[1]
    subject = np.concatenate((route[:1], np.repeat(end[None], len(route) - 1, 0)))
    return dataclasses.replace(scenario, human_routes=(subject, *scenario.human_routes[1:]))
