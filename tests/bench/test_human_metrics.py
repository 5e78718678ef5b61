"""The humans' episode metrics on hand-made open_room scenes whose answers are known."""

import numpy as np
import pytest

from socialzoo.bench.human_metrics import HumanEpisodeMetrics
from socialzoo.env.config import EnvConfig
from socialzoo.env.tasks.action_selection import ActionSelectionTask
from socialzoo.nav.subpolicies import HALT
from socialzoo.scenarios.scenario import Scenario


def scene(spawn, goals, robot=(9.0, 1.0, 0.0)):
    n = len(spawn)
    return Scenario(
        map_name="open_room",
        seed=3,
        robot_starts=[list(robot)],
        robot_goals=[[9.0, 9.0, 0.0]],
        human_spawn=spawn,
        human_start_index=[-1] * n,
        human_goal_index=[-1] * n,
        human_routes=tuple(np.array([s, g]) for s, g in zip(spawn, goals, strict=True)),
        human_speed=[1.0] * n,
    )


def run(s, walker, steps):
    """Step the scene with every human learned (the walker) and the robot halted; the summary."""
    config = EnvConfig(map="open_room", num_learned_humans=len(s.human_spawn), human_action_frame="human")
    task = ActionSelectionTask(config, 1)
    task.reset_rows([0], [s])
    world = config.world
    metrics = HumanEpisodeMetrics(
        1, config.max_humans, 1, task.core.walls, world.human_collision_distance, world.human.waypoint_radius
    )
    metrics.reset(np.array([0]), task.core.state)
    for _ in range(steps):
        before = task.core.state
        result = task.step(np.array([[HALT]]), walker.act(task.human_obs)).detail
        metrics.update(before, task.core.state, result.events.human_blocked, config.dt, np.array([False]))
    return metrics.summaries([0])[0]


@pytest.fixture(scope="module")
def walker(walker_policy_path):
    from socialzoo.env.human_policy import LearnedHumanPolicy

    return LearnedHumanPolicy.load(walker_policy_path)


def test_a_straight_walk_reaches_its_goal_at_ratio_one_and_its_speed(walker):
    # One human, 4 m straight to its goal, far from everyone; 6 s is time enough at ~1 m/s.
    got = run(scene([[3.0, 5.0]], [[7.0, 5.0]], robot=(3.0, 1.0, 0.0)), walker, 240)
    assert got["humans_goal_rate"] == 1.0
    assert got["humans_path_ratio"] == pytest.approx(1.0, abs=0.03)
    # At most tanh(3) x 1 m/s; less on average: it starts from rest and turns back at the goal.
    assert 0.7 < got["humans_mean_speed"] < np.tanh(3.0)
    assert got["humans_hh_collisions"] == got["humans_hw_collisions"] == got["humans_hr_collisions"] == 0
    assert np.isnan(got["humans_min_human_distance"])  # a single human
    assert got["humans_min_robot_distance"] == pytest.approx(4.0, abs=1e-9)  # at the start, walking away


def test_distances_to_walls_and_between_humans_and_an_unreached_goal(walker):
    # Two humans side by side, 0.6 m apart, 0.5 m off the left wall, walking up along it; 1 s only.
    got = run(scene([[0.5, 2.0], [1.1, 2.0]], [[0.5, 9.0], [1.1, 9.0]]), walker, 40)
    assert got["humans_goal_rate"] == 0.0 and np.isnan(got["humans_path_ratio"])
    # At most the starting gaps; the pair pushes apart (the outer one towards the wall) without touching.
    assert 0.2 < got["humans_min_wall_distance"] <= 0.5 + 1e-9
    assert 0.4 < got["humans_min_human_distance"] <= 0.6 + 1e-9
    assert got["humans_hh_collisions"] == 0 and got["humans_hw_collisions"] == 0


def test_rows_keep_apart_and_a_compacted_tracker_keeps_its_rows(walker):
    config = EnvConfig(map="open_room", num_learned_humans=1, human_action_frame="human")
    task = ActionSelectionTask(config, 2)
    near, far = scene([[3.0, 5.0]], [[7.0, 5.0]]), scene([[3.0, 5.0]], [[3.0, 9.5]])
    task.reset_rows([0, 1], [near, far])
    metrics = HumanEpisodeMetrics(2, config.max_humans, 1, task.core.walls, 0.4, 1.0)
    metrics.reset(np.array([0, 1]), task.core.state)
    for _ in range(40):
        before = task.core.state
        result = task.step(np.full((2, 1), HALT), walker.act(task.human_obs)).detail
        metrics.update(before, task.core.state, result.events.human_blocked, config.dt, np.zeros(2, bool))
    both = metrics.summaries([0, 1])
    assert both[0]["humans_min_robot_distance"] != both[1]["humans_min_robot_distance"]
    assert metrics.rows([1]).summaries([0]) == [both[1]] or str(metrics.rows([1]).summaries([0])) == str(
        [both[1]]
    )
