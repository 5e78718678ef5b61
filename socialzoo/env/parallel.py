"""The multi-agent environment: a PettingZoo ParallelEnv of R robots and L learned humans.

A thin adapter over SocialNavCore with a batch of one world: agent dicts in and out, agents that
leave when their episode ends, per-agent spaces, a global state, rendering.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium
import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv
from pettingzoo.utils.wrappers import BaseParallelWrapper

from socialzoo.core.state import WorldState
from socialzoo.env.config import EnvConfig
from socialzoo.env.core import SocialNavCore, StepResult
from socialzoo.env.human_agents import human_observation_size
from socialzoo.env.observation import observation_space
from socialzoo.env.scenario_source import ScenarioStream, with_robots
from socialzoo.nav.maps import Map
from socialzoo.nav.scenarios import Scenario
from socialzoo.nav.subpolicies import NUM_ACTIONS

# The sub-policy given to robots that already left (the core halts them anyway).
_HALT = 1
# Entries of the global state per robot: pose (x, y, theta), velocity (v, omega), goal (x, y, theta).
STATE_ROBOT_SIZE = 8
# Entries of the global state per human slot: position (x, y), velocity (vx, vy), present (0 or 1).
STATE_HUMAN_SIZE = 5
# Info key of a robot's episode metrics, present on the step it leaves (as in ActionSelectionEnv).
EPISODE_KEY = "metrics"


class SocialNavParallelEnv(ParallelEnv[str, np.ndarray, Any]):
    """R robots (and optionally L learned humans) navigating among social-force humans.

    ## Description
    The PettingZoo view of the batched core (one world): several robots of the benchmark, and
    human slots that a learner may drive.

    Agents: "robot_0" .. "robot_{R-1}", then "human_0" .. "human_{L-1}" for the first L human
    slots when config.num_learned_humans = L > 0. The other humans follow the scripted social-force
    policy. A scenario may have fewer humans than L: the human agents of empty slots are still
    agents (so that `agents` is the same at every reset), with an all-zero observation, reward 0,
    actions ignored and info["present"] False.

    ## Action Space
    Robots Discrete(4) (GoAlone, Halt, Follow, Pass; SPEC section 7) or, with
    robot_action="velocity", Box([-1, 1]^2) of (v, omega) scaled by the robot's maximum speeds;
    learned humans Box([-1, 1]^2), a desired velocity scaled by the human's preferred speed, in the
    world frame or the human's own frame (config.human_action_frame).

    ## Observation Space
    Robots get the benchmark observation (SPEC section 8; `observation`
    config); learned humans get socialzoo.env.human_agents.human_observations (waypoint, velocity,
    nearest wall and neighbours in their own frame).

    ## Rewards
    Robots the benchmark reward (SPEC section 9); learned humans the weighted terms of
    config.human_reward (socialzoo.env.human_agents.HumanRewardConfig): by default progress towards
    their waypoint minus 1 per step in contact with a human and 1 with a robot.

    ## Starting State
    `reset` draws the next scenario of the seeded stream: each robot at rest on its own legal
    pose with a goal on another, 5 to 25 humans (the first L of them driven by learners) spawned
    near their start poses (as in `ActionSelectionEnv`).

    ## Episode End
    A robot leaves `agents` the step it terminates (goal reached or wall touched) or
    is truncated (config.max_steps, or max_cycles steps when set); it then stands still in the
    world until the next reset. Learned humans never terminate (they shuttle forever); they are
    truncated at the time limit and on the step the last robot leaves, which ends the episode
    (`agents` empty).

    Infos (plain dicts with stable keys): robots "reached", "wall_collision", "human_collisions",
    "force", "blame", "progress", "target_human" (-1 for none), and on the step the robot leaves
    "metrics" (socialzoo.env.metrics.SUMMARY_KEYS) unless episode_info=False; humans "contact"
    (within 0.4 m of anyone after the step) and "present".

    ## Arguments
    Args:
        config: an EnvConfig (default: the benchmark's, on gdc1).
        render_mode: None, "rgb_array" or "human".
        max_cycles: if set, every agent still alive is truncated after this many steps.
        map_data: an already loaded Map instead of config.map.
        episode_info: put the "metrics" dict in the leaving robot's info. TorchRL's
            PettingZooWrapper needs False: it turns every info value into a tensor, and a key
            present only on the last step breaks its specs. The metrics stay available from
            `episode_summary(agent)`.
        **overrides: EnvConfig fields as plain values (nested configs as dicts).

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

    metadata: ClassVar[dict[str, Any]] = {
        "name": "socialzoo_parallel_v1",
        "render_modes": ["human", "rgb_array"],
        "render_fps": 40,
        "is_parallelizable": True,
    }

    def __init__(
        self,
        config: EnvConfig | None = None,
        *,
        render_mode: str | None = None,
        max_cycles: int | None = None,
        map_data: Map | None = None,
        episode_info: bool = True,
        **overrides: Any,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']}, got {render_mode!r}"
            )
        if max_cycles is not None and (
            not isinstance(max_cycles, int) or isinstance(max_cycles, bool) or max_cycles < 1
        ):
            raise ValueError(f"max_cycles must be None or an int >= 1, got {max_cycles!r}")
        self.config = EnvConfig.resolve(config, overrides)
        self.render_mode = render_mode
        self.max_cycles = max_cycles
        self.episode_info = bool(episode_info)
        cfg = self.config
        self.core = SocialNavCore(cfg, 1, map_data=map_data)
        num_poses = len(self.core.map.legal_poses)
        if cfg.num_robots > 1 and num_poses < cfg.num_robots + 1:
            raise ValueError(
                f"num_robots={cfg.num_robots} needs at least {cfg.num_robots + 1} legal poses for distinct "
                f"starts; map {self.core.map.name!r} has {num_poses}"
            )
        self.scenarios = ScenarioStream.for_config(self.core.map, 1, cfg)
        self.robots = [f"robot_{i}" for i in range(cfg.num_robots)]
        self.humans = [f"human_{j}" for j in range(cfg.num_learned_humans)]
        self.possible_agents = self.robots + self.humans
        self.agents: list[str] = []
        self.observation_spaces = {a: observation_space(cfg.observation) for a in self.robots}
        human_size = human_observation_size(cfg.num_human_neighbours)
        for a in self.humans:
            self.observation_spaces[a] = spaces.Box(-np.inf, np.inf, (human_size,), dtype=np.float32)
        self.action_spaces = {a: self._robot_action_space() for a in self.robots}
        for a in self.humans:
            self.action_spaces[a] = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        state_size = STATE_ROBOT_SIZE * cfg.num_robots + STATE_HUMAN_SIZE * cfg.max_humans
        self.state_space = spaces.Box(-np.inf, np.inf, (state_size,), dtype=np.float32)
        self.stream_seed: int | None = None
        self.scenario: Scenario | None = None
        self.num_cycles = 0
        self._renderer: Any = None

    def _robot_action_space(self) -> spaces.Space:
        if self.config.robot_action == "subpolicy":
            return spaces.Discrete(NUM_ACTIONS)
        return spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)

    def observation_space(self, agent: str) -> spaces.Space:
        """The observation space of `agent` (the same object at every call)."""
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        """The action space of `agent` (the same object at every call)."""
        return self.action_spaces[agent]

    # ------------------------------------------------------------------ reset
    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict[str, Any]]]:
        """Start an episode with every possible agent alive.

        Args:
            seed: seeds the scenario stream. None continues the stream; the first reset without
                a seed draws fresh entropy, kept in `stream_seed` so the run can be replayed.
            options: {"scenario": Scenario} replays that scenario (robots beyond its own get
                poses as in ScenarioStream); other keys are ignored.

        Returns:
            (observations, infos) for every agent.
        """
        scenario = (options or {}).get("scenario")
        if scenario is not None and not isinstance(scenario, Scenario):
            raise TypeError(f"options['scenario'] must be a Scenario, got {type(scenario).__name__}")
        if scenario is not None:
            scenario = with_robots(scenario, self.core.map, self.config.num_robots)
        if seed is not None or self.stream_seed is None:
            stream_seed = seed if seed is not None else int(np.random.SeedSequence().entropy)  # type: ignore[arg-type]
            self.scenarios.seed(stream_seed)
            self.stream_seed = stream_seed
        if scenario is None:
            scenario = self.scenarios.next(np.array([0]))[0]
        self.core.reset_rows(np.array([0]), [scenario])
        self.scenario = scenario
        self.num_cycles = 0
        self.agents = self.possible_agents[:]
        if self._renderer is not None:
            self._renderer.reset()
        if self.render_mode == "human":
            self.render()
        infos: dict[str, dict[str, Any]] = {a: StepResult.initial_info() for a in self.robots}
        present = self.core.state.human_mask[0, self.core.learned]  # type: ignore[union-attr]
        for j, a in enumerate(self.humans):
            infos[a] = {"contact": False, "present": bool(present[j])}
        return self._observations(self.agents), infos

    # ------------------------------------------------------------------ step
    def step(
        self, actions: Mapping[str, Any]
    ) -> tuple[
        dict[str, np.ndarray],
        dict[str, float],
        dict[str, bool],
        dict[str, bool],
        dict[str, dict[str, Any]],
    ]:
        """Advance the world one step (0.025 s) with an action for every agent in `agents`.

        Actions of agents that already left are ignored.

        Returns:
            (observations, rewards, terminations, truncations, infos), each keyed by the agents
            that were alive before the step.

        Raises:
            RuntimeError: before the first reset, or after the episode ended (`agents` empty).
            TypeError: `actions` is not a dict.
            KeyError: an action missing for a live agent, or given for an unknown agent name.
            ValueError: an action outside its agent's space; nothing has changed then.
        """
        if self.scenario is None:
            raise RuntimeError("SocialNavParallelEnv: call reset() before step()")
        if not self.agents:
            raise RuntimeError("SocialNavParallelEnv: the episode has ended (no agents left); call reset()")
        if not isinstance(actions, Mapping):
            raise TypeError(f"actions must be a dict of agent name -> action, got {type(actions).__name__}")
        unknown = [a for a in actions if a not in self.action_spaces]
        if unknown:
            raise KeyError(f"actions for unknown agents {unknown}; agents are {self.possible_agents}")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise KeyError(f"no action for live agents {missing}")
        robot_action, human_action = self._action_arrays(actions)
        live = self.agents
        result = self.core.step(robot_action, human_action)
        after = self.core.state
        assert after is not None
        self.num_cycles += 1
        out_of_cycles = self.max_cycles is not None and self.num_cycles >= self.max_cycles
        out_of_time = out_of_cycles or bool(after.step_count[0] >= self.config.max_steps)

        observations = self._observations(live)
        rewards: dict[str, float] = {}
        terminations: dict[str, bool] = {}
        truncations: dict[str, bool] = {}
        infos: dict[str, dict[str, Any]] = {}
        for i, agent in enumerate(self.robots):
            if agent not in live:
                continue
            terminated = bool(result.terminated[0, i])
            truncated = bool(result.truncated[0, i]) or (out_of_cycles and not terminated)
            rewards[agent] = float(result.reward[0, i])
            terminations[agent] = terminated
            truncations[agent] = truncated
            infos[agent] = result.info(0, i)
            if (terminated or truncated) and self.episode_info:
                infos[agent][EPISODE_KEY] = self.episode_summary(agent)
        robots_left = all(a not in live or terminations[a] or truncations[a] for a in self.robots)
        if self.humans:
            assert result.human_reward is not None and result.human is not None
            present = after.human_mask[0, self.core.learned]
            contact = result.human.contact[0]
            for j, agent in enumerate(self.humans):
                if agent not in live:
                    continue
                rewards[agent] = float(result.human_reward[0, j])
                terminations[agent] = False
                truncations[agent] = out_of_time or robots_left
                infos[agent] = {"contact": bool(contact[j]), "present": bool(present[j])}
        self.agents = [a for a in live if not (terminations[a] or truncations[a])]
        if self.render_mode == "human":
            self.render()
        return observations, rewards, terminations, truncations, infos

    def _action_arrays(self, actions: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray | None]:
        """(robot actions (1, R) or (1, R, 2), human actions (1, L, 2) or None), validated."""
        cfg = self.config
        if cfg.robot_action == "subpolicy":
            robot_action = np.full((1, cfg.num_robots), _HALT, dtype=np.int64)
        else:
            robot_action = np.zeros((1, cfg.num_robots, 2))
        for i, agent in enumerate(self.robots):
            if agent in self.agents:
                if cfg.robot_action == "subpolicy":
                    robot_action[0, i] = _discrete_action(agent, actions[agent])
                else:
                    robot_action[0, i] = _box_action(agent, actions[agent])
        if not self.humans:
            return robot_action, None
        human_action = np.zeros((1, len(self.humans), 2))
        for j, agent in enumerate(self.humans):
            if agent in self.agents:
                human_action[0, j] = _box_action(agent, actions[agent])
        return robot_action, human_action

    def _observations(self, agents: list[str]) -> dict[str, np.ndarray]:
        """Current observations (copies) of `agents`."""
        out: dict[str, np.ndarray] = {}
        num_robots = self.config.num_robots
        for i, agent in enumerate(self.possible_agents):
            if agent not in agents:
                continue
            if i < num_robots:
                out[agent] = self.core.obs[0, i].copy()
            else:
                assert self.core.human_obs is not None
                out[agent] = self.core.human_obs[0, i - num_robots].copy()
        return out

    # ------------------------------------------------------------------ state, metrics
    def state(self) -> np.ndarray:
        """The global state: float32 of length 8 R + 5 H (state_space), world frame, SI units.

        Per robot: pose x, y, theta; velocity v, omega; goal x, y, theta. Then per human slot
        (H = scenario.max_humans, learned or scripted): position x, y; velocity vx, vy; present
        (1.0) or empty (0.0, with zero position and velocity).
        """
        s = self.core.state
        if s is None:
            raise RuntimeError("SocialNavParallelEnv: call reset() before state()")
        return global_state(s)[0]

    def episode_summary(self, agent: str) -> dict[str, Any]:
        """The episode metrics of robot `agent` so far (socialzoo.env.metrics.SUMMARY_KEYS)."""
        if agent not in self.robots:
            raise KeyError(f"episode_summary needs a robot agent ({self.robots}), got {agent!r}")
        if self.scenario is None:
            raise RuntimeError("SocialNavParallelEnv: call reset() before episode_summary()")
        return self.core.episode_summaries([0], robot=self.robots.index(agent))[0]

    # ------------------------------------------------------------------ rendering
    def render(self) -> np.ndarray | None:
        """An (H, W, 3) uint8 frame of the whole map (rgb_array), or None after showing it (human)."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        if self.scenario is None:
            raise RuntimeError("SocialNavParallelEnv: call reset() before render()")
        if self._renderer is None:
            from socialzoo.env.rendering import CoreRenderer

            self._renderer = CoreRenderer(self.core, self.render_mode, view="map")
        return self._renderer.render()

    def close(self) -> None:
        """Close the renderer's window or figure, if one was opened."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


def global_state(s: WorldState) -> np.ndarray:
    """(B, 8 R + 5 H) float32: the global state of every world (SocialNavParallelEnv.state)."""
    b = s.batch_size
    robots = np.concatenate((s.robot_pose, s.robot_vel, s.robot_goal), axis=-1).reshape(b, -1)
    humans = np.concatenate((s.human_pos, s.human_vel, s.human_mask[..., None]), axis=-1).reshape(b, -1)
    return np.concatenate((robots, humans), axis=1).astype(np.float32)


def parallel_env(
    config: EnvConfig | None = None,
    *,
    render_mode: str | None = None,
    max_cycles: int | None = None,
    map_data: Map | None = None,
    episode_info: bool = True,
    **overrides: Any,
) -> SocialNavParallelEnv:
    """A SocialNavParallelEnv (arguments as there); `overrides` are EnvConfig fields.

    Example:
        >>> env = parallel_env(map="open_room", num_robots=2, num_learned_humans=3, max_steps=400)
    """
    return SocialNavParallelEnv(
        config,
        render_mode=render_mode,
        max_cycles=max_cycles,
        map_data=map_data,
        episode_info=episode_info,
        **overrides,
    )


class BlackDeath(BaseParallelWrapper):
    """Keeps every agent in `agents` until the episode ends, for fixed-size learners (supersuit).

    An agent that left gets a zero observation, reward 0, terminated and truncated False and an
    empty info until the wrapped env's last agent leaves; that step reports every agent done
    (agents that left earlier with the flags they left with) and empties `agents`. This is
    supersuit's black_death_v3, whose end-of-episode test (terminated and truncated for every
    live agent, in supersuit 3.11) never fires for this env and steps past the episode's end.
    The wrapped env's own per-agent flags stay in its infos ("reached", "wall_collision").

    Args:
        env: a ParallelEnv whose observation spaces are Boxes.
    """

    def __init__(self, env: ParallelEnv) -> None:
        super().__init__(env)
        self.agents: list[str] = []
        self._left: dict[str, tuple[bool, bool]] = {}

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict[str, Any]]]:
        """Reset the wrapped env (PettingZoo's ParallelEnv.reset)."""
        observations, infos = self.env.reset(seed=seed, options=options)
        self.agents = list(self.env.agents)
        self._left = {}
        return observations, infos

    def step(self, actions: Mapping[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """Step the live agents; agents that left get a zero observation and reward, flags False, until the end."""
        live = list(self.env.agents)
        observations, rewards, terminations, truncations, infos = self.env.step({a: actions[a] for a in live})
        for agent in live:
            if terminations[agent] or truncations[agent]:
                self._left[agent] = (bool(terminations[agent]), bool(truncations[agent]))
        ended = not self.env.agents
        for agent in self.agents:
            if agent in live:
                if not ended:
                    terminations[agent] = truncations[agent] = False
                continue
            observations[agent] = np.zeros_like(self.observation_space(agent).low)
            rewards[agent] = 0.0
            terminations[agent], truncations[agent] = self._left[agent] if ended else (False, False)
            infos[agent] = {}
        if ended:
            self.agents = []
        return observations, rewards, terminations, truncations, infos


def _discrete_action(agent: str, action: Any) -> int:
    """A sub-policy index from an int-like action; anything else raises naming the agent."""
    value = np.asarray(action)
    ok = value.size == 1 and (
        np.issubdtype(value.dtype, np.integer) or np.issubdtype(value.dtype, np.floating)
    )
    if ok:
        scalar = value.reshape(()).item()
        ok = bool(np.isfinite(scalar)) and int(scalar) == scalar and 0 <= int(scalar) < NUM_ACTIONS
    if not ok:
        raise ValueError(f"{agent}: action must be one integer in 0..{NUM_ACTIONS - 1}, got {action!r}")
    return int(scalar)


def _box_action(agent: str, action: Any) -> np.ndarray:
    """A (2,) float action in [-1, 1]; anything else raises naming the agent."""
    try:
        value = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        value = None
    if value is None or value.shape != (2,) or not np.isfinite(value).all() or np.abs(value).max() > 1.0:
        raise ValueError(f"{agent}: action must be 2 finite numbers in [-1, 1], got {action!r}")
    return value
