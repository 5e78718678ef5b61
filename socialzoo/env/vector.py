"""A Gymnasium VectorEnv over the batched core: B benchmark envs stepped by one process.

Rows that end an episode are reset within the same step (AutoresetMode.SAME_STEP): the returned
observation starts the new episode, and info["final_obs"] / info["final_info"] hold the last
observation and the episode metrics of the one that ended. Row i of a VectorEnv seeded with s
plays the same episodes whatever the number of envs (row 0 matches a single env seeded with s).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from socialzoo.env.config import EnvConfig
from socialzoo.env.core import SocialNavCore
from socialzoo.env.metrics import SUMMARY_KEYS
from socialzoo.env.observation import observation_space
from socialzoo.env.scenario_source import ScenarioStream
from socialzoo.nav.maps import Map
from socialzoo.nav.subpolicies import NUM_ACTIONS


class ActionSelectionVectorEnv(VectorEnv):
    """num_envs Social Action Selection envs in one batched world.

    ## Description
    B rows of `ActionSelectionEnv` stepped together by one `SocialNavCore` (one process, no env
    per row): `gym.make_vec("socialzoo/ActionSelection-v2", num_envs=B,
    vectorization_mode="vector_entry_point")`. Row i plays the same scenarios whatever B.

    ## Action Space
    `MultiDiscrete([4] * B)`: one sub-policy per row (0 GoAlone, 1 Halt, 2 Follow, 3 Pass);
    `Box(-1, 1, (B, 2))` with `robot_action="velocity"`.

    ## Observation Space
    `Box((B, 107), float32)`, row by row `ActionSelectionEnv`'s observation (the paper layout;
    (B, 244) with the socialgym1 layout).

    ## Rewards
    (B,) float64, the benchmark reward of each row (see `ActionSelectionEnv`).

    ## Starting State
    `reset(seed=s)` seeds the rows' scenario streams and starts every row on its next scenario;
    `options={"reset_mask": mask}` resets only the masked rows (after the first reset).

    ## Episode End
    Per row, as `ActionSelectionEnv`: terminated (goal or wall), truncated (time limit). Gymnasium's
    same-step autoreset: an ended row is reset within the step; `info["final_obs"]` holds its last
    observation and `info["final_info"]["metrics"]` its episode metrics (masks `_final_obs`,
    `_final_info`).

    ## Arguments
    Args:
        num_envs: B.
        config: an EnvConfig (default: the benchmark on gdc1).
        map_data: an already loaded Map instead of config.map.
        render_mode: None or "rgb_array" (renders row 0).
        **overrides: EnvConfig fields as plain values.

    ## Version History
    - v2: the robot recovers when it makes no progress (backs off, replans over another edge);
      its carrot and plans keep its full wall distance; people in contact with the robot do not
      press into it; episode metrics gain `stuck` and the failure causes (as `ActionSelectionEnv`).
    - v1: force and blame no longer skip the passed human (only the followed one, SPEC 9); the
      robot's carrot stays in sight of its wall distance and its plans keep clear of walls;
      scenarios draw only feasible start/goal pairs (unchanged on GDC1/GHC3).
    - v0: initial release.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": ["rgb_array"], "render_fps": 40}

    def __init__(
        self,
        num_envs: int,
        config: EnvConfig | None = None,
        map_data: Map | None = None,
        render_mode: str | None = None,
        **overrides: Any,
    ) -> None:
        self.config = EnvConfig.resolve(config, overrides)
        if self.config.num_robots != 1 or self.config.num_learned_humans:
            raise ValueError("ActionSelectionVectorEnv needs num_robots=1 and num_learned_humans=0")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.num_envs = num_envs
        self.render_mode = render_mode
        self.core = SocialNavCore(self.config, num_envs, map_data=map_data)
        self.scenarios = ScenarioStream.for_config(self.core.map, num_envs, self.config)
        self.single_observation_space = observation_space(self.config.observation)
        if self.config.robot_action == "subpolicy":
            self.single_action_space: gym.Space = gym.spaces.Discrete(NUM_ACTIONS)
        else:
            self.single_action_space = gym.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._all = np.arange(num_envs)
        self._started = False
        self._renderer: Any = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict]:
        """Reset every row (options {"reset_mask": (B,) bool} resets only those rows)."""
        super().reset(seed=seed)
        if seed is not None or not self._started:
            self.scenarios.seed(seed if seed is not None else int(self.np_random.integers(2**63 - 1)))
        rows = self._all
        if options and "reset_mask" in options:
            if not self._started:
                raise RuntimeError("the first reset must reset every row")
            rows = np.flatnonzero(np.asarray(options["reset_mask"], dtype=bool))
        scenarios = self.scenarios.next(rows)
        self.core.reset_rows(rows, scenarios)
        self._started = True
        seeds = np.zeros(self.num_envs, dtype=np.uint64)
        seeds[rows] = [int(s.seed) for s in scenarios]
        return self.core.obs[:, 0].copy(), {"scenario_seed": seeds}

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step every row; rows whose episode ended are reset in the same call."""
        if not self._started:
            raise RuntimeError("ActionSelectionVectorEnv: call reset() before step()")
        actions = np.asarray(actions)
        if self.config.robot_action == "subpolicy":
            if actions.shape != (self.num_envs,) or not np.issubdtype(actions.dtype, np.integer):
                if (
                    actions.shape == (self.num_envs,)
                    and np.all(np.isfinite(actions))
                    and np.all(actions == np.round(actions))
                ):
                    actions = actions.astype(np.int64)
                else:
                    raise ValueError(f"actions must be {self.num_envs} integers, got {actions!r}")
            robot_action = actions.reshape(self.num_envs, 1)
        else:
            robot_action = actions.reshape(self.num_envs, 1, 2)
        result = self.core.step(robot_action)
        terminated = result.terminated[:, 0].copy()
        truncated = result.truncated[:, 0].copy()
        reward = result.reward[:, 0].copy()
        info: dict[str, Any] = result.info_arrays()
        ended = np.flatnonzero(terminated | truncated)
        if len(ended):
            final_obs = np.zeros_like(self.core.obs[:, 0])
            final_obs[ended] = self.core.obs[ended, 0]
            summaries = self.core.episode_summaries(ended)
            metrics = {key: np.zeros(self.num_envs) for key in SUMMARY_KEYS}
            for key in SUMMARY_KEYS:
                metrics[key][ended] = [s[key] for s in summaries]
            mask = np.zeros(self.num_envs, dtype=bool)
            mask[ended] = True
            info["final_obs"], info["_final_obs"] = final_obs, mask
            info["final_info"], info["_final_info"] = {"metrics": metrics, "_metrics": mask}, mask
            self.core.reset_rows(ended, self.scenarios.next(ended))
        return self.core.obs[:, 0].copy(), reward, terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """Row 0's frame as (H, W, 3) uint8, or None without render_mode."""
        if self.render_mode is None:
            return None
        if self._renderer is None:
            from socialzoo.env.rendering import CoreRenderer

            self._renderer = CoreRenderer(self.core, "rgb_array")
        return self._renderer.render(row=0)

    def close_extras(self, **kwargs: Any) -> None:
        """Close the renderer, if one was opened (Gymnasium's VectorEnv.close calls this)."""
        if self._renderer is not None:
            self._renderer.close()
