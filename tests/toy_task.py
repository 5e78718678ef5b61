"""A toy robot task in one file, to show (and test) that a new task needs nothing but its own class.

Reach a goal among people with four discrete actions (forward, turn left, turn right, stop) on the
shared batched core: the core steps the world, the people and the time limit; this class says how an
action becomes a command, what the robot observes (its goal and the three nearest people in its own
frame) and what it is rewarded for (metres gained, 10 at the goal, -1 per step touching someone).
Registered with one line: `register_task("socialzoo-test/ToyReach-v0", "toy_task:ToyReachTask")`.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces

from socialzoo.env.config import EnvConfig
from socialzoo.env.core import SocialNavCore
from socialzoo.env.scenario_source import ScenarioStream
from socialzoo.env.tasks.base import Task, TaskStep, fixed_cases

# (v, omega) of each action as a fraction of the robot's top speeds.
COMMANDS = np.array([[1.0, 0.0], [0.3, 1.0], [0.3, -1.0], [0.0, 0.0]])
NEAREST = 3


class ToyReachTask(Task):
    """Reach the goal among people (see the module docstring)."""

    name: ClassVar[str] = "toy_reach"
    render_modes: ClassVar[tuple[str, ...]] = ("rgb_array",)
    render_fps: ClassVar[int] = 40

    def __init__(self, config: EnvConfig | None = None, batch_size: int = 1, **overrides: Any) -> None:
        defaults = {"map": "open_room", "max_steps": 300, "robot_action": "velocity"}
        self.config = EnvConfig.resolve(config, {**defaults, **overrides})
        self.core = SocialNavCore(self.config, batch_size)
        self.scenarios = ScenarioStream.for_config(self.core.map, batch_size, self.config)
        self.batch_size = batch_size
        self.num_robots = self.config.num_robots
        self.num_human_slots = self.config.max_humans
        self.observation_space = spaces.Box(-np.inf, np.inf, (4 + 4 * NEAREST,), np.float32)
        self.action_space = spaces.Discrete(len(COMMANDS))

    def seed(self, seed: int | None) -> None:
        self.scenarios.seed(seed)

    def case_splits(self) -> dict[str, int]:
        return {"test": 20}

    def reset(self, rows: np.ndarray, options: dict[str, Any]) -> np.ndarray:
        cases = fixed_cases(dict(options), rows, self.case_splits(), self.name)
        if cases is None:
            scenarios = self.scenarios.next(rows)
        else:  # test case k: the scenario of seed 10**6 + k, never drawn in training
            scenarios = [self.scenarios.make(10**6 + int(k)) for k in cases[1]]
        self.core.reset_rows(rows, scenarios)
        return np.array([s.seed for s in scenarios], dtype=np.uint64)

    def step(self, action: np.ndarray, human_action: np.ndarray | None = None) -> TaskStep:
        index = np.asarray(action).reshape(self.batch_size, self.num_robots)
        if ((index < 0) | (index >= len(COMMANDS))).any():
            raise ValueError(f"toy_reach: actions must be in 0..{len(COMMANDS) - 1}, got {index.tolist()}")
        result = self.core.step(COMMANDS[index])
        reward = result.progress + 10.0 * result.reached - 1.0 * (result.human_collisions > 0)
        return TaskStep(
            reward=np.where(result.terminated | result.truncated | ~self.core.done, reward, 0.0),
            terminated=result.terminated,
            truncated=result.truncated,
            info={"reached": result.reached, "human_collisions": result.human_collisions},
            time_up=self.core.state.step_count >= self.config.max_steps,
        )

    def observations(self) -> np.ndarray:
        s = self.core.state
        pose = s.robot_pose
        c, n = np.cos(pose[..., 2]), np.sin(pose[..., 2])

        def robot_frame(v: np.ndarray) -> np.ndarray:  # (B, R, ..., 2) world -> robot frame
            cc, nn = c.reshape(c.shape + (1,) * (v.ndim - 3)), n.reshape(n.shape + (1,) * (v.ndim - 3))
            return np.stack((cc * v[..., 0] + nn * v[..., 1], cc * v[..., 1] - nn * v[..., 0]), axis=-1)

        goal = robot_frame(s.robot_goal[..., :2] - pose[..., :2])
        offset = s.human_pos[:, None] - pose[..., None, :2]
        dist = np.where(s.human_mask[:, None], np.hypot(offset[..., 0], offset[..., 1]), np.inf)
        nearest = np.argsort(dist, axis=-1, kind="stable")[..., :NEAREST]
        seen = np.take_along_axis(np.isfinite(dist), nearest, axis=-1)[..., None]
        people = np.concatenate(
            (
                robot_frame(np.take_along_axis(offset, nearest[..., None], axis=2)),
                robot_frame(
                    np.take_along_axis(
                        np.broadcast_to(s.human_vel[:, None], offset.shape), nearest[..., None], 2
                    )
                ),
            ),
            axis=-1,
        )
        people = np.where(seen, people, 0.0).reshape(pose.shape[:2] + (-1,))
        return np.concatenate((goal, s.robot_vel, people), axis=-1).astype(np.float32)

    def episode_metrics(self, rows: np.ndarray, robot: int = 0) -> list[dict[str, Any]]:
        return self.core.episode_summaries(rows, robot)

    @property
    def info_keys(self) -> tuple[str, ...]:
        return ("reached", "human_collisions")

    def initial_info(self) -> dict[str, Any]:
        return {"reached": False, "human_collisions": 0}

    def idle_action(self) -> Any:
        return 3

    def action_labels(self) -> tuple[str, ...]:
        return ("forward", "left", "right", "stop")

    @property
    def world_state(self) -> Any:
        return self.core.state

    def make_renderer(self, render_mode: str, view: str = "follow") -> Any:
        from socialzoo.env.rendering import CoreRenderer

        return CoreRenderer(self.core, render_mode, view=view)


class ToyHeadForGoal:
    """An engineered policy of the toy task: turn towards the goal, then drive forward."""

    reads_core = False

    def act(self, obs: np.ndarray, core: Any = None) -> np.ndarray:
        angle = np.arctan2(obs[..., 1], obs[..., 0])  # the goal's bearing in the robot frame
        return np.where(angle > 0.3, 1, np.where(angle < -0.3, 2, 0)).astype(np.int64)

    def config(self) -> dict[str, Any]:
        return {}
