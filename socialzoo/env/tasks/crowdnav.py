"""The CrowdNav velocity task (Chen et al. 2019, vita-epfl/CrowdNav) and its variants on the batched
core, with CrowdNav's settings as the defaults (socialzoo.env.crowd_config.CrowdNavConfig).

A robot chooses its velocity (or one of CrowdNav's 81 actions) every 0.25 s to cross an open arena,
or a building among the benchmark's people (the Walls variant), judged as CrowdNav judges it
(socialzoo.env.crowd_outcome). Training episodes are CrowdNav's training cases drawn per row;
`reset` options {"split": "val"|"test", "case": k} or {"cases": [...]} play fixed cases
(case_splits).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces

from socialzoo.core.state import WorldState
from socialzoo.env.crowd_config import CrowdNavConfig, discrete_actions
from socialzoo.env.crowd_core import CrowdNavCore
from socialzoo.env.crowd_observation import HUMAN_FEATURES, ROBOT_FEATURES, JointState, flat_size
from socialzoo.env.crowd_source import CrowdCaseSource
from socialzoo.env.tasks.base import Task, TaskStep, fixed_cases
from socialzoo.scenarios.crowd_cases import SPLIT_SIZE

# The per-step info of a robot: its closest approach to anyone during the step (m, negative: an
# overlap), the benchmark's social force and blame terms after it, whether it collided with a person
# (or another robot) or with a wall.
INFO_KEYS = ("closest", "force", "blame", "human_collisions", "wall_collision")


def resolve_config(config: CrowdNavConfig | None, overrides: dict[str, Any]) -> CrowdNavConfig:
    """The config of `config` (default CrowdNav's) with plain overrides; `variant=NAME` starts from
    a registered variant (socialzoo.env.crowd_variants)."""
    overrides = dict(overrides)
    variant = overrides.pop("variant", None)
    if config is not None and not isinstance(config, CrowdNavConfig):
        raise TypeError(f"config must be a CrowdNavConfig or None, got {type(config).__name__}")
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
    """One robot's action space: Box([-1, 1]^2) or Discrete(81)."""
    if config.action == "discrete":
        return spaces.Discrete(len(discrete_actions(config.robot)))
    return spaces.Box(-1.0, 1.0, (2,), np.float32)


class CrowdNavTask(Task):
    """The CrowdNav task over B rows of R robots (see the module docstring).

    Args:
        config: a CrowdNavConfig (default CrowdNav's task).
        batch_size: B.
        **overrides: CrowdNavConfig fields as plain values, or variant=NAME.
    """

    name: ClassVar[str] = "crowdnav"
    render_fps: ClassVar[int] = 4
    reset_info_key: ClassVar[str] = "case_seed"

    def __init__(self, config: CrowdNavConfig | None = None, batch_size: int = 1, **overrides: Any) -> None:
        self.config = resolve_config(config, overrides)
        self.core = CrowdNavCore(self.config, batch_size)
        self.source = CrowdCaseSource(self.config, batch_size)
        self.batch_size = batch_size
        self.num_robots = self.config.num_robots
        self.num_human_slots = self.config.slots
        self.observation_space = observation_space(self.config)
        self.action_space = action_space(self.config)
        # Metrics of the robots whose episode ended, by flat index (row * R + robot).
        self._ended: dict[int, dict[str, Any]] = {}

    # ------------------------------------------------------------------ episodes
    def seed(self, seed: int | None) -> None:
        """Reseed the rows' training streams (CrowdNav's training split only)."""
        self.source.seed(seed)

    def reset(self, rows: np.ndarray, options: dict[str, Any]) -> np.ndarray:
        """Start the rows on their next training cases, or on fixed validation or test cases."""
        rows = np.asarray(rows, dtype=np.intp)
        chosen = fixed_cases(dict(options), rows, self.case_splits(), self.name)
        if chosen is not None:
            scenarios = self.source.fixed(chosen[0], chosen[1])  # type: ignore[arg-type]
        else:
            scenarios = self.source.next(rows)
        self.core.reset_rows(rows, scenarios)
        for row in rows.tolist():
            for robot in range(self.num_robots):
                self._ended.pop(row * self.num_robots + robot, None)
        return self.core.case_seed[rows].copy()

    def case_splits(self) -> dict[str, int]:
        """CrowdNav's validation and test cases (100 and 500); among walls the map's validation
        scenarios and its registered test set."""
        if self.config.map is None:
            return dict(SPLIT_SIZE)
        from socialzoo.maps.map_file import load_map
        from socialzoo.scenarios.scenario import get_test_set, validation_set

        name = load_map(self.config.map).name
        return {"val": len(validation_set(name)), "test": len(get_test_set(f"{name}-test"))}

    def step(self, action: np.ndarray, human_action: np.ndarray | None = None) -> TaskStep:
        """One decision step (CrowdNavCore.step)."""
        if human_action is not None:
            raise ValueError(
                f"{self.name}: the task has no learned-human agents, but human actions were given"
            )
        b, r = self.batch_size, self.num_robots
        result = self.core.step(action)
        self._ended.update(result.metrics)
        outcome = result.outcome
        truncated = outcome.truncated.reshape(b, r)
        return TaskStep(
            reward=outcome.reward.reshape(b, r),
            terminated=outcome.terminated.reshape(b, r),
            truncated=truncated,
            info={
                "closest": outcome.closest.reshape(b, r),
                "force": self.core.step_force.reshape(b, r),
                "blame": self.core.step_blame.reshape(b, r),
                "human_collisions": (outcome.collision & ~result.wall_collision)
                .astype(np.int64)
                .reshape(b, r),
                "wall_collision": result.wall_collision.reshape(b, r),
            },
            time_up=truncated.any(axis=1),
        )

    def observations(self) -> Any:
        """(B, R, D) float32 flat joint states, or the dict layout of (B, R, ...) arrays."""
        observation = self.core.observation
        assert observation is not None
        return _per_robot(observation, self.config.observation, self.batch_size, self.num_robots)

    def episode_metrics(self, rows: np.ndarray, robot: int = 0) -> list[dict[str, Any]]:
        """The metrics of the episodes that ended (socialzoo.env.crowd_outcome.CrowdNavMetrics).

        Raises:
            ValueError: a robot whose episode has not ended yet.
        """
        out = []
        for row in np.asarray(rows, dtype=np.intp).reshape(-1).tolist():
            flat = row * self.num_robots + robot
            if flat not in self._ended:
                raise ValueError(f"{self.name}: robot {robot} of row {row} has not ended its episode")
            out.append(self._ended[flat])
        return out

    # ------------------------------------------------------------------ per-robot info
    @property
    def info_keys(self) -> tuple[str, ...]:
        """closest, force, blame, human_collisions, wall_collision."""
        return INFO_KEYS

    def initial_info(self) -> dict[str, Any]:
        """Nothing approached or touched yet."""
        return {
            "closest": float("inf"),
            "force": 0.0,
            "blame": 0.0,
            "human_collisions": 0,
            "wall_collision": False,
        }

    def idle_action(self) -> Any:
        """Stop: action 0, a zero velocity, or a unicycle's speed 0 (the lowest of its range)."""
        if self.config.action == "discrete":
            return 0
        if self.config.robot.kinematics == "unicycle":
            return np.array([-1.0, 0.0])
        return np.zeros(2)

    # ------------------------------------------------------------------ world view
    @property
    def world_state(self) -> WorldState:
        """The core's WorldState."""
        assert self.core.state is not None
        return self.core.state

    def viewer_guides(self, row: int = 0) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Among walls the route's carrot and plan; in the arena none (the goal, a straight line)."""
        if self.core.navigator is None:
            return None, None
        plans = self.core.navigator.plans
        length = int(plans.lengths[row, 0])
        return self.core.seen_goal()[0][row, 0].copy(), plans.paths[row, 0, :length].copy()

    def viewer_scene(self, title: str, subtitle: str, traces: Any) -> Any:
        """The arena (or the map's walls) around every trace; the robot's disc as a square of its
        diameter; the people's radius."""
        import dataclasses

        scene = super().viewer_scene(title, subtitle, traces)
        diameter = 2.0 * float(self.config.robot.radius)  # type: ignore[arg-type]
        return dataclasses.replace(
            scene,
            map_name=self.config.map or "arena",
            robot_length=diameter,
            robot_width=diameter,
            human_radius=self.config.cases.human_radius,
            goal_radius=float(self.config.robot.radius),  # type: ignore[arg-type]
        )


def _per_robot(observation: JointState, kind: str, b: int, r: int) -> Any:
    """A JointState of B R robots as (B, R, ...) arrays (flat, or the dict layout)."""
    if kind == "flat":
        flat = observation.flat()
        return flat.reshape(b, r, flat.shape[-1])
    return {k: v.reshape((b, r) + v.shape[1:]) for k, v in observation.as_dict().items()}
