"""The episode viewer's recorder: run policies on one scenario and keep every step's arrays
(socialzoo.render.replay_data.EpisodeTrace), for `socialzoo replay`."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.agents import Policy, make_policy
from socialzoo.bench.episode_play import episode_outcome, play_episode, scenario_task, step_seconds
from socialzoo.core.config import LaserConfig
from socialzoo.core.laser import laser_scan, ray_angles
from socialzoo.core.validation import check_int
from socialzoo.env.config import EnvConfig
from socialzoo.env.scenario_source import ScenarioStream
from socialzoo.maps.map_file import Map, load_map
from socialzoo.render.replay_data import EpisodeTrace, ReplayScene
from socialzoo.scenarios.scenario import Scenario

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class PolicySpec:
    """A policy to record: its registry name, make_policy keyword arguments, and panel label.

    Attributes:
        name: registry name (socialzoo.agents.POLICIES).
        kwargs: make_policy keyword arguments, e.g. {"path": "ppo.zip"} for a learned policy.
        label: the panel's title (default: the name, with the file name for a learned policy).
    """

    name: str
    kwargs: dict[str, Any]
    label: str

    @classmethod
    def parse(cls, text: str) -> PolicySpec:
        """The spec of "name", "name=PATH" or "name:PATH" (a learned policy's saved file).

        Raises:
            ValueError: an empty name.
        """
        name, _, path = text.partition("=") if "=" in text else text.partition(":")
        name = name.strip().lower()
        if not name:
            raise ValueError(f"a policy must be NAME or NAME=PATH, got {text!r}")
        if path:
            return cls(name, {"path": path}, f"{name} ({Path(path).name})")
        return cls(name, {}, name)

    def build(self) -> Policy:
        """The policy (make_policy).

        Raises:
            ValueError: an unknown name, or arguments the policy does not take (e.g. a path for
                an engineered policy).
        """
        try:
            return make_policy(self.name, **self.kwargs)
        except TypeError as err:
            raise ValueError(f"policy {self.name!r} cannot be built with {self.kwargs}: {err}") from None


def benchmark_scenario(env_config: EnvConfig, seed: int, world_map: Map | None = None) -> Scenario:
    """The scenario of `seed` as `socialzoo demo` makes it: the env config's scenario generator
    (the benchmark's, or its scenario family's) with the config's robot count."""
    m = world_map if world_map is not None else load_map(env_config.map_name)
    stream = ScenarioStream(m, 1, env_config.num_robots, env_config.scenario, env_config.family)
    return stream.make(seed)


def record_episode(
    env_config: EnvConfig,
    scenario: Scenario,
    policy: Policy,
    *,
    label: str | None = None,
    laser_rays: int | None = None,
    laser_stride: int = 1,
    world_map: Map | None = None,
) -> EpisodeTrace:
    """Run `policy` on `scenario` of the action-selection task until the episode ends and keep
    every state and step (record_task_episode on an ActionSelectionTask of env_config).

    Args:
        env_config: the env (map, time limit, ...); robot 0 is recorded.
        scenario: the scenario to play.
        policy: a socialzoo.agents Policy.
        label: the panel's title (default: the policy's name).
        laser_rays: as record_task_episode.
        laser_stride: as record_task_episode.
        world_map: the already loaded map of env_config.map, if at hand.

    Returns:
        The EpisodeTrace, with the episode's metrics (the same as the benchmark's for this
        scenario, env config and policy).
    """
    task = scenario_task(env_config, scenario, world_map)
    return record_task_episode(task, policy, label=label, laser_rays=laser_rays, laser_stride=laser_stride)


def case_task(env_id: str, split: str, case: int, **overrides: Any) -> Any:
    """A task of one row of any registered task id (socialzoo.bench.task_benchmark.TaskId), reset to
    play case `case` of a split; `overrides` are the task's config fields."""
    from socialzoo.bench.task_benchmark import TaskId

    task = TaskId.of(env_id).make(1, **overrides)
    task.reset(np.array([0]), {"split": split, "cases": [case]})
    return task


def record_case(
    env_id: str, policy: Policy, split: str, case: int, *, label: str | None = None, **overrides: Any
) -> tuple[EpisodeTrace, Any]:
    """(the trace, the task) of `policy` on case `case` of a split of any registered task id
    (case_task); `overrides` are the task's config fields."""
    task = case_task(env_id, split, case, **overrides)
    return record_task_episode(task, policy, label=label), task


def record_task_episode(
    task: Any,
    policy: Policy,
    *,
    label: str | None = None,
    laser_rays: int | None = None,
    laser_stride: int = 1,
) -> EpisodeTrace:
    """Run `policy` on row 0 of a task of one row (already reset) until robot 0's episode ends,
    keeping every state and step: the world's bodies, the task's guides and scan for the viewer
    (Task.viewer_guides, viewer_laser) and its per-step force, blame and collisions where its
    info has them.

    The env does not compute the laser scan by default; the recorder scans every state itself
    (socialzoo.core.laser), which changes nothing in the episode.

    Args:
        task: a socialzoo.env.tasks Task of batch size 1, reset.
        policy: an object with act(observations, task).
        label: the panel's title (default: the policy's name).
        laser_rays: scan with this many rays over the same field of view (default: the laser's
            own count; 0: no scan); every ray's range is exact, there are just fewer of them.
        laser_stride: scan every `laser_stride` states (and the last one): a scan of gdc1 costs
            about as much as a step.
    """
    check_int("record_episode", "laser_stride", laser_stride, low=1)
    check_int("record_episode", "laser_rays", laser_rays, low=0, allow_none=True)
    scan = task.viewer_laser()
    if scan is not None and laser_rays:
        scan = (dataclasses.replace(scan[0], num_rays=laser_rays), *scan[1:])
    recorder = _Recorder(task, None if laser_rays == 0 else scan)
    recorder.keep_state(scan=True)
    named = bool(task.action_labels())  # the timeline shows actions that have names
    for action, step, ended in play_episode(task, policy):
        recorder.keep_step(int(action.reshape(-1)[0]) if named else -1, step)
        recorder.keep_state(scan=len(recorder.actions) % laser_stride == 0 or ended)
    name = getattr(policy, "name", type(policy).__name__)
    return recorder.trace(label or str(name))


class _Recorder:
    """The lists one episode of a batch-of-one task fills, state by state and step by step."""

    def __init__(self, task: Any, laser: tuple[Any, Any, float] | None) -> None:
        state = task.world_state
        self.task = task
        self.laser = laser
        self.goal = np.asarray(state.robot_goal[0, 0], dtype=np.float64).copy()
        self.start = np.asarray(state.robot_pose[0, 0, :2], dtype=np.float64).copy()
        self.holonomic = getattr(getattr(task.config, "robot", None), "kinematics", None) == "holonomic"
        self.states: dict[str, list[np.ndarray]] = {
            k: [] for k in ("pose", "vel", "others", "humans", "human_vel", "human_mask", "carrot")
        }
        self.plans: list[np.ndarray] = []
        self.plan_index: list[int] = []
        self.scans: list[np.ndarray] = []
        self.scanned: list[int] = []
        self.actions: list[int] = []
        self.steps: dict[str, list[Any]] = {
            k: [] for k in ("target", "reward", "force", "blame", "contacts", "wall")
        }
        self.last: Any = None  # the last TaskStep

    def keep_state(self, scan: bool) -> None:
        """Keep the task's current state (and scan it when `scan`)."""
        s = self.task.world_state
        kept = self.states
        pose, vel = s.robot_pose[0, 0].copy(), s.robot_vel[0, 0].copy()
        if self.holonomic:  # (vx, vy): the viewer shows the heading along the velocity, and the speed
            from socialzoo.core.robot import world_velocity

            velocity = world_velocity(s.robot_pose[0, 0], s.robot_vel[0, 0], self.task.config.robot)
            speed = float(np.hypot(*velocity))
            if speed > 1e-6:
                pose[2] = np.arctan2(velocity[1], velocity[0])
            vel = np.array([speed, 0.0])
        kept["pose"].append(pose)
        kept["vel"].append(vel)
        kept["others"].append(s.robot_pose[0, 1:].copy())
        # Every slot: people of a recorded scene enter and leave (the trace keeps those ever present).
        kept["humans"].append(s.human_pos[0].copy())
        kept["human_vel"].append(s.human_vel[0].copy())
        kept["human_mask"].append(s.human_mask[0].copy())
        carrot, path = self.task.viewer_guides(0)
        kept["carrot"].append(self.goal[:2].copy() if carrot is None else carrot)
        path = np.array([self.start, self.goal[:2]]) if path is None else path
        if not self.plans or self.plans[-1].shape != path.shape or not np.array_equal(self.plans[-1], path):
            self.plans.append(path)
        self.plan_index.append(len(self.plans) - 1)
        # Without a laser only the start state gets its (empty) scan.
        if (scan and self.laser is not None) or not self.scanned:
            if self.laser is not None:
                laser, walls, radius = self.laser
                ranges = laser_scan(s, walls, laser, radius)[0, 0]
            else:
                ranges = np.zeros(0)
            self.scans.append(ranges)
            self.scanned.append(len(kept["pose"]) - 1)

    def keep_step(self, action: int, step: Any) -> None:
        """Keep the step's action and the values of its TaskStep (row 0, robot 0)."""
        self.actions.append(action)
        steps, info = self.steps, step.info

        def value(key: str, default: Any) -> Any:
            return info[key][0, 0] if key in info else default

        steps["target"].append(int(value("target_human", -1)))  # a slot; trace() maps it
        steps["reward"].append(float(step.reward[0, 0]))
        steps["force"].append(float(value("force", 0.0)))
        steps["blame"].append(float(value("blame", 0.0)))
        steps["contacts"].append(int(value("human_collisions", 0)))
        steps["wall"].append(bool(value("wall_collision", False)))
        self.last = step

    def trace(self, label: str) -> EpisodeTrace:
        """The EpisodeTrace of what was kept, with the episode's metrics."""
        metrics = self.task.episode_metrics(np.array([0]))[0]
        kept, steps = self.states, self.steps
        count = len(kept["pose"])
        mask = np.array(kept["human_mask"], dtype=bool).reshape(count, -1)
        present = np.flatnonzero(mask.any(axis=0))  # the slots anyone fills during the episode
        # Slot -> index among those kept; the extra last entry stays -1, so "no target" (-1) is -1.
        slot_to_kept = np.full(mask.shape[1] + 1, -1, dtype=np.int64)
        slot_to_kept[present] = np.arange(len(present))
        laser = self.laser[0] if self.laser is not None else None
        return EpisodeTrace(
            label=label,
            dt=step_seconds(self.task),
            robot_pose=np.array(kept["pose"]),
            robot_vel=np.array(kept["vel"]),
            other_robots=np.array(kept["others"]).reshape(count, -1, 3),
            goal=self.goal,
            human_pos=np.array(kept["humans"]).reshape(count, -1, 2)[:, present],
            human_vel=np.array(kept["human_vel"]).reshape(count, -1, 2)[:, present],
            human_present=mask[:, present],
            carrot=np.array(kept["carrot"]),
            plans=tuple(self.plans),
            plan_index=np.array(self.plan_index),
            laser_angles=ray_angles(laser) if laser else np.zeros(0),
            laser_steps=np.array(self.scanned, dtype=np.int64),
            laser_ranges=np.array(self.scans).reshape(len(self.scanned), -1),
            laser_max_range=laser.max_range if laser else LaserConfig().max_range,
            action=np.array(self.actions, dtype=np.int64),
            target_human=slot_to_kept[np.array(steps["target"], dtype=np.int64)],
            reward=np.array(steps["reward"], dtype=np.float64),
            force=np.array(steps["force"], dtype=np.float64),
            blame=np.array(steps["blame"], dtype=np.float64),
            human_collisions=np.array(steps["contacts"], dtype=np.int64),
            wall_collision=np.array(steps["wall"], dtype=bool),
            metrics=metrics,
            outcome=episode_outcome(metrics, self.last),
        )


def replay_scene(env_config: EnvConfig, world_map: Map, title: str, subtitle: str = "") -> ReplayScene:
    """The scene every panel of the action-selection task shares (its Task.viewer_scene)."""
    from socialzoo.env.tasks.action_selection import ActionSelectionTask

    return ActionSelectionTask(env_config, 1, map_data=world_map).viewer_scene(title, subtitle, ())


def record_policies(
    env_config: EnvConfig,
    scenario: Scenario,
    policies: Sequence[PolicySpec],
    *,
    laser_rays: int | None = None,
    laser_stride: int = 1,
    world_map: Map | None = None,
) -> list[EpisodeTrace]:
    """Record each policy on the same scenario (one panel each, in order); `laser_rays` and
    `laser_stride` as in `record_episode`.

    Each policy runs its own batch-of-one core, so a recording is the same episode the benchmark runner
    plays for that scenario (rows of a batch never interact).

    Raises:
        ValueError: no policies, or an unknown policy name (make_policy's message).
    """
    if not policies:
        raise ValueError("record_policies: at least one policy is needed")
    m = world_map if world_map is not None else load_map(env_config.map_name)
    built = [(spec, spec.build()) for spec in policies]  # fail on a bad name before any episode runs
    traces = []
    for spec, policy in built:
        trace = record_episode(
            env_config,
            scenario,
            policy,
            label=spec.label,
            laser_rays=laser_rays,
            laser_stride=laser_stride,
            world_map=m,
        )
        logger.debug("replay: %s: %s in %d steps", spec.label, trace.outcome, trace.num_steps)
        traces.append(trace)
    return traces
