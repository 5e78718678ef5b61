"""Gymnasium adapters of the CrowdNav task: a single env and a batched VectorEnv over CrowdNavCore.

import gymnasium as gym, socialzoo
env = gym.make("socialzoo/CrowdNav-v1")                  # CrowdNav's task
venv = gym.make_vec("socialzoo/CrowdNav-v1", num_envs=256, vectorization_mode="vector_entry_point")
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from socialzoo.env.crowd_config import CrowdNavConfig, discrete_actions
from socialzoo.env.crowd_core import CrowdNavCore
from socialzoo.env.crowd_observation import HUMAN_FEATURES, ROBOT_FEATURES, JointState, flat_size
from socialzoo.env.crowd_source import CrowdCaseSource
from socialzoo.nav.crowd_cases import SPLITS


def _resolve(config: CrowdNavConfig | None, overrides: dict[str, Any]) -> CrowdNavConfig:
    """The config of an adapter's arguments: `config` (default CrowdNav's) with plain overrides;
    `variant=NAME` starts from a registered variant."""
    variant = overrides.pop("variant", None)
    base = config or (CrowdNavConfig.variant(variant) if variant is not None else CrowdNavConfig())
    return base.replace(**overrides) if overrides else base


def observation_space(config: CrowdNavConfig) -> spaces.Space:
    """One robot's observation space (flat Box or Dict, socialzoo.env.crowd_observation)."""
    h = config.observed_slots
    if config.observation == "flat":
        return spaces.Box(-np.inf, np.inf, (flat_size(h),), np.float32)
    return spaces.Dict(
        {
            "robot": spaces.Box(-np.inf, np.inf, (len(ROBOT_FEATURES),), np.float32),
            "humans": spaces.Box(-np.inf, np.inf, (h, len(HUMAN_FEATURES)), np.float32),
            "mask": spaces.MultiBinary(h),
        }
    )


def action_space(config: CrowdNavConfig) -> spaces.Space:
    """One row's action space: Box([-1, 1]^2) or Discrete(81)."""
    if config.action == "discrete":
        return spaces.Discrete(len(discrete_actions(config.robot)))
    return spaces.Box(-1.0, 1.0, (2,), np.float32)


def _one_robot(config: CrowdNavConfig, who: str) -> CrowdNavConfig:
    """`config`, refused when it has several robots (the PettingZoo env has them)."""
    if config.num_robots != 1:
        raise ValueError(
            f"{who} drives one robot, got num_robots={config.num_robots}; several robots: "
            "socialzoo.env.crowd_parallel.CrowdNavParallelEnv"
        )
    return config


def _copy(rows: Any) -> Any:
    """A copy of a batch of observations (an array, or a dict of arrays)."""
    return {k: v.copy() for k, v in rows.items()} if isinstance(rows, dict) else rows.copy()


def _rows(observation: JointState, kind: str) -> Any:
    return observation.flat() if kind == "flat" else observation.as_dict()


class CrowdNavVectorEnv(VectorEnv):
    """num_envs CrowdNav envs in one batched world (CrowdNavCore).

    ## Description
    A robot crosses an open arena from (0, -4) to (0, 4) among people (CrowdNav, Chen et al. 2019),
    choosing its velocity every 0.25 s. CrowdNav's settings are the defaults
    (socialzoo.env.crowd_config.CrowdNavConfig); the registered variants change one of them.

    ## Action Space
    `Box(-1, 1, (2,))` per row: (vx, vy) / v_pref for a holonomic robot, (2 speed / v_pref - 1,
    turn / (pi/4)) for a unicycle; or `Discrete(81)` with `action="discrete"` (CrowdNav's set).

    ## Observation Space
    The robot-centred joint state (socialzoo.env.crowd_observation): `Box((6 + 8 H,))` flat, or
    a Dict of robot (6,), humans (H, 7) and mask (H,).

    ## Rewards
    CrowdNav's: +1 at the goal, -0.25 on a collision, (d - 0.2) * 0.5 * 0.25 within 0.2 m.

    ## Starting State
    `reset(seed=s)` seeds the rows' training streams (CrowdNav's training split, never a
    validation or test case); `options={"split": "val"|"test", "cases": [k_0, ..., k_{B-1}]}`
    starts the rows on fixed cases; `options={"reset_mask": mask}` resets only the masked rows.

    ## Episode End
    terminated: goal reached or a collision; truncated: a step starting at 24 s (CrowdNav's time
    limit of 25 s). Same-step autoreset: `info["final_obs"]`, `info["final_info"]["metrics"]`.

    ## Arguments
    Args:
        num_envs: B.
        config: a CrowdNavConfig (default CrowdNav's task).
        **overrides: CrowdNavConfig fields as plain values, or variant=NAME.

    ## Version History
    - v1: initial release.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, num_envs: int, config: CrowdNavConfig | None = None, **overrides: Any) -> None:
        self.config = _one_robot(_resolve(config, overrides), "CrowdNavVectorEnv")
        self.num_envs = num_envs
        self.core = CrowdNavCore(self.config, num_envs)
        self.source = CrowdCaseSource(self.config, num_envs)
        self.single_observation_space = observation_space(self.config)
        self.single_action_space = action_space(self.config)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._started = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset rows (all, the masked ones, or onto fixed cases); see the class docstring."""
        options = dict(options or {})
        if seed is not None or not self._started:
            self.source.seed(seed)
        rows = np.arange(self.num_envs)
        if "reset_mask" in options:
            if not self._started:
                raise ValueError("CrowdNavVectorEnv: the first reset resets every row (no reset_mask)")
            rows = np.flatnonzero(np.asarray(options.pop("reset_mask"), dtype=bool))
        if "split" in options or "cases" in options:
            split = options.pop("split", "test")
            if split not in SPLITS or split == "train":
                raise ValueError(f"CrowdNavVectorEnv: options split must be 'val' or 'test', got {split!r}")
            cases = np.asarray(options.pop("cases"), dtype=np.int64).reshape(-1)
            if len(cases) != len(rows):
                raise ValueError(f"CrowdNavVectorEnv: {len(rows)} rows to reset but {len(cases)} cases")
            scenarios = self.source.fixed(split, cases)
        else:
            scenarios = self.source.next(rows)
        if options:
            raise ValueError(f"CrowdNavVectorEnv: unknown reset options {sorted(options)}")
        observation = self.core.reset_rows(rows, scenarios)
        self._started = True
        return _rows(observation, self.config.observation), {
            "case_seed": self.core.case_seed.copy()
        }

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step every row; rows whose episode ended are reset within the step."""
        if not self._started:
            raise RuntimeError("CrowdNavVectorEnv: reset before step")
        result = self.core.step(actions)
        outcome = result.outcome
        ended = np.flatnonzero(result.row_done)
        info: dict[str, Any] = {}
        if len(ended):
            # A copy: resetting the ended rows below rewrites the observation's rows in place.
            final_obs = _copy(_rows(result.observation, self.config.observation))
            info["final_obs"] = final_obs
            info["_final_obs"] = np.isin(np.arange(self.num_envs), ended)
            keys = next(iter(result.metrics.values())).keys()
            metrics = {k: np.full(self.num_envs, np.nan) for k in keys}
            for row, summary in result.metrics.items():
                for k, v in summary.items():
                    metrics[k][row] = v
            info["final_info"] = {"metrics": metrics}
            info["_final_info"] = info["_final_obs"]
            self.core.reset_rows(ended, self.source.next(ended))
        observation = _rows(self.core.observation, self.config.observation)  # type: ignore[arg-type]
        return observation, outcome.reward, outcome.terminated, outcome.truncated, info


class CrowdNavEnv(gym.Env):
    """One CrowdNav env (the batch of size 1 of CrowdNavVectorEnv; see its docstring).

    `reset(options={"split": "test", "case": k})` plays CrowdNav's test case k. At the end of an
    episode `info["metrics"]` holds its metrics (socialzoo.env.crowd_outcome.CrowdNavMetrics).

    ## Version History
    - v1: initial release.
    """

    metadata = {"render_modes": []}

    def __init__(self, config: CrowdNavConfig | None = None, **overrides: Any) -> None:
        self.config = _one_robot(_resolve(config, overrides), "CrowdNavEnv")
        self.core = CrowdNavCore(self.config, 1)
        self.source = CrowdCaseSource(self.config, 1)
        self.observation_space = observation_space(self.config)
        self.action_space = action_space(self.config)
        self._started = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start the next training case, or a fixed one (options split and case)."""
        super().reset(seed=seed)
        options = dict(options or {})
        if seed is not None or not self._started:
            self.source.seed(seed)
        if "case" in options:
            split = options.pop("split", "test")
            if split not in ("val", "test"):
                raise ValueError(f"CrowdNavEnv: options split must be 'val' or 'test', got {split!r}")
            scenarios = self.source.fixed(split, [int(options.pop("case"))])
        else:
            scenarios = self.source.next(np.array([0]))
        if options:
            raise ValueError(f"CrowdNavEnv: unknown reset options {sorted(options)}")
        self._started = True
        observation = self.core.reset_rows([0], scenarios)
        return self._one(observation), {"case_seed": scenarios[0].seed}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """One decision step."""
        if not self._started:
            raise RuntimeError("CrowdNavEnv: reset before step")
        batch = np.asarray(action)[None] if self.config.action == "continuous" else np.asarray([action])
        result = self.core.step(batch)
        outcome = result.outcome
        info: dict[str, Any] = {"closest": float(outcome.closest[0])}
        if 0 in result.metrics:
            info["metrics"] = result.metrics[0]
        return (
            self._one(result.observation),
            float(outcome.reward[0]),
            bool(outcome.terminated[0]),
            bool(outcome.truncated[0]),
            info,
        )

    def _one(self, observation: JointState) -> Any:
        rows = _rows(observation, self.config.observation)
        return rows[0] if self.config.observation == "flat" else {k: v[0] for k, v in rows.items()}
