"""The PettingZoo ParallelEnv of any task: R robots and, where the task has them, L learned humans."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv
from pettingzoo.utils.wrappers import BaseParallelWrapper

from socialzoo.core.state import WorldState
from socialzoo.core.validation import check_int, check_seed
from socialzoo.env.gym_env import TaskAdapter, robot_row
from socialzoo.env.tasks.base import agent_action
from socialzoo.scenarios.scenario import Scenario

# Entries of the global state per robot: pose (x, y, theta), velocity (v, omega), goal (x, y, theta).
STATE_ROBOT_SIZE = 8
# Entries of the global state per human slot: position (x, y), velocity (vx, vy), present (0 or 1).
STATE_HUMAN_SIZE = 5
# Info keys of a learned human (stable from reset on: TorchRL's PettingZooWrapper builds its specs
# from the reset infos): within 0.4 m of anyone after the step, and the slot holds a person.
HUMAN_INFO_KEYS = ("contact", "present")
# Info key of a robot's episode metrics, present on the step it leaves (as in the single env).
EPISODE_KEY = "metrics"


class TaskParallelEnv(TaskAdapter, ParallelEnv[str, Any, Any]):
    """The robots (and learned humans) of one world of a task as PettingZoo agents.

    ## Description
    Agents: "robot_0" .. "robot_{R-1}", then "human_0" .. "human_{L-1}" for the task's
    learned-human slots (the action-selection task's config.num_learned_humans); the other
    people follow their crowd model. A scenario may have fewer people than L: the human agents
    of empty slots are still agents (so that `agents` is the same at every reset), with an
    all-zero observation, reward 0, actions ignored and info["present"] False.

    ## Action Space
    Robots: the task's action space; learned humans Box([-1, 1]^2), a desired velocity scaled
    by the person's preferred speed.

    ## Observation Space
    Robots: the task's observation; learned humans the task's human observation
    (socialzoo.env.human_agents). `state()` is the global state (`global_state`).

    ## Rewards
    Robots: the task's reward; learned humans the weighted terms of config.human_reward.

    ## Episode End
    A robot leaves `agents` the step it terminates (the task's end) or is truncated (its time
    limit, or max_cycles steps when set); it then stands still in the world until the next
    reset. Learned humans never terminate; they are truncated at the time limit and on the step
    the last robot leaves, which ends the episode (`agents` empty).

    Infos (plain dicts with stable keys): robots the task's per-step info keys, and on the step
    the robot leaves "metrics" unless episode_info=False; humans "contact" and "present".

    ## Arguments
    Args:
        config: the task's config object (None: its defaults).
        render_mode: None, or one of the task's render modes.
        max_cycles: if set, every agent still alive is truncated after this many steps.
        episode_info: put the "metrics" dict in the leaving robot's info. TorchRL's
            PettingZooWrapper needs False: it turns every info value into a tensor, and a key
            present only on the last step breaks its specs. The metrics stay available from
            `episode_summary(agent)`.
        task: the task's registry name, "module:Class" path or class (default: `default_task`).
        **kwargs: the task's keyword arguments (config fields as plain values, map_data=...).
    """

    metadata: dict[str, Any] = {
        "name": "socialzoo_parallel_v2",
        "render_modes": ["human", "rgb_array"],
        "render_fps": 40,
        "is_parallelizable": True,
    }

    def __init__(
        self,
        config: Any = None,
        *,
        render_mode: str | None = None,
        max_cycles: int | None = None,
        episode_info: bool = True,
        task: Any = None,
        **kwargs: Any,
    ) -> None:
        check_int(type(self).__name__, "max_cycles", max_cycles, low=1, allow_none=True)
        cls = self.make_task(task, config, 1, kwargs, render_mode)
        self.metadata = {
            **type(self).metadata,
            "render_modes": list(cls.render_modes),
            "render_fps": self.task.frames_per_second,
        }
        self.max_cycles = max_cycles
        self.episode_info = bool(episode_info)
        task_ = self.task
        self.robots = [f"robot_{i}" for i in range(task_.num_robots)]
        self.humans = [f"human_{j}" for j in range(task_.num_human_agents)]
        self.possible_agents = self.robots + self.humans
        self.agents: list[str] = []
        self.observation_spaces = {a: task_.observation_space for a in self.robots}
        self.action_spaces = {a: task_.action_space for a in self.robots}
        for a in self.humans:
            assert task_.human_observation_space is not None and task_.human_action_space is not None
            self.observation_spaces[a] = task_.human_observation_space
            self.action_spaces[a] = task_.human_action_space
        state_size = STATE_ROBOT_SIZE * task_.num_robots + STATE_HUMAN_SIZE * task_.num_human_slots
        self.state_space = spaces.Box(-np.inf, np.inf, (state_size,), dtype=np.float64)
        self.stream_seed: int | None = None
        self.num_cycles = 0
        self._started = False

    def observation_space(self, agent: str) -> spaces.Space:
        """The observation space of `agent` (the same object at every call)."""
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        """The action space of `agent` (the same object at every call)."""
        return self.action_spaces[agent]

    @property
    def scenario(self) -> Scenario | None:
        """The scenario the current episode plays, for `reset(options={"scenario": ...})` to replay;
        None before the first reset and for cases that are no Scenario (CrowdNav's arena)."""
        core = getattr(self.task, "core", None)
        return None if core is None else core.scenarios[0]

    # ------------------------------------------------------------------ reset
    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
        """Start an episode with every possible agent alive.

        Args:
            seed: seeds the task's training stream. None continues the stream; the first reset
                without a seed draws fresh entropy, kept in `stream_seed` so the run can be replayed.
            options: the task's reset options (a scenario to replay, a fixed case).

        Returns:
            (observations, infos) for every agent.
        """
        seed = check_seed(type(self).__name__ + ".reset", seed)
        if seed is not None or self.stream_seed is None:
            stream_seed = seed if seed is not None else int(np.random.SeedSequence().entropy)  # type: ignore[arg-type]
            self.task.seed(stream_seed)
            self.stream_seed = stream_seed
        self.task.reset(np.array([0]), dict(options or {}))
        self._started = True
        self.num_cycles = 0
        self.agents = self.possible_agents[:]
        self.show(reset=True)
        infos: dict[str, dict[str, Any]] = {a: self.task.initial_info() for a in self.robots}
        present = self.task.human_present()
        for j, a in enumerate(self.humans):
            infos[a] = {"contact": False, "present": bool(present[0, j])}
        return self._observations(self.agents), infos

    # ------------------------------------------------------------------ step
    def step(
        self, actions: Mapping[str, Any]
    ) -> tuple[
        dict[str, Any],
        dict[str, float],
        dict[str, bool],
        dict[str, bool],
        dict[str, dict[str, Any]],
    ]:
        """Advance the world one step with an action for every agent in `agents`.

        Returns:
            (observations, rewards, terminations, truncations, infos), each keyed by the agents
            that were alive before the step.

        Raises:
            RuntimeError: before the first reset, or after the episode ended (`agents` empty).
            TypeError: `actions` is not a dict.
            KeyError: an action missing for a live agent, or given for an unknown agent name.
            ValueError: an action outside its agent's space; nothing has changed then.
        """
        name = type(self).__name__
        if not self._started:
            raise RuntimeError(f"{name}: call reset() before step()")
        if not self.agents:
            raise RuntimeError(f"{name}: the episode has ended (no agents left); call reset()")
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
        step = self.task.step(robot_action, human_action)
        self.num_cycles += 1
        out_of_cycles = self.max_cycles is not None and self.num_cycles >= self.max_cycles
        out_of_time = out_of_cycles or bool(step.time_up[0])

        observations = self._observations(live)
        rewards: dict[str, float] = {}
        terminations: dict[str, bool] = {}
        truncations: dict[str, bool] = {}
        infos: dict[str, dict[str, Any]] = {}
        for i, agent in enumerate(self.robots):
            if agent not in live:
                continue
            terminated = bool(step.terminated[0, i])
            truncated = bool(step.truncated[0, i]) or (out_of_cycles and not terminated)
            rewards[agent] = float(step.reward[0, i])
            terminations[agent] = terminated
            truncations[agent] = truncated
            infos[agent] = self.task.robot_info(step, 0, i)
            if (terminated or truncated) and self.episode_info:
                infos[agent][EPISODE_KEY] = self.episode_summary(agent)
        # Learned humans never terminate: they are truncated with the time limit or the last robot.
        humans_out = out_of_time or all(
            a not in live or terminations[a] or truncations[a] for a in self.robots
        )
        for j, agent in enumerate(self.humans):
            if agent in live:
                assert step.human_reward is not None and step.human_info is not None
                rewards[agent] = float(step.human_reward[0, j])
                terminations[agent] = False
                truncations[agent] = humans_out
                infos[agent] = {key: bool(step.human_info[key][0, j]) for key in HUMAN_INFO_KEYS}
        self.agents = [a for a in live if not (terminations[a] or truncations[a])]
        self.show()
        return observations, rewards, terminations, truncations, infos

    def _action_arrays(self, actions: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray | None]:
        """(robot actions (1, R, ...), human actions (1, L, 2) or None), each checked."""
        task = self.task
        shape = tuple(task.action_space.shape or ())
        discrete = isinstance(task.action_space, (spaces.Discrete, spaces.MultiDiscrete))
        robot_action = np.zeros((1, task.num_robots) + shape, dtype=np.int64 if discrete else np.float64)
        for i, agent in enumerate(self.robots):
            value = actions[agent] if agent in self.agents else task.idle_action()
            robot_action[0, i] = agent_action(task.action_space, value, agent)
        if not self.humans:
            return robot_action, None
        assert task.human_action_space is not None
        human_action = np.zeros((1, len(self.humans), 2))
        for j, agent in enumerate(self.humans):
            if agent in self.agents:
                human_action[0, j] = agent_action(task.human_action_space, actions[agent], agent)
        return robot_action, human_action

    def _observations(self, agents: list[str]) -> dict[str, Any]:
        """Current observations (copies) of `agents`."""
        robots = self.task.observations()
        out = {agent: robot_row(robots, 0, i) for i, agent in enumerate(self.robots) if agent in agents}
        if self.humans:
            humans = self.task.human_observations()
            assert humans is not None
            for j, agent in enumerate(self.humans):
                if agent in agents:
                    out[agent] = humans[0, j].copy()
        return out

    # ------------------------------------------------------------------ state, metrics
    def state(self) -> np.ndarray:
        """The global state: float64 of length 8 R + 5 H (state_space), world frame, SI units;
        float64 so that positions keep the world's precision on maps with large coordinates
        (float32's steps are 0.03 m at a UTM easting of 5e5 m and 0.5 m at a northing of 5e6 m).

        Per robot: pose x, y, theta; velocity v, omega; goal x, y, theta. Then per human slot
        (learned or scripted): position x, y; velocity vx, vy; present (1.0) or empty (0.0, with
        zero position and velocity).
        """
        if not self._started:
            raise RuntimeError(f"{type(self).__name__}: call reset() before state()")
        return global_state(self.task.world_state)[0]

    def episode_summary(self, agent: str) -> dict[str, Any]:
        """The episode metrics of robot `agent` (the task's episode_metrics)."""
        if agent not in self.robots:
            raise KeyError(f"episode_summary needs a robot agent ({self.robots}), got {agent!r}")
        if not self._started:
            raise RuntimeError(f"{type(self).__name__}: call reset() before episode_summary()")
        return self.task.episode_metrics(np.array([0]), robot=self.robots.index(agent))[0]

    # ------------------------------------------------------------------ rendering
    def render(self) -> np.ndarray | None:
        """An (H, W, 3) uint8 frame of the whole map (rgb_array), or None after showing it (human)."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        return self.draw(self.render_mode, view="map")

    def close(self) -> None:
        """Close the renderer's window or figure, if one was opened."""
        self.close_extras()


class SocialNavParallelEnv(TaskParallelEnv):
    """The Social Action Selection task's robots and learned humans (socialzoo.env.tasks.action_selection)."""

    default_task = "action_selection"


class CrowdNavParallelEnv(TaskParallelEnv):
    """Several robots of the CrowdNav task (socialzoo.env.tasks.crowdnav), each seeing the others
    as people; a robot that left stands still where it is, still an obstacle to the others."""

    metadata: dict[str, Any] = {**TaskParallelEnv.metadata, "name": "socialzoo_crowdnav_v2"}
    default_task = "crowdnav"


def global_state(s: WorldState, dtype: type[np.floating] = np.float64) -> np.ndarray:
    """(B, 8 R + 5 H): the global state of every world (TaskParallelEnv.state), float64 unless
    `dtype` says otherwise (the TorchRL env's "state" is float32, as its golden rollouts are)."""
    b = s.batch_size
    robots = np.concatenate((s.robot_pose, s.robot_vel, s.robot_goal), axis=-1).reshape(b, -1)
    humans = np.concatenate((s.human_pos, s.human_vel, s.human_mask[..., None]), axis=-1).reshape(b, -1)
    return np.concatenate((robots, humans), axis=1).astype(dtype)


def parallel_env(config: Any = None, **kwargs: Any) -> SocialNavParallelEnv:
    """The action-selection task's SocialNavParallelEnv (arguments as there: render_mode,
    max_cycles, episode_info, then EnvConfig fields and map_data).

    Example:
        >>> env = parallel_env(map="open_room", num_robots=2, num_learned_humans=3, max_steps=400)
    """
    return SocialNavParallelEnv(config, **kwargs)


def parallel_crowd_env(**kwargs: Any) -> CrowdNavParallelEnv:
    """A CrowdNavParallelEnv of CrowdNavConfig overrides (num_robots=3, variant=NAME, ...)."""
    return CrowdNavParallelEnv(**kwargs)


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
