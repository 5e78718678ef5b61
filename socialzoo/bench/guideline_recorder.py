"""The live path of the guidelines' Table I metrics: the world states of B rows recorded step by step, and each
episode's metrics computed from its own samples when it ends (socialzoo.bench.guideline_metrics)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from socialzoo.bench.guideline_metrics import GuidelineParams, Trajectories, guideline_metrics
from socialzoo.core.geometry import wall_distances
from socialzoo.core.state import WorldState
from socialzoo.env.world import robot_collisions, robot_velocity_vectors

if TYPE_CHECKING:
    from socialzoo.env.tasks.base import TaskStep


@dataclass(frozen=True)
class EpisodeFrame:
    """The constants of the episodes of a task that the metrics need.

    Attributes:
        dt: time between samples (one task step), s.
        robot_radius: the robot's disc for the gaps, m (a box footprint: its circumscribed circle).
        people_radius: m.
        goal_radius: the goal is reached within this centre distance, m.
        time_limit: s, or None: the timeout rule of a recorder that is not told which episodes the
            task's time limit ended (GuidelineRecorder.record without the step).
    """

    dt: float
    robot_radius: float
    people_radius: float
    goal_radius: float
    time_limit: float | None

    @classmethod
    def of(cls, task: Any) -> EpisodeFrame:
        """The frame of an action-selection or CrowdNav task (its config names the constants)."""
        core, config = task.core, task.config
        world = core.world
        robot = world.robot
        radius = robot.radius if robot.radius is not None else math.hypot(robot.length, robot.width) / 2
        dt = float(getattr(config, "time_step", world.dt))
        if hasattr(config, "goal_radius"):  # the action-selection task
            goal_radius, limit = float(config.goal_radius), config.max_steps * world.dt
        else:  # the CrowdNav task: the goal within the robot's radius, its time limit
            goal_radius, limit = float(radius), float(config.time_limit)
        return cls(dt, float(radius), float(world.human.radius), goal_radius, limit)


class GuidelineRecorder:
    """Records B rows of a task's core and gives the Table I metrics of finished episodes.

    Per sample: robot 0's centre, world velocity and distance to the nearest wall (or closed door), the people's
    centres, velocities and presence, the other robots' centres, and the world's own contact flags
    (the world step's collision rules, socialzoo.env.world.robot_collisions: a person's centre within
    the collision distance, the footprint touching a wall; a robot touching a closed door of a
    scenario script collides as with a wall), and the collisions the task judged on the step when
    `record` is given it. The samples between a row's reset and its end are its
    episode (sample 0 is the start). Samples that no running episode needs any more are dropped, so
    memory stays within the longest running episode.

    Args:
        task: the task (its `core` holds the world state).
        params: Table I's thresholds.
    """

    def __init__(self, task: Any, params: GuidelineParams | None = None) -> None:
        self.frame = EpisodeFrame.of(task)
        self.params = params or GuidelineParams()
        core = task.core
        self.walls = np.asarray(core.walls.walls, dtype=np.float64).reshape(-1, 4)
        b = core.batch_size
        self.samples: list[dict[str, np.ndarray]] = []
        self.first = 0  # the global index of samples[0]
        self.start = np.zeros(b, dtype=np.int64)  # each row's sample 0, global index
        self.goal = np.zeros((b, 2))
        self.shortest = np.full(b, np.nan)
        # Each row's episode was ended by the task's time limit (TaskStep.truncated), once record is told.
        self.truncated: np.ndarray | None = None

    def reset(self, rows: np.ndarray, task: Any) -> None:
        """Rows whose episodes start now (their state just reset): their sample 0 is the current state."""
        rows = np.asarray(rows, dtype=np.intp)
        core = task.core
        if not self.samples:
            self.record(task)
        self.start[rows] = self.first + len(self.samples) - 1
        # Overwrite the latest sample's rows with the state now (a reset after the sample was taken).
        latest = self.samples[-1]
        for key, value in self._sample(core).items():
            if latest[key].shape[1:] != value.shape[1:]:
                latest[key] = _pad_like(latest[key], value)
            latest[key][rows] = value[rows]
        state = core.state
        self.goal[rows] = state.robot_goal[rows, 0, :2]
        if self.truncated is not None:
            self.truncated[rows] = False
        route = core.route_left[rows, 0] if core.navigator is not None else None
        straight = np.hypot(*(state.robot_goal[rows, 0, :2] - state.robot_pose[rows, 0, :2]).T)
        self.shortest[rows] = straight if route is None else np.maximum(route, straight)

    def record(self, task: Any, step: TaskStep | None = None) -> None:
        """Take a sample of every row after a step; `step`: the task's judgement of that step.

        Given, an episode times out (gl_timeout) when the task's own time limit ended it
        (TaskStep.truncated), however the task applies it (CrowdNav ends an episode at the step
        starting 1 s before its time limit; a recorded scene has its own budget); and a collision
        the task judged on the step (its info's wall_collision, human_collisions) is a contact at
        this sample besides the world's own flags (CrowdNav judges one along the step, which the
        bodies may have left by its end; a person the task hit that the world's flags miss is the
        one nearest the robot). Without it, the timeout is an episode that lasted the
        frame's time_limit and the contacts are the world's alone."""
        sample = self._sample(task.core)
        self.samples.append(sample)
        if step is None:
            return
        b = len(self.start)
        if self.truncated is None:
            self.truncated = np.zeros(b, dtype=bool)
        self.truncated |= np.asarray(step.truncated, dtype=bool).reshape(b, -1)[:, 0]
        info = step.info
        if "wall_collision" in info:
            sample["wall_contact"] |= np.asarray(info["wall_collision"], dtype=bool).reshape(b, -1)[:, 0]
        if "human_collisions" in info:
            missed = np.asarray(info["human_collisions"]).reshape(b, -1)[:, 0] > 0
            rows = np.flatnonzero(missed & ~sample["human_contact"].any(axis=1))
            # The task does not say whom it hit: the person nearest the robot at the step's end.
            dist = np.hypot(
                *(sample["people_pos"][rows] - sample["robot_pos"][rows, None]).transpose(2, 0, 1)
            )
            nearest = np.where(sample["people_mask"][rows], dist, np.inf).argmin(axis=1)
            sample["human_contact"][rows, nearest] = True

    def _sample(self, core: Any) -> dict[str, np.ndarray]:
        s: WorldState = core.state
        robot = core.world.robot
        wall, human = robot_collisions(s, core.walls, core.world)
        # Measured as it is sampled: one pass over the walls per step, not per episode and sample.
        wall_distance = wall_distances(s.robot_pose[:, 0, :2], self.walls)
        if core.script.active:  # a closed door of a scenario script is a wall, for contacts and clearance
            wall = wall | core.script.door_contacts(s)
            wall_distance = np.minimum(wall_distance, core.script.closed_door_distances(s)[:, 0])
        return {
            "robot_pos": s.robot_pose[:, 0, :2].copy(),
            "robot_vel": robot_velocity_vectors(s, robot)[:, 0].copy(),
            "people_pos": s.human_pos.copy(),
            "people_vel": s.human_vel.copy(),
            "people_mask": s.human_mask.copy(),
            "others_pos": s.robot_pose[:, 1:, :2].copy(),
            "wall_distance": wall_distance,
            "wall_contact": wall[:, 0].copy(),
            "human_contact": human[:, 0].copy(),
        }

    def summaries(self, rows: np.ndarray) -> list[dict[str, Any]]:
        """The Table I metrics of the episodes of `rows`, which end at the latest sample."""
        rows = np.asarray(rows, dtype=np.intp)
        if len(rows) == 0:
            return []
        end = self.first + len(self.samples)
        lengths = end - self.start[rows]
        n = int(lengths.max())
        stacked = {key: np.stack([s[key] for s in self.samples[-n:]], axis=1) for key in self.samples[-1]}
        # Row i's episode is its last lengths[i] samples: shift each to start at 0 (pad at the end).
        offset = n - lengths
        index = np.minimum(offset[:, None] + np.arange(n)[None, :], n - 1)
        fields: dict[str, np.ndarray | None] = {
            key: np.take_along_axis(value[rows], index.reshape(index.shape + (1,) * (value.ndim - 2)), axis=1)
            for key, value in stacked.items()
        }
        if not stacked["others_pos"].shape[2]:
            fields["others_pos"] = None
        f = self.frame
        traj = Trajectories(
            dt=f.dt,
            goal=self.goal[rows],
            length=lengths,
            robot_radius=f.robot_radius,
            goal_radius=f.goal_radius,
            people_radius=f.people_radius,
            shortest_path=self.shortest[rows],
            # The task's time limit as it applied it: the end of the episodes it truncated, else none.
            time_limit=f.time_limit
            if self.truncated is None
            else np.where(self.truncated[rows], f.dt * (lengths - 1), np.inf),
            **fields,
        )
        found = guideline_metrics(traj, self.params)
        return [{name: values[i].item() for name, values in found.items()} for i in range(len(rows))]

    def forget(self, live: np.ndarray) -> None:
        """Drop the samples no episode of the `live` rows needs (call after refilling rows)."""
        live = np.asarray(live, dtype=np.intp)
        keep_from = int(self.start[live].min()) if len(live) else self.first + len(self.samples) - 1
        drop = keep_from - self.first
        if drop > 0:
            del self.samples[:drop]
            self.first = keep_from

    def rows(self, live: list[int]) -> GuidelineRecorder:
        """The recorder of the task compacted to rows `live` (socialzoo.env.compaction)."""
        out = object.__new__(GuidelineRecorder)
        out.frame, out.params, out.walls = self.frame, self.params, self.walls
        out.samples = [{key: value[live] for key, value in s.items()} for s in self.samples]
        out.first = self.first
        out.start, out.goal, out.shortest = self.start[live], self.goal[live], self.shortest[live]
        out.truncated = None if self.truncated is None else self.truncated[live]
        return out


def _pad_like(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    out = np.zeros(old.shape[:1] + new.shape[1:], dtype=old.dtype)
    out[(slice(None),) + tuple(slice(0, s) for s in old.shape[1:])] = old
    return out
