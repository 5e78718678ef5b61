"""The CrowdNav task with several robots as a PettingZoo ParallelEnv.

Agents "robot_0" .. "robot_{R-1}" start on the circle (socialzoo.nav.crowd_cases.robot_poses:
robot_0 where CrowdNav's robot starts, the others spread around it, each heading for its
antipode) among the task's people; each observes its own joint state in which the other robots
are people too (socialzoo.env.crowd_observation), acts with the task's action, and gets the
task's reward. A robot leaves `agents` when its episode ends (goal, collision or the time limit)
and stands still where it is, still an obstacle to the others; the episode ends when every
robot's has.

    from socialzoo.env.crowd_parallel import parallel_crowd_env
    env = parallel_crowd_env(num_robots=3)
    observations, infos = env.reset(seed=0)
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from socialzoo.env.crowd_config import CrowdNavConfig
from socialzoo.env.crowd_core import CrowdNavCore
from socialzoo.env.crowd_env import _resolve, _rows, action_space, observation_space
from socialzoo.env.crowd_source import CrowdCaseSource


class CrowdNavParallelEnv(ParallelEnv):
    """Several robots of the CrowdNav task (see the module docstring).

    ## Action Space
    Per agent, the task's: `Box(-1, 1, (2,))` or `Discrete(81)`.

    ## Observation Space
    Per agent, the joint state with the people and the other robots in its slots: flat
    `Box((6 + 8 (H + R - 1),))` or the Dict layout.

    ## Rewards
    Per agent, the task's reward (CrowdNav's).

    ## Episode End
    terminations: the robot reached its goal or collided (with a person, a robot or a wall);
    truncations: the step that starts at time_limit - 1 s. `infos[agent]["metrics"]` holds its
    episode's metrics on its last step.

    ## Arguments
    Args:
        config: a CrowdNavConfig (num_robots >= 1).
        **overrides: CrowdNavConfig fields as plain values (num_robots=3, variant=NAME, ...).

    ## Version History
    - v1: initial release.
    """

    metadata = {"name": "socialzoo_crowdnav_v1", "render_modes": []}

    def __init__(self, config: CrowdNavConfig | None = None, **overrides: Any) -> None:
        self.config = _resolve(config, overrides)
        self.possible_agents = [f"robot_{k}" for k in range(self.config.num_robots)]
        self.agents: list[str] = []
        self.core = CrowdNavCore(self.config, 1)
        self.source = CrowdCaseSource(self.config, 1)
        self._started = False

    @functools.cache  # noqa: B019  (one space per agent, cached as PettingZoo asks)
    def observation_space(self, agent: str) -> spaces.Space:
        """Every agent's observation space."""
        return observation_space(self.config)

    @functools.cache  # noqa: B019
    def action_space(self, agent: str) -> spaces.Space:
        """Every agent's action space."""
        return action_space(self.config)

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[dict, dict]:
        """Start the next training case (a seed reseeds the case stream; no options are read)."""
        if seed is not None or not self._started:
            self.source.seed(seed)
        self._started = True
        observation = self.core.reset_rows([0], self.source.next(np.array([0])))
        self.agents = list(self.possible_agents)
        rows = _rows(observation, self.config.observation)
        return self._per_agent(rows, self.agents), {agent: {} for agent in self.agents}

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """One decision step of every agent still in the episode."""
        if not self.agents:
            raise RuntimeError("CrowdNavParallelEnv: the episode is over; call reset")
        missing = set(self.agents) - set(actions)
        if missing:
            raise ValueError(f"CrowdNavParallelEnv: no action for {sorted(missing)}")
        unknown = set(actions) - set(self.agents)
        if unknown:
            raise ValueError(f"CrowdNavParallelEnv: actions for agents not in the episode: {sorted(unknown)}")
        discrete = self.config.action == "discrete"
        batch = np.zeros(
            (1, self.config.num_robots) + (() if discrete else (2,)),
            dtype=np.int64 if discrete else np.float64,
        )
        if not discrete and self.config.robot.kinematics == "unicycle":
            batch[..., 0] = -1.0  # a finished unicycle asks for speed 0
        for agent, action in actions.items():
            batch[0, int(agent.split("_")[1])] = action
        result = self.core.step(batch)
        outcome = result.outcome
        live = self.agents
        index = {agent: int(agent.split("_")[1]) for agent in live}
        rows = _rows(result.observation, self.config.observation)
        observations = self._per_agent(rows, live)
        rewards = {a: float(outcome.reward[k]) for a, k in index.items()}
        terminations = {a: bool(outcome.terminated[k]) for a, k in index.items()}
        truncations = {a: bool(outcome.truncated[k]) for a, k in index.items()}
        infos: dict[str, dict[str, Any]] = {a: {} for a in live}
        for a, k in index.items():
            if k in result.metrics:
                infos[a]["metrics"] = result.metrics[k]
        self.agents = [a for a in live if not (terminations[a] or truncations[a])]
        return observations, rewards, terminations, truncations, infos

    def _per_agent(self, rows: Any, agents: list[str]) -> dict[str, Any]:
        if self.config.observation == "flat":
            return {a: rows[int(a.split("_")[1])] for a in agents}
        return {a: {k: v[int(a.split("_")[1])] for k, v in rows.items()} for a in agents}


def parallel_crowd_env(**overrides: Any) -> CrowdNavParallelEnv:
    """A CrowdNavParallelEnv of CrowdNavConfig overrides (num_robots=3, variant=NAME, ...)."""
    return CrowdNavParallelEnv(**overrides)
