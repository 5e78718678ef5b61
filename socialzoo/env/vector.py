"""The Gymnasium VectorEnv of any task: B rows of a Task stepped by one process, no env per row."""

from __future__ import annotations

import operator
from typing import Any, cast

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from socialzoo.core.validation import check_int
from socialzoo.env.gym_env import TaskAdapter, one_robot, robot_row
from socialzoo.env.tasks.base import batch_actions


def checked_reset_mask(mask: Any, num_envs: int, started: bool, name: str) -> np.ndarray:
    """options["reset_mask"] of a vector env of `num_envs` rows: (num_envs,) bools, as Gymnasium's
    vector envs take it.

    Raises:
        RuntimeError: naming `name`, on the first reset (`started` False: every row must start).
        ValueError: naming `name`, a mask of another shape or dtype (row indices, one entry per
            ended row); nothing is reset then.
    """
    if not started:
        raise RuntimeError(f"{name}: the first reset must reset every row (no reset_mask)")
    array = np.asarray(mask)
    if array.dtype != np.bool_ or array.shape != (num_envs,):
        raise ValueError(
            f"{name}: options['reset_mask'] must be {num_envs} bools, one per row, "
            f"got {array.dtype} of shape {array.shape}"
        )
    return array


class TaskVectorEnv(TaskAdapter, VectorEnv):
    """num_envs rows of a one-robot task in one batched world (below).

    Rows that end an episode are reset within the same step (AutoresetMode.SAME_STEP): the
    returned observation starts the new episode, and `info["final_obs"]` and
    `info["final_info"]["metrics"]` hold the last observation and the episode metrics of the one
    that ended (zeros in the other rows; masks "_final_obs", "_final_info", "_metrics"). Row i of
    a VectorEnv seeded with s plays the same episodes whatever the number of envs (row 0 matches a
    single env seeded with s), bit for bit except with learned people, whose network's matrix
    product rounds by the batch's row count (to float32 rounding: docs/benchmark.md).

    ## Action Space
    The task's action space batched: `MultiDiscrete` or `Box((B, ...))`.

    ## Observation Space
    The task's observation space batched (B, ...), row by row the single env's.

    ## Starting State
    `reset(seed=s)` seeds the rows' training streams and starts every row on its next episode;
    `options={"reset_mask": mask}` ((num_envs,) bools) resets only the masked rows (after the
    first reset; another shape or dtype, such as row indices, is refused before any change), and
    with a seed reseeds only theirs, as Gymnasium's SyncVectorEnv seeds only the envs it resets
    (row i gets row i's stream of s; the other rows' episodes go on as before); other
    options are the task's (fixed cases: {"split": "test", "cases": [k_0, ..., k_{B-1}]}).

    ## Episode End
    A row ends on the task's end (terminated) or time limit (truncated), or truncated after
    `max_episode_steps` steps when given (as Gymnasium's TimeLimit wraps a single env: gymnasium's
    make_vec passes it to this vector entry point), with the episode's metrics so far.

    ## Arguments
    Args:
        num_envs: B.
        config: the task's config object (None: its defaults).
        render_mode: None or "rgb_array" (render() draws every row), where the task can draw.
        max_episode_steps: if set, truncate each row's episode after this many steps.
        task: the task's registry name, "module:Class" path or class (default: `default_task`).
        **kwargs: the task's keyword arguments (config fields as plain values, map_data=...).
    """

    metadata: dict[str, Any] = {
        "autoreset_mode": AutoresetMode.SAME_STEP,
        "render_modes": ["rgb_array"],
        "render_fps": 40,
    }

    def __init__(
        self,
        num_envs: int,
        config: Any = None,
        render_mode: str | None = None,
        *,
        max_episode_steps: int | None = None,
        task: Any = None,
        **kwargs: Any,
    ) -> None:
        check_int(type(self).__name__, "max_episode_steps", max_episode_steps, low=1, allow_none=True)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        cls = self.make_task(task, config, num_envs, kwargs, render_mode)
        one_robot(self.task, type(self).__name__)
        self.num_envs = num_envs
        self.metadata = {
            "autoreset_mode": AutoresetMode.SAME_STEP,
            "render_modes": [m for m in cls.render_modes if m == "rgb_array"],
            "render_fps": self.task.frames_per_second,
        }
        self.single_observation_space = self.task.observation_space
        self.single_action_space = self.task.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        # The type of each episode metric (bool success, int counts), as a single env reports it;
        # final_info carries them as float arrays.
        self.metric_types: dict[str, type] = {}
        self._all = np.arange(num_envs)
        self.max_episode_steps = max_episode_steps
        # Steps of each row's episode so far (for max_episode_steps).
        self._elapsed = np.zeros(num_envs, dtype=np.int64)
        self._action_shape = (num_envs, 1) + tuple(self.single_action_space.shape or ())
        self._started = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict]:
        """Reset every row, or the rows of options["reset_mask"] (see the class docstring)."""
        options = dict(options or {})
        rows = self._all
        if "reset_mask" in options:
            rows = self._masked_rows(options.pop("reset_mask"))
        super().reset(seed=seed)
        if seed is not None or not self._started:
            # As Gymnasium's SyncVectorEnv seeds only the envs it resets: rows outside a mask keep their streams.
            masked = None if rows is self._all else rows
            self.task.seed(seed if seed is not None else int(self.np_random.integers(2**63 - 1)), masked)
        seeds = np.zeros(self.num_envs, dtype=np.uint64)
        seeds[rows] = self.task.reset(rows, options)
        self._elapsed[rows] = 0
        self._started = True
        return robot_row(self.task.observations(), slice(None)), {self.task.reset_info_key: seeds}

    def _masked_rows(self, mask: Any) -> np.ndarray:
        """The rows a reset mask names (`checked_reset_mask`)."""
        return np.flatnonzero(checked_reset_mask(mask, self.num_envs, self._started, type(self).__name__))

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step every row; rows whose episode ended are reset in the same call."""
        if not self._started:
            raise RuntimeError(f"{type(self).__name__}: call reset() before step()")
        action = batch_actions(self.single_action_space, actions, (self.num_envs,), type(self).__name__)
        step = self.task.step(action.reshape(self._action_shape))
        terminated = step.terminated[:, 0].copy()
        truncated = step.truncated[:, 0].copy()
        self._elapsed += 1
        if self.max_episode_steps is not None:
            truncated |= self._elapsed >= self.max_episode_steps
        reward = step.reward[:, 0].astype(np.float64)
        info: dict[str, Any] = {key: step.info[key][:, 0].copy() for key in self.task.info_keys}
        ended = np.flatnonzero(terminated | truncated)
        if len(ended):
            mask = np.zeros(self.num_envs, dtype=bool)
            mask[ended] = True
            info["final_obs"], info["_final_obs"] = self._final_observations(ended), mask
            metrics = self._final_metrics(ended)
            info["final_info"], info["_final_info"] = {"metrics": metrics, "_metrics": mask}, mask
            self.task.reset(ended, {})
            self._elapsed[ended] = 0
        return robot_row(self.task.observations(), slice(None)), reward, terminated, truncated, info

    def _final_observations(self, ended: np.ndarray) -> Any:
        """The ended rows' last observations, zeros in the other rows (only the ended rows are
        copied: a few rows end on a step)."""

        def only_ended(values: np.ndarray) -> np.ndarray:  # (B, R, ...) -> robot 0's (B, ...)
            out = np.zeros(values.shape[:1] + values.shape[2:], dtype=values.dtype)
            out[ended] = values[ended, 0]
            return out

        last = self.task.observations()
        return {k: only_ended(v) for k, v in last.items()} if isinstance(last, dict) else only_ended(last)

    def _final_metrics(self, ended: np.ndarray) -> dict[str, np.ndarray]:
        """Metric -> (B,) float values of the ended rows' episodes, zeros in the other rows."""
        summaries = self.task.episode_metrics(ended)
        first = summaries[0]
        if not self.metric_types.keys() >= first.keys():
            for key, value in first.items():
                self.metric_types.setdefault(key, type(value))
        keys = list(first)
        if not keys:
            return {}
        # One (metrics, B) table filled at once: a write per metric cost more than the values, and
        # itemgetter reads a row's values in one call.
        values = operator.itemgetter(*keys)
        table = np.zeros((len(keys), self.num_envs))
        table[:, ended] = np.array([values(s) for s in summaries], dtype=np.float64).T
        return dict(zip(keys, table, strict=True))

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Every row's frame, (H, W, 3) uint8 each, as Gymnasium's vector envs render (a tuple of
        num_envs frames, which its vector RecordVideo tiles); None without render_mode. Drawing
        costs one frame per row: `draw("rgb_array", row=k)` draws row k alone."""
        if self.render_mode is None:
            return None
        return tuple(
            cast(np.ndarray, self.draw("rgb_array", row=k)) for k in range(self.num_envs)
        )  # drawn, not shown


class ActionSelectionVectorEnv(TaskVectorEnv):
    """The Social Action Selection task, B rows (socialzoo.env.tasks.action_selection)."""

    default_task = "action_selection"


class CrowdNavVectorEnv(TaskVectorEnv):
    """The CrowdNav task, B rows (socialzoo.env.tasks.crowdnav)."""

    default_task = "crowdnav"
