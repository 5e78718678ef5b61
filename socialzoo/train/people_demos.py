"""The demonstrations of people-bc: each recorded person's observation at a frame of the replay and
the action that walks it to its recorded position, with noisy copies labelled with the way back."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.train.people_replay import frame_steps, mean_speeds, replay_world, window_scenario, windows

if TYPE_CHECKING:
    from socialzoo.core.config import WorldConfig
    from socialzoo.core.state import WorldState
    from socialzoo.data.tracks import Recording

# Demonstrated actions are clipped to this (tanh reaches it at a finite mean).
ACTION_LIMIT = 0.98


def inverse_action(state: WorldState, desired: np.ndarray, frame: str, scale: float) -> np.ndarray:
    """(B, H, 2) the actions whose desired velocities (socialzoo.env.human_agents.action_velocities
    of every slot) are `desired` (B, H, 2), m/s, world frame; 0 for slots of no preferred speed."""
    from socialzoo.core.geometry import rotate
    from socialzoo.env.human_agents import human_frames

    slots = np.arange(state.max_humans)
    if frame == "human":
        desired = rotate(desired, -human_frames(state, slots))
    speed = scale * state.human_pref_speed[:, :, None]
    return np.where(speed > 0, desired / np.where(speed > 0, speed, 1.0), 0.0)


def reaching_velocity(
    v0: np.ndarray, displacement: np.ndarray, other: np.ndarray, period: float, world: WorldConfig
) -> np.ndarray:
    """The desired velocity (..., 2) that carries a person of velocity v0 over `displacement` in
    `period` s under dv/dt = c (v_d - v) / tau + other (the social force, c its desired_factor),
    other held constant. With u = v_d + tau other / c: v(t) = u + exp(-c t / tau) (v0 - u), so
    displacement = u T + (v0 - u) s with s = tau / c (1 - exp(-c T / tau)); tau is the learned
    people's (HumanConfig.learned_tau)."""
    rate = world.human.desired_factor / world.human.learned_tau
    s = (1.0 - math.exp(-rate * period)) / rate
    u = (displacement - s * v0) / (period - s)
    return u - other / rate


@dataclass(frozen=True)
class Demonstrations:
    """Observations and actions of recorded people.

    Attributes:
        obs: (N, D) float32 observations (socialzoo.env.human_agents.human_observations).
        action: (N, 2) float32 actions in [-ACTION_LIMIT, ACTION_LIMIT].
        window: (N,) the replay row (time window) of each, numbered within its scene.
        clipped: (N,) bool, the action was clipped.
    """

    obs: np.ndarray
    action: np.ndarray
    window: np.ndarray
    clipped: np.ndarray

    def __len__(self) -> int:
        return len(self.obs)

    def take(self, index: np.ndarray) -> Demonstrations:
        """The demonstrations at `index`."""
        return Demonstrations(self.obs[index], self.action[index], self.window[index], self.clipped[index])

    @staticmethod
    def concatenate(parts: Sequence[Demonstrations]) -> Demonstrations:
        """One set of several."""
        return Demonstrations(
            *(np.concatenate([getattr(p, f.name) for p in parts]) for f in dataclasses.fields(Demonstrations))
        )


def demonstrations(
    recording: Recording,
    *,
    window: int = 40,
    num_neighbours: int = 6,
    action_frame: str = "human",
    action_scale: float = 4.0,
    world: WorldConfig | None = None,
    velocity_noise: float = 0.0,
    noisy_copies: int = 0,
    label_frames: int = 1,
    seed: int = 0,
) -> Demonstrations:
    """Every demonstration of a recording (defined in socialzoo.train.people_bc.train's docstring),
    replayed in one batched core.

    With `noisy_copies` > 0, each demonstration comes `noisy_copies` more times with its own
    velocity perturbed (normal, `velocity_noise` m/s per axis, drawn from `seed`), its action the
    one that still reaches the recorded position on the next frame from the perturbed velocity:
    states a little off the recorded ones, labelled with the way back, as a person walked by the
    policy reaches them (noise injection against compounding errors: DART, Laskey et al. 2017).
    Each label reaches the recorded position `label_frames` frames ahead (held over their period).

    Raises:
        ValueError: a world step that does not divide the recording's frame period.
    """
    from socialzoo.core.walls import WallIndex
    from socialzoo.env.core import BatchedCore
    from socialzoo.env.human_agents import human_observations
    from socialzoo.env.people import without_robots
    from socialzoo.humans.social_force import human_acceleration

    world = world or replay_world()
    rng = np.random.default_rng([int(seed), 0x64617274])  # "dart"
    steps = frame_steps(recording, world)
    speeds = mean_speeds(recording)
    rows = windows(recording.num_frames, window, label_frames)
    if not rows:  # a recording of one frame: nobody moves
        return _no_demonstrations(num_neighbours)
    built = [window_scenario(recording, a, b, speeds) for a, b in rows]
    scenarios = [s for s, _ in built]
    slots = max(s.num_humans for s in scenarios)
    grids = np.full((len(rows), slots, window + 1 + label_frames, 2), np.nan)
    for i, (scenario, _) in enumerate(built):
        assert scenario.recorded is not None
        t = scenario.recorded.tracks
        grids[i, : len(t), : t.shape[1]] = t
    walls = WallIndex(np.zeros((0, 4)))
    core = BatchedCore(len(rows), 1, slots, world, walls, robot_visible=False)
    core.reset_rows(np.arange(len(rows)), scenarios)
    command = np.zeros((len(rows), 1, 2))
    every = np.arange(slots)
    out: list[Demonstrations] = []
    for f in range(1, window + 1):
        for _ in range(steps):
            core.step(command)
        state = core.state
        assert state is not None
        prev, here, nxt = grids[:, :, f - 1], grids[:, :, f], grids[:, :, f + label_frames]
        usable = ~np.isnan(prev[..., 0]) & ~np.isnan(here[..., 0]) & ~np.isnan(nxt[..., 0])
        usable &= state.human_mask & np.isclose(state.human_pos, np.nan_to_num(here)).all(-1)
        # Near its exit a person's target turns back to its entry (the waypoint radius).
        exit_dist = np.hypot(*(state.human_route[:, :, 1] - state.human_pos).transpose(2, 0, 1))
        usable &= exit_dist > world.human.waypoint_radius
        if not usable.any():
            continue
        recorded_v = np.where(usable[..., None], (here - prev) / recording.dt, state.human_vel)
        row, slot = np.nonzero(usable)
        for copy in range(noisy_copies + 1):
            v_in = recorded_v
            if copy:
                v_in = recorded_v + np.where(
                    usable[..., None], rng.normal(0.0, velocity_noise, recorded_v.shape), 0.0
                )
            seen = dataclasses.replace(state, human_vel=v_in)
            # The parked robot is seen by nobody: observed without it, as the env's people observe it.
            obs = human_observations(without_robots(seen), walls, every, num_neighbours)
            other, _ = human_acceleration(
                seen.human_pos, v_in, seen.human_target, seen.human_pref_speed, seen.human_mask,
                seen.robot_pose[:, :0, :2], np.zeros((len(rows), 0, 2)), walls, world.human, v_in,
                seen.human_mask,
            )  # fmt: skip
            desired = reaching_velocity(
                v_in, np.nan_to_num(nxt - here), other, label_frames * recording.dt, world
            )
            action = inverse_action(seen, desired, action_frame, action_scale)
            clipped = (np.abs(action) > ACTION_LIMIT).any(-1)
            out.append(
                Demonstrations(
                    obs[row, slot],
                    np.clip(action[row, slot], -ACTION_LIMIT, ACTION_LIMIT).astype(np.float32),
                    row.astype(np.int64),
                    clipped[row, slot],
                )
            )
    return Demonstrations.concatenate(out) if out else _no_demonstrations(num_neighbours)


def _no_demonstrations(num_neighbours: int) -> Demonstrations:
    """An empty set, its observations of the size num_neighbours gives."""
    return Demonstrations(
        np.zeros((0, num_neighbours * 5 + 8), np.float32),
        np.zeros((0, 2), np.float32),
        np.zeros(0, np.int64),
        np.zeros(0, bool),
    )
