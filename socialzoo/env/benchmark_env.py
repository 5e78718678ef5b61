"""The Social Action Selection benchmark as a Gymnasium single-agent env (SPEC sections 2 to 9).

One robot chooses among four sub-policies (GoAlone, Halt, Follow, Pass) every 0.025 s step, among
5 to 25 social-force humans, on a building map; episodes end on success (goal within 0.5 m), on a
wall collision, or after 3200 steps (truncation).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from socialzoo.env.config import EnvConfig
from socialzoo.env.core import SocialNavCore
from socialzoo.env.observation import observation_space
from socialzoo.env.scenario_source import ScenarioStream
from socialzoo.nav.maps import Map
from socialzoo.nav.scenarios import Scenario
from socialzoo.nav.subpolicies import ACTION_NAMES, NUM_ACTIONS


class ActionSelectionEnv(gym.Env):
    """Social Action Selection (SocialGym benchmark), single robot.

    ## Description
    A differential-drive robot crosses a building among 5 to 25 pedestrians (the social force
    model) and picks, every 0.025 s step, one of four sub-policies that drive it: GoAlone, Halt,
    Follow, Pass. The policy learns *when* to wait, follow or overtake people; the sub-policies
    do the driving (A* plan, carrot, trajectory rollout). This is the batch-of-one view of the
    batched core (`SocialNavCore`); `ActionSelectionVectorEnv`, `SB3VecEnv` and
    `ActionSelectionTorchEnv` step the same functions. Ids: `socialzoo/ActionSelection-v2` (GDC1,
    the training map), `socialzoo/ActionSelectionTransfer-v2` (GHC3) and the scenario families.

    ## Action Space
    `Discrete(4)`: 0 GoAlone, 1 Halt, 2 Follow, 3 Pass (socialzoo.nav.subpolicies). With
    `robot_action="velocity"`: `Box(-1, 1, (2,))`, (v, omega) scaled by the robot's maximum speeds.

    ## Observation Space
    `observation="paper"` (default): `Box((107,), float32)`, all in the robot frame: goal x, y (m),
    carrot x, y (m), robot v (m/s) and omega (rad/s), the previous action, then 25 human slots of
    (x, y, vx, vy) (m, m/s), visible humans nearest first, occluded and empty slots zero.
    `observation={"layout": "socialgym1"}`: the reference code's 244 numbers. Unbounded, except
    the previous action in [0, 3]. Index table: docs/benchmark.md.

    ## Rewards
    5 x distance gained towards the goal (10 x when negative) - 0.1 x blame - 0.01 x force, plus
    100 on the step the goal is reached (weights in `reward`, socialzoo.env.reward.RewardConfig).
    Force and blame leave out the followed human, during Follow only (socialzoo.env.outcome).

    ## Starting State
    `reset` draws the next scenario of the env's seeded stream (socialzoo.nav.scenarios): the robot
    at rest on one legal pose of the map with its goal on another (a pair whose route fits the
    time limit), and 5 to 25 humans spawned within 0.5 m of their start poses with preferred
    speeds from N(1.0, 0.1) m/s, each shuttling between its start and its goal. `scenario.repeats`
    episodes run on a scenario before the next one is drawn; `options={"scenario": s}` replays `s`.

    ## Episode End
    Terminated when the robot is within 0.5 m of the goal or its footprint touches a wall;
    truncated after `max_steps` (3200 steps, 80 s). The final info holds "metrics": the episode's
    metrics (success, time_to_goal, force, blame, collisions, ...; not "episode", which SB3 and
    Gymnasium wrappers reserve for their return/length record).

    ## Arguments
    Args:
        config: an EnvConfig (default: the benchmark on gdc1).
        render_mode: None, "rgb_array" or "human".
        map_data: an already loaded Map instead of config.map.
        **overrides: EnvConfig fields as plain values (nested configs as dicts), e.g.
            map="ghc3", max_steps=800, observation={"layout": "socialgym1"}.

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

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 40}

    def __init__(
        self,
        config: EnvConfig | None = None,
        render_mode: str | None = None,
        map_data: Map | None = None,
        **overrides: Any,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']}, got {render_mode!r}"
            )
        self.config = EnvConfig.resolve(config, overrides)
        if self.config.num_robots != 1:
            raise ValueError(
                f"ActionSelectionEnv has one robot; got num_robots={self.config.num_robots} (use parallel_env)"
            )
        if self.config.num_learned_humans:
            raise ValueError("ActionSelectionEnv has no learned humans; use parallel_env for them")
        self.render_mode = render_mode
        self.core = SocialNavCore(self.config, 1, map_data=map_data)
        self.scenarios = ScenarioStream.for_config(self.core.map, 1, self.config)
        self.observation_space = observation_space(self.config.observation)
        if self.config.robot_action == "subpolicy":
            self.action_space: gym.Space = gym.spaces.Discrete(NUM_ACTIONS)
        else:
            self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        self._renderer: Any = None
        self._needs_reset = True
        self._seeded = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict]:
        """Start an episode.

        Args:
            seed: seeds the scenario stream (and Gymnasium's np_random); None continues the stream
                (first reset without a seed: fresh entropy).
            options: {"scenario": Scenario} replays that scenario.
        """
        super().reset(seed=seed)
        if seed is not None or not self._seeded:
            self.scenarios.seed(seed if seed is not None else int(self.np_random.integers(2**63 - 1)))
            self._seeded = True
        scenario = (options or {}).get("scenario")
        if scenario is not None and not isinstance(scenario, Scenario):
            raise TypeError(f"options['scenario'] must be a Scenario, got {type(scenario).__name__}")
        scenarios = [scenario] if scenario is not None else self.scenarios.next(np.array([0]))
        self.core.reset_rows(np.array([0]), scenarios)
        self._needs_reset = False
        if self._renderer is not None:
            self._renderer.reset()
        if self.render_mode == "human":
            self.render()
        return self.core.obs[0, 0].copy(), {"scenario_seed": int(scenarios[0].seed)}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One 0.025 s step with sub-policy `action`.

        Raises:
            RuntimeError: stepping before reset or after the episode ended.
            ValueError: an action outside the action space (before any state changes).
        """
        if self._needs_reset:
            raise RuntimeError("ActionSelectionEnv: call reset() before step() (the episode has ended)")
        if self.config.robot_action == "subpolicy":
            robot_action = np.array([[_discrete(action)]])
        else:
            robot_action = np.asarray(action, dtype=np.float64).reshape(1, 1, -1)
        result = self.core.step(robot_action)
        terminated = bool(result.terminated[0, 0])
        truncated = bool(result.truncated[0, 0])
        info = result.info()
        if self.config.robot_action == "subpolicy":
            info["action_name"] = ACTION_NAMES[int(robot_action[0, 0])]
        if terminated or truncated:
            info["metrics"] = self.core.episode_summaries([0])[0]
            self._needs_reset = True
        if self.render_mode == "human":
            self.render()
        return result.obs[0, 0].copy(), float(result.reward[0, 0]), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The current frame as (H, W, 3) uint8 ("rgb_array"), or drawn in a window ("human")."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        if self._renderer is None:
            from socialzoo.env.rendering import CoreRenderer

            self._renderer = CoreRenderer(self.core, self.render_mode)
        return self._renderer.render()

    def close(self) -> None:
        """Close the renderer's window or figure, if one was opened."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


def _discrete(action: Any) -> int:
    """A sub-policy index from an int-like action; anything else raises naming the value."""
    value = np.asarray(action)
    if value.size != 1 or not np.issubdtype(value.dtype, np.number) or not np.isfinite(value).all():
        raise ValueError(f"action must be one integer in 0..{NUM_ACTIONS - 1}, got {action!r}")
    scalar = value.reshape(()).item()
    if int(scalar) != scalar or not 0 <= int(scalar) < NUM_ACTIONS:
        raise ValueError(f"action must be one integer in 0..{NUM_ACTIONS - 1}, got {action!r}")
    return int(scalar)
