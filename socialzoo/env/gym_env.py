"""The Gymnasium single-agent env of any task: the batch of one of a Task (socialzoo.env.tasks)."""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from socialzoo.env.tasks import make_task as build_task
from socialzoo.env.tasks import task_class
from socialzoo.env.tasks.base import Task, agent_action

_ROW = np.array([0])


def one_robot(task: Task, adapter: str) -> Task:
    """`task`, refused when it has several robots or learned-human agents (the ParallelEnv has them)."""
    if task.num_robots != 1 or task.num_human_agents:
        raise ValueError(
            f"{adapter} drives one robot and no learned humans; got num_robots={task.num_robots}, "
            f"learned-human agents={task.num_human_agents} (use socialzoo.env.parallel.TaskParallelEnv)"
        )
    return task


def robot_row(observations: Any, row: int | slice, robot: int = 0) -> Any:
    """A copy of one robot's observation out of (B, R, ...) observations (an array or a dict)."""
    if isinstance(observations, dict):
        return {k: v[row, robot].copy() for k, v in observations.items()}
    return observations[row, robot].copy()


class TaskAdapter:
    """What every adapter of a task shares: the task it steps, named or its class's `default_task`,
    that task's batched core, and the renderer it draws with (made on the first frame)."""

    default_task: ClassVar[str | None] = None
    task: Task
    render_mode: str | None = None
    _renderer: Any = None
    # True from the first reset on: the task's worlds exist only then.
    _started: bool = False

    def make_task(
        self, task: Any, config: Any, batch_size: int, kwargs: dict[str, Any], render_mode: str | None = None
    ) -> type[Task]:
        """Build the adapter's task of `batch_size` rows (`config` and its keyword arguments) once
        `render_mode` is one it can draw; sets task, config and render_mode, returns the task class."""
        cls = self.task_class(task)
        cls.check_render_mode(render_mode)
        self.task = build_task(cls, batch_size, config, **kwargs)
        self.config = self.task.config
        self.render_mode = render_mode
        return cls

    def task_class(self, task: Any) -> type[Task]:
        """The Task class of `task` (a name, "module:Class" path or class), or of `default_task`."""
        chosen = task if task is not None else self.default_task
        if chosen is None:
            raise ValueError(f"{type(self).__name__}: name a task (task='action_selection', 'crowdnav', ...)")
        return task_class(chosen)

    @property
    def core(self) -> Any:
        """The task's batched core."""
        return self.task.core  # type: ignore[attr-defined]

    def draw(self, mode: str, view: str = "follow", row: int = 0) -> np.ndarray | None:
        """Row `row`'s frame from the task's renderer for `mode` (socialzoo.env.tasks.base.Task.make_renderer).

        Raises:
            RuntimeError: before the first reset (there is no world to draw yet).
        """
        if not self._started:
            raise RuntimeError(f"{type(self).__name__}: call reset() before render()")
        if self._renderer is None:
            self._renderer = self.task.make_renderer(mode, view=view)
        return self._renderer.render(row=row)

    def show(self, reset: bool = False) -> None:
        """After a reset (`reset`) or a step: start the renderer's new episode, and draw the frame
        in render_mode "human"."""
        if reset and self._renderer is not None:
            self._renderer.reset()
        if self.render_mode == "human":
            self.render()  # type: ignore[attr-defined]

    def close_extras(self, **kwargs: Any) -> None:
        """Close the renderer's window or figure, if one was opened (Gymnasium's VectorEnv.close
        calls this; the other adapters' close)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


class TaskEnv(TaskAdapter, gym.Env):
    """One robot of a task as a Gymnasium Env (see the task's class for its spaces and rewards).

    ## Description
    The batch-of-one view of a Task: `reset` starts the next episode of the task's seeded
    training stream (or the fixed case or scenario its options name), `step` takes one robot
    action. The task's docstring (socialzoo.env.tasks.*) describes its action and observation
    spaces, rewards, starting state and episode end.

    ## Episode End
    terminated: the task's end (goal reached, collision); truncated: its time limit. On the last
    step `info["metrics"]` holds the episode's metrics (not "episode", which SB3 and Gymnasium
    wrappers reserve for their return/length record). Stepping after the end raises; reset.

    ## Arguments
    Args:
        config: the task's config object (None: its defaults).
        render_mode: None, or one of the task's render modes.
        task: the task's registry name, "module:Class" path or class (default: the class's
            `default_task`).
        **kwargs: the task's keyword arguments: its config fields as plain values
            (map="ghc3", variant="Square", ...) and its own options (map_data=...).
    """

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array"], "render_fps": 40}

    def __init__(
        self, config: Any = None, render_mode: str | None = None, *, task: Any = None, **kwargs: Any
    ) -> None:
        cls = self.make_task(task, config, 1, kwargs, render_mode)
        one_robot(self.task, type(self).__name__)
        self.metadata = {"render_modes": list(cls.render_modes), "render_fps": self.task.frames_per_second}
        self.observation_space = self.task.observation_space
        self.action_space = self.task.action_space
        self._needs_reset = True
        self._started = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict]:
        """Start an episode.

        Args:
            seed: seeds the task's training stream (and Gymnasium's np_random); None continues
                the stream (the first reset without a seed draws fresh entropy).
            options: the task's reset options (a fixed case or a scenario to replay).
        """
        super().reset(seed=seed)
        if seed is not None or not self._started:
            self.task.seed(seed if seed is not None else int(self.np_random.integers(2**63 - 1)))
            self._started = True
        seeds = self.task.reset(_ROW, dict(options or {}))
        self._needs_reset = False
        self.show(reset=True)
        return robot_row(self.task.observations(), 0), {self.task.reset_info_key: int(seeds[0])}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """One step of the task with `action`.

        Raises:
            RuntimeError: stepping before reset or after the episode ended.
            ValueError: an action outside the action space (before any state changes).
        """
        if self._needs_reset:
            raise RuntimeError(f"{type(self).__name__}: call reset() before step() (the episode has ended)")
        value = agent_action(self.action_space, action, type(self).__name__)
        step = self.task.step(np.asarray(value).reshape((1, 1) + tuple(self.action_space.shape or ())))
        terminated = bool(step.terminated[0, 0])
        truncated = bool(step.truncated[0, 0])
        info = self.task.robot_info(step, 0, 0)
        name = self.task.action_name(0, 0)
        if name is not None:
            info["action_name"] = name
        if terminated or truncated:
            info["metrics"] = self.task.episode_metrics(_ROW)[0]
            self._needs_reset = True
        self.show()
        return robot_row(self.task.observations(), 0), float(step.reward[0, 0]), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The current frame as (H, W, 3) uint8 ("rgb_array"), or drawn in a window ("human")."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        return self.draw(self.render_mode)

    def close(self) -> None:
        """Close the renderer's window or figure, if one was opened."""
        self.close_extras()


class ActionSelectionEnv(TaskEnv):
    """The Social Action Selection task, one robot (socialzoo.env.tasks.action_selection)."""

    default_task = "action_selection"


class CrowdNavEnv(TaskEnv):
    """The CrowdNav task, one robot (socialzoo.env.tasks.crowdnav)."""

    default_task = "crowdnav"
