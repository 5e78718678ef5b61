"""A Stable-Baselines3 VecEnv of any task: B rows of a TaskVectorEnv in one process, no env per row."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any, cast

import gymnasium as gym
import numpy as np
from gymnasium.vector import VectorEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvStepReturn

from socialzoo.core.validation import check_int
from socialzoo.env.vector import TaskVectorEnv


def observation_row(observations: Any, row: int) -> Any:
    """Row `row` of (B, ...) observations: an array, or a dict of them (a Dict observation space,
    such as CrowdNav's observation="dict") as a dict of that row's arrays."""
    if isinstance(observations, dict):
        return {key: values[row] for key, values in observations.items()}
    return observations[row]


class SB3VecEnv(VecEnv):
    """num_envs rows of a one-robot task as one SB3 VecEnv (below).

    It adapts `socialzoo.env.vector.TaskVectorEnv` (same rows, same seeded episodes) to SB3's
    conventions: `step` returns (obs, rewards, dones, infos) with dones = terminated | truncated; a
    row whose episode ended is reset within the step and its info holds `terminal_observation`
    (the last observation of the ended episode; a dict of arrays for a Dict observation space),
    `TimeLimit.truncated` (True when the time limit, not the task's own end, ended it) and
    `metrics` (the episode's metrics). SB3 algorithms, VecNormalize and VecMonitor work on it
    unchanged.

    Row 0 of a VecEnv seeded with s plays the same episodes as the task's single env reset with
    seed s and then without a seed; row i plays those of row i of a TaskVectorEnv seeded with s,
    whatever num_envs.

    Seeding follows SB3: `seed(s)` (which SB3 algorithms call with their own seed) takes effect at
    the next `reset()`; all rows draw their training streams from that one seed. Without a seed the
    first reset seeds from fresh entropy. So do options: `set_options(dict)` gives the next `reset()`
    the task's reset options for all rows.

    Attributes and methods (`get_attr`, `set_attr`, `env_method`) are those of the one batched env
    that every row shares (`self.vector_env`): `get_attr("config")` gives its config once per
    asked row. Spaces are the task's per row; rewards are float32. With render_mode="rgb_array"
    (a keyword of the vector env) `get_images` gives every row's frame, which SB3's `render` and
    `VecVideoRecorder` tile.

    Args:
        num_envs: B, the rows stepped together.
        config: the task's config object (None: its defaults).
        task: the task's registry name, "module:Class" path or class (default: action selection).
        vector_env: an already built TaskVectorEnv of num_envs rows instead of task and config.
        **kwargs: the task's keyword arguments, e.g. map="ghc3", scenario={"repeats": 20}, map_data=,
            and the vector env's (render_mode, max_episode_steps).
    """

    def __init__(
        self,
        num_envs: int,
        config: Any = None,
        *,
        task: Any = "action_selection",
        vector_env: VectorEnv | None = None,
        **kwargs: Any,
    ) -> None:
        check_int("SB3VecEnv", "num_envs", num_envs, low=1)
        if vector_env is None:
            vector_env = TaskVectorEnv(num_envs, config, task=task, **kwargs)
        elif vector_env.num_envs != num_envs:
            raise ValueError(
                f"SB3VecEnv: num_envs {num_envs} but the vector env has {vector_env.num_envs} rows"
            )
        # Any of socialzoo's batched VectorEnvs (same-step autoreset, final_obs and final_info
        # metrics), e.g. the CrowdNav task's CrowdNavVectorEnv.
        self.vector_env = vector_env
        self.config = cast(Any, self.vector_env).config  # every socialzoo VectorEnv has one
        # The vector env's (render_mode="rgb_array" among the task's keywords): SB3's render and
        # VecVideoRecorder read it and tile get_images' frames.
        self.render_mode = getattr(self.vector_env, "render_mode", None)
        super().__init__(
            num_envs, self.vector_env.single_observation_space, self.vector_env.single_action_space
        )
        self._actions: np.ndarray | None = None
        self._started = False

    # ----------------------------------------------------------------- stepping
    def reset(self) -> np.ndarray:
        """Reset every row; returns (B, D) observations. Uses the seed given to `seed()` and the
        options given to `set_options()` (the task's reset options, e.g. {"split": "val", "cases":
        [...]}: one dict for all rows, which share one env), if any.

        Raises:
            ValueError: `set_options` gave the rows different options.
        """
        seed = self._seeds[0]
        options = self._options[0]
        if any(other != options for other in self._options):
            raise ValueError(
                "SB3VecEnv.reset: rows share one env; set_options takes one dict for all rows "
                "(a split's cases as {'split': NAME, 'cases': [one per row]}), got different options per row"
            )
        obs, info = self.vector_env.reset(seed=seed, options=options or None)
        self._started = True
        # One dict per row of the vector env's reset info, under its task's own keys ("scenario_seed",
        # CrowdNav's "case_seed", ...), as plain Python values.
        self.reset_infos = [
            {key: np.asarray(values)[row].item() for key, values in info.items() if not key.startswith("_")}
            for row in range(self.num_envs)
        ]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Remember the (B,) actions for `step_wait`."""
        self._actions = np.asarray(actions)

    def step_wait(self) -> VecEnvStepReturn:
        """Step every row; rows whose episode ended are reset (SB3's autoreset)."""
        if not self._started or self._actions is None:
            raise RuntimeError("SB3VecEnv: call reset() and step_async(actions) before step_wait()")
        actions, self._actions = self._actions, None
        if actions.ndim == 2 and actions.shape[1] == 1 and isinstance(self.action_space, gym.spaces.Discrete):
            actions = actions[:, 0]  # SB3 gives (B, 1) discrete actions from some code paths
        obs, reward, terminated, truncated, info = self.vector_env.step(actions)
        dones = terminated | truncated
        # SB3's API wants one info dict per row; only rows that ended get entries (a loop over
        # the rows being reset, like the scenario draws, not over every row of every step).
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        ended = np.flatnonzero(dones)
        if len(ended):
            final_obs = info["final_obs"]
            metrics = info["final_info"]["metrics"]
            # The vector env hands episode metrics over as float arrays; its metric_types (bool
            # success, int counts) say what each one is, as a single env reports it.
            types = getattr(self.vector_env, "metric_types", {})
            for row in ended.tolist():
                infos[row] = {
                    "terminal_observation": observation_row(final_obs, row),
                    "TimeLimit.truncated": bool(truncated[row] and not terminated[row]),
                    "metrics": {key: types.get(key, float)(values[row]) for key, values in metrics.items()},
                }
        return obs, reward.astype(np.float32), dones, infos

    def get_images(self) -> Sequence[np.ndarray | None]:
        """Every row's frame (the vector env's render), for SB3's render and VecVideoRecorder;
        Nones, with a warning as SB3's DummyVecEnv gives, without render_mode="rgb_array"."""
        if self.render_mode != "rgb_array":
            warnings.warn(
                f"SB3VecEnv: the render mode is {self.render_mode!r}; get_images needs render_mode='rgb_array'",
                stacklevel=2,
            )
            return [None] * self.num_envs
        return list(cast(tuple[np.ndarray, ...], self.vector_env.render()))

    def close(self) -> None:
        """Release the batched env."""
        self.vector_env.close()

    # ----------------------------------------------------------- SB3 plumbing
    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seed the next reset: all rows derive their scenario streams from `seed` (None: entropy)."""
        if seed is None:
            seed = int(np.random.SeedSequence().generate_state(1)[0])
        self._seeds = [int(seed)] * self.num_envs
        return self._seeds

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The batched env's attribute `attr_name`, once per asked row."""
        value = getattr(self.vector_env, attr_name) if attr_name != "render_mode" else self.render_mode
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set an attribute of the batched env; rows share it, so only all rows at once."""
        if sorted(self._get_indices(indices)) != list(range(self.num_envs)):
            raise ValueError(f"SB3VecEnv.set_attr({attr_name!r}): rows share one env; set it for all rows")
        setattr(self.vector_env, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any
    ) -> list[Any]:
        """Call a method of the batched env once; its result is repeated for each asked row."""
        result = getattr(self.vector_env, method_name)(*method_args, **method_kwargs)
        return [result for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        """No row is wrapped: the rows are not gym.Env objects."""
        return [False for _ in self._get_indices(indices)]
