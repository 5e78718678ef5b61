"""A toy robot task in one file, to show (and test) that a new task needs nothing but its own class.

Reach a goal among people with four discrete actions (forward, turn left, turn right, stop) on the
shared batched core (socialzoo.env.core.BatchedCore): the core steps the world and the people; this
class says how an action becomes a command, what the robot observes (its goal and the three nearest
people in its own frame), what it is rewarded for (metres gained, 10 at the goal, -1 per step
touching someone), when its episode ends (the goal, a wall, the time limit) and its metrics.
Registered with one line: `register_task("socialzoo-test/ToyReach-v0", "toy_task:ToyReachTask")`.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces

from socialzoo.env.config import EnvConfig
from socialzoo.env.core import BatchedCore
from socialzoo.env.scenario_source import ScenarioStream
from socialzoo.env.tasks.base import Task, TaskStep, fixed_cases
from socialzoo.maps.map_file import load_map

# (v, omega) of each action as a fraction of the robot's top speeds.
COMMANDS = np.array([[1.0, 0.0], [0.3, 1.0], [0.3, -1.0], [0.0, 0.0]])
NEAREST = 3


class ToyReachTask(Task):
    """Reach the goal among people (see the module docstring)."""

    name: ClassVar[str] = "toy_reach"
    render_modes: ClassVar[tuple[str, ...]] = ("rgb_array",)
    render_fps: ClassVar[int] = 40

    def __init__(self, config: EnvConfig | None = None, batch_size: int = 1, **overrides: Any) -> None:
        # The task's own defaults apply only without a config: a given config is whole (the
        # evaluation rebuilds a task from the config an id's kwargs resolved to).
        defaults = {"map": "open_room", "max_steps": 300} if config is None else {}
        self.config = cfg = EnvConfig.resolve(config, {**defaults, **overrides})
        m = load_map(cfg.map)
        self.core = BatchedCore(batch_size, cfg.num_robots, cfg.max_humans, cfg.world, m.wall_index, m=m)
        self.scenarios = ScenarioStream.for_config(m, batch_size, cfg)
        self.batch_size = batch_size
        self.num_robots = cfg.num_robots
        self.num_human_slots = cfg.max_humans
        self.speeds = np.array([cfg.world.robot.max_speed, cfg.world.robot.max_angular_speed])
        # Per robot, in the episode so far: steps, the goal reached, anyone touched.
        self.steps = np.zeros((batch_size, self.num_robots), dtype=np.int64)
        self.reached = np.zeros((batch_size, self.num_robots), dtype=bool)
        self.touched = np.zeros((batch_size, self.num_robots), dtype=bool)
        self.observation_space = spaces.Box(-np.inf, np.inf, (4 + 4 * NEAREST,), np.float32)
        self.action_space = spaces.Discrete(len(COMMANDS))

    def seed(self, seed: int | None, rows: np.ndarray | None = None) -> None:
        self.scenarios.seed(seed, rows)

    def case_splits(self) -> dict[str, int]:
        return {"test": 20}

    def reset(self, rows: np.ndarray, options: dict[str, Any]) -> np.ndarray:
        cases = fixed_cases(dict(options), rows, self.case_splits(), self.name)
        if cases is None:
            scenarios = self.scenarios.next(rows)
        else:  # test case k: the scenario of seed 10**6 + k, never drawn in training
            scenarios = [self.scenarios.make(10**6 + int(k)) for k in cases[1]]
        self.core.reset_rows(rows, scenarios)
        self.steps[rows], self.reached[rows], self.touched[rows] = 0, False, False
        return np.array([s.seed for s in scenarios], dtype=np.uint64)

    def command(self, action: np.ndarray) -> np.ndarray:
        """(B, R, 2) robot commands (v, omega) of the (B, R) actions, checked."""
        index = np.asarray(action).reshape(self.batch_size, self.num_robots)
        if ((index < 0) | (index >= len(COMMANDS))).any():
            raise ValueError(f"toy_reach: actions must be in 0..{len(COMMANDS) - 1}, got {index.tolist()}")
        return COMMANDS[index] * self.speeds

    def step(self, action: np.ndarray, human_action: np.ndarray | None = None) -> TaskStep:
        command = self.command(action)
        live, before = ~self.core.done, self.core.goal_distance()
        events = self.core.step(command)
        after, contacts = self.core.goal_distance(), events.robot_human.sum(-1)
        reached = after < self.config.goal_radius
        terminated = (reached | events.robot_wall) & live
        time_up = self.core.state.step_count >= self.config.max_steps
        truncated = time_up[:, None] & live & ~terminated
        self.core.end_episodes(terminated | truncated)
        self.steps += live
        self.reached |= reached & live
        self.touched |= (contacts > 0) & live
        reward = before - after + 10.0 * reached - 1.0 * (contacts > 0)
        return TaskStep(
            reward=np.where(live, reward, 0.0),
            terminated=terminated,
            truncated=truncated,
            info={"reached": reached, "human_collisions": contacts},
            time_up=time_up,
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
        rows = np.asarray(rows).reshape(-1)
        steps, success = self.steps[rows, robot], self.reached[rows, robot] & ~self.touched[rows, robot]
        return [{"success": bool(s), "steps": int(n)} for s, n in zip(success, steps, strict=True)]

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

    def make_renderer(self, render_mode: str, view: str = "follow", **frame: Any) -> Any:
        from socialzoo.env.rendering import CoreRenderer

        return CoreRenderer(self, render_mode, view=view, **frame)


class ToyVelocityTask(ToyReachTask):
    """The toy task driven by (v, omega) as fractions of the top speeds: a Box of v in [0, 1] (no
    reversing) and omega in [-1, 1]."""

    name: ClassVar[str] = "toy_velocity"

    def __init__(self, config: EnvConfig | None = None, batch_size: int = 1, **overrides: Any) -> None:
        super().__init__(config, batch_size, **overrides)
        self.action_space = spaces.Box(np.array([0.0, -1.0], np.float32), np.array([1.0, 1.0], np.float32))

    def command(self, action: np.ndarray) -> np.ndarray:
        value = np.asarray(action, dtype=np.float64).reshape(self.batch_size, self.num_robots, 2)
        if not ((value >= self.action_space.low) & (value <= self.action_space.high)).all():
            raise ValueError(f"toy_velocity: (v, omega) must be in [0, 1] x [-1, 1], got {value.tolist()}")
        return value * self.speeds

    def action_labels(self) -> tuple[str, ...]:
        return ()


class ToyPairTask(ToyReachTask):
    """The toy task driven by a pair of choices, MultiDiscrete([3, 3]): (stop, slow, fast), (right,
    straight, left)."""

    name: ClassVar[str] = "toy_pair"

    def __init__(self, config: EnvConfig | None = None, batch_size: int = 1, **overrides: Any) -> None:
        super().__init__(config, batch_size, **overrides)
        self.action_space = spaces.MultiDiscrete([3, 3])

    def command(self, action: np.ndarray) -> np.ndarray:
        pair = np.asarray(action).reshape(self.batch_size, self.num_robots, 2)
        if not np.issubdtype(pair.dtype, np.integer) or ((pair < 0) | (pair > 2)).any():
            raise ValueError(f"toy_pair: actions must be pairs of integers in 0..2, got {pair.tolist()}")
        return np.stack((pair[..., 0] / 2, pair[..., 1] - 1.0), axis=-1) * self.speeds

    def idle_action(self) -> Any:
        return np.array([0, 1])

    def action_labels(self) -> tuple[str, ...]:
        return ()


class ToyDictTask(ToyReachTask):
    """The toy task observing a Dict: "goal" (its goal and velocity, 4) and "people" (3 x 4)."""

    name: ClassVar[str] = "toy_dict"

    def __init__(self, config: EnvConfig | None = None, batch_size: int = 1, **overrides: Any) -> None:
        super().__init__(config, batch_size, **overrides)
        box = spaces.Box(-np.inf, np.inf, (4,), np.float32)
        self.observation_space = spaces.Dict(
            {"goal": box, "people": spaces.Box(-np.inf, np.inf, (NEAREST, 4))}
        )

    def observations(self) -> dict[str, np.ndarray]:
        flat = super().observations()
        return {"goal": flat[..., :4], "people": flat[..., 4:].reshape(flat.shape[:2] + (NEAREST, 4))}


class ToyHeadForGoal:
    """An engineered policy of the toy task: turn towards the goal, then drive forward."""

    reads_core = False

    def act(self, obs: np.ndarray, core: Any = None) -> np.ndarray:
        angle = np.arctan2(obs[..., 1], obs[..., 0])  # the goal's bearing in the robot frame
        return np.where(angle > 0.3, 1, np.where(angle < -0.3, 2, 0)).astype(np.int64)

    def config(self) -> dict[str, Any]:
        return {}
