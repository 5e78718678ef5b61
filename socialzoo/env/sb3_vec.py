"""A Stable-Baselines3 VecEnv over the batched core: B benchmark envs in one process, no env per row.

It adapts `socialzoo.env.vector.ActionSelectionVectorEnv` (same rows, same seeded episodes) to SB3's
conventions: `step` returns (obs, rewards, dones, infos) with dones = terminated | truncated; a
row whose episode ended is reset within the step and its info holds `terminal_observation` (the
last observation of the ended episode), `TimeLimit.truncated` (True when the time limit, not the
goal or a wall, ended it) and `metrics` (the episode's metrics). SB3 algorithms, VecNormalize and
VecMonitor work on it unchanged:

    from stable_baselines3 import PPO
    from socialzoo.env.sb3_vec import SB3VecEnv
    venv = SB3VecEnv(64, map="gdc1")
    PPO("MlpPolicy", venv, n_steps=32).learn(100_000)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import VectorEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvStepReturn

from socialzoo.env.config import EnvConfig
from socialzoo.env.vector import ActionSelectionVectorEnv
from socialzoo.nav.maps import Map


class SB3VecEnv(VecEnv):
    """num_envs Social Action Selection envs as one SB3 VecEnv.

    Row 0 of a VecEnv seeded with s plays the same episodes as a single env
    (`gymnasium.make("socialzoo/ActionSelection-v2")`) reset with seed s and then without a seed;
    row i plays those of row i of an ActionSelectionVectorEnv seeded with s, whatever num_envs.

    Seeding follows SB3: `seed(s)` (which SB3 algorithms call with their own seed) takes effect at
    the next `reset()`; all rows draw their scenario streams from that one seed. Without a seed the
    first reset seeds from fresh entropy.

    Attributes and methods (`get_attr`, `set_attr`, `env_method`) are those of the one batched env
    that every row shares (`self.vector_env`): `get_attr("config")` gives its EnvConfig once per
    asked row.

    ## Description
    An SB3 `VecEnv` over `ActionSelectionVectorEnv` (self.vector_env): B benchmark rows stepped
    by one batched core, for PPO, DQN, VecNormalize and VecMonitor.

    ## Action Space
    `Discrete(4)` per row (SB3 passes a (B,) array): 0 GoAlone, 1 Halt, 2 Follow, 3 Pass.

    ## Observation Space
    `Box((107,), float32)` per row (the paper layout; see `ActionSelectionEnv`); `reset` and
    `step` return (B, 107).

    ## Rewards
    (B,) float32, the benchmark reward of each row (see `ActionSelectionEnv`).

    ## Starting State
    Every row starts on its next scenario at `reset()`, seeded by `seed(s)` (see Seeding above).

    ## Episode End
    `dones` = terminated | truncated; an ended row is reset within the step (SB3's autoreset) and
    its info holds `terminal_observation`, `TimeLimit.truncated` and `metrics`.

    ## Arguments
    Args:
        num_envs: B, the rows stepped together.
        config: an EnvConfig (default: the benchmark on gdc1).
        map_data: an already loaded Map instead of config.map.
        **overrides: EnvConfig fields as plain values, e.g. map="ghc3", scenario={"repeats": 20}.

    ## Version History
    - v2: the robot recovers when it makes no progress (backs off, replans over another edge);
      its carrot is in sight only along a line keeping its full wall distance; its plans join the
      graph by lines it can drive; people in contact with the robot do not press into it;
      episode metrics gain `stuck` and the failure causes (socialzoo.env.metrics).
    - v1: force and blame no longer skip the passed human (only the followed one, SPEC 9); the
      robot's carrot stays in sight of its wall distance and its plans keep clear of walls;
      scenarios draw only feasible start/goal pairs (unchanged on GDC1/GHC3).
    - v0: initial release.
    """

    def __init__(
        self,
        num_envs: int,
        config: EnvConfig | None = None,
        map_data: Map | None = None,
        vector_env: VectorEnv | None = None,
        **overrides: Any,
    ) -> None:
        if not isinstance(num_envs, int) or isinstance(num_envs, bool) or num_envs < 1:
            raise ValueError(f"SB3VecEnv: num_envs must be an int >= 1, got {num_envs!r}")
        if vector_env is None:
            vector_env = ActionSelectionVectorEnv(num_envs, config=config, map_data=map_data, **overrides)
        elif vector_env.num_envs != num_envs:
            raise ValueError(
                f"SB3VecEnv: num_envs {num_envs} but the vector env has {vector_env.num_envs} rows"
            )
        # Any of socialzoo's batched VectorEnvs (same-step autoreset, final_obs and final_info
        # metrics), e.g. the CrowdNav task's CrowdNavVectorEnv.
        self.vector_env = vector_env
        self.config = self.vector_env.config
        self.render_mode = None
        super().__init__(
            num_envs, self.vector_env.single_observation_space, self.vector_env.single_action_space
        )
        self._actions: np.ndarray | None = None
        self._started = False
        self._metric_types: dict[str, type] = {}

    # ----------------------------------------------------------------- stepping
    def reset(self) -> np.ndarray:
        """Reset every row; returns (B, D) observations. Uses the seed given to `seed()`, if any."""
        seed = self._seeds[0]
        obs, info = self.vector_env.reset(seed=seed)
        self._started = True
        seeds = info.get("scenario_seed", info.get("case_seed", [None] * self.num_envs))
        self.reset_infos = [{"scenario_seed": None if s is None else int(s)} for s in seeds]
        if not self._metric_types and hasattr(self.vector_env.core, "episode_summaries"):
            # The vector env hands episode metrics over as float arrays; the core's typed summary
            # (bool success, int counts) says what each one is, as a single env reports it.
            summary = self.vector_env.core.episode_summaries([0])[0]
            self._metric_types = {key: type(value) for key, value in summary.items()}
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
        if (
            actions.ndim == 2
            and actions.shape[1] == 1
            and isinstance(self.action_space, gym.spaces.Discrete)
        ):
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
            for row in ended.tolist():
                infos[row] = {
                    "terminal_observation": final_obs[row],
                    "TimeLimit.truncated": bool(truncated[row] and not terminated[row]),
                    "metrics": {
                        key: self._metric_types.get(key, float)(values[row])
                        for key, values in metrics.items()
                    },
                }
        return obs, reward.astype(np.float32), dones, infos

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
