"""One episode of a policy on row 0 of a task of one row, step by step: what the episode viewer's recorder
(socialzoo.bench.replay) and the animation (socialzoo.bench.episode_video) both play, how it ended, and the
action-selection task of one row that plays a given scenario."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from socialzoo.agents import Policy
from socialzoo.env.config import EnvConfig
from socialzoo.maps.map_file import Map
from socialzoo.scenarios.scenario import Scenario


def episode_outcome(metrics: dict[str, Any], last: Any) -> str:
    """One phrase for how robot 0's episode of row 0 ended: its metrics and its last TaskStep."""
    info = last.info

    def value(key: str) -> bool:
        return bool(info[key][0, 0]) if key in info else False

    if metrics.get("success"):
        return "success"
    if metrics.get("reached"):
        return "goal reached after a collision"
    if last.terminated[0, 0] and value("wall_collision") and not value("reached"):
        return "wall collision"
    if metrics.get("collision"):
        return "collision"
    if last.truncated[0, 0]:
        return "time limit"
    return "ended"


def step_seconds(task: Any) -> float:
    """A task's step, s: its config's dt (the action-selection task), else its time_step (the
    CrowdNav task's decision step)."""
    return float(getattr(task.config, "dt", getattr(task.config, "time_step", None)))  # type: ignore[arg-type]


def play_episode(
    task: Any, policy: Policy, human_policy: Any = None
) -> Iterator[tuple[np.ndarray, Any, bool]]:
    """Step `policy` on row 0 of a task of one row (already reset) until robot 0's episode ends,
    yielding each step's actions (1, R, *action_space.shape), its TaskStep, and whether robot 0's
    episode ended with it; the task is stepped again only when the next step is asked for (an
    episode's viewer and animation read its state in between, and may stop early).

    Every robot of the row acts (robot 0 is the one followed); a policy of observations alone
    (reads_core False) takes them as the runner gives them, a (N, D) batch. `human_policy` (an
    act(observations) such as socialzoo.env.human_policy.LearnedHumanPolicy) drives the task's
    learned-human agents (EnvConfig.num_learned_humans) from their observations
    (Task.human_observations); without it they get no actions."""
    shape = (1, task.world_state.robot_pose.shape[1], *(task.action_space.shape or ()))
    reads_core = getattr(policy, "reads_core", True)
    while True:
        obs = task.observations()
        if reads_core:
            action = np.asarray(policy.act(obs, task)).reshape(shape)
        else:
            flat = obs.reshape(-1, obs.shape[-1]) if isinstance(obs, np.ndarray) and obs.ndim == 3 else obs
            action = np.asarray(policy.act(flat)).reshape(shape)
        humans = None if human_policy is None else human_policy.act(task.human_observations())
        step = task.step(action, humans)
        ended = bool(step.terminated[0, 0] or step.truncated[0, 0])
        yield action, step, ended
        if ended:
            return


def scenario_task(env_config: EnvConfig, scenario: Scenario, world_map: Map | None = None) -> Any:
    """An action-selection task of one row of env_config, reset to play `scenario` (world_map: the
    already loaded map of env_config.map, if at hand)."""
    from socialzoo.env.tasks.action_selection import ActionSelectionTask

    task = ActionSelectionTask(env_config, 1, map_data=world_map)
    task.reset(np.array([0]), {"scenario": scenario})
    return task
