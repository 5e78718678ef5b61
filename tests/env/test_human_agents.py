"""Learned humans: reward terms and weights, the action frame, and their config fields."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.env.config import EnvConfig
from socialzoo.env.human_agents import HumanRewardConfig, action_velocities, human_frames
from socialzoo.env.tasks.action_selection import ActionSelectionTask
from socialzoo.scenarios.scenario import Scenario


def scenario(spawn: list[list[float]], goals: list[list[float]], robot=(5.0, 1.0, 0.0)) -> Scenario:
    """Humans in open_room (walls on x, y = 0 and 10), each walking from its spawn to its goal."""
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


def task_for(s: Scenario, **reward) -> ActionSelectionTask:
    config = EnvConfig(map="open_room", num_learned_humans=4, human_reward=HumanRewardConfig(**reward))
    task = ActionSelectionTask(config, 1)
    task.reset_rows([0], [s])
    return task


def test_contact_terms_name_who_is_touched():
    # human 0 and 1 touch each other; human 2 stands 0.15 m off the left wall; human 3 next to the robot.
    s = scenario(
        [[3.0, 5.0], [3.3, 5.0], [0.15, 7.0], [5.2, 1.2]], [[3.0, 9.0], [3.3, 9.0], [0.15, 9.0], [5.2, 9.0]]
    )
    task = task_for(s, human_contact=1.0, robot_contact=10.0, wall_contact=100.0, progress=0.0)
    result = task.step(np.array([[1]]), np.zeros((1, 4, 2))).detail
    step = result.human
    assert step.human_contact[0].tolist() == [True, True, False, False]
    assert step.robot_contact[0].tolist() == [False, False, False, True]
    assert step.wall_contact[0].tolist() == [False, False, True, False]
    assert step.contact[0].tolist() == [True, True, False, True]
    np.testing.assert_allclose(result.human_reward[0], [-1.0, -1.0, -100.0, -10.0])
    # Standing still but pushed by the social forces: the speed term is the relative deviation.
    speed = np.linalg.norm(task.core.state.human_vel[0, :4], axis=-1)
    np.testing.assert_allclose(step.speed_error[0], np.abs(speed - 1.0))
    assert (step.speed_error[0] > 0.5).all()


def test_progress_waypoint_bonus_and_speed_penalty_add_up():
    s = scenario([[2.0, 5.0]], [[2.6, 5.0]])  # the goal is within the 1 m waypoint radius: reached at once
    task = task_for(s, progress=2.0, waypoint_bonus=3.0, speed=0.5, human_contact=0.0, robot_contact=0.0)
    toward = np.zeros((1, 4, 2))
    toward[0, 0] = [1.0, 0.0]
    result = task.step(np.array([[1]]), toward).detail
    step = result.human
    assert step.waypoint_reached[0, 0] and not step.waypoint_reached[0, 1:].any()
    expected = 2.0 * step.progress[0, 0] + 3.0 - 0.5 * step.speed_error[0, 0]
    assert result.human_reward[0, 0] == pytest.approx(expected)
    assert step.progress[0, 0] > 0
    # Absent slots: zero everything.
    assert not result.human_reward[0, 1:].any() and not step.speed_error[0, 1:].any()


def test_human_frame_actions_point_at_the_waypoint():
    s = scenario([[2.0, 2.0], [8.0, 8.0]], [[2.0, 8.0], [2.0, 2.0]])
    task = task_for(s)
    state = task.core.state
    learned = np.arange(2)
    forward = np.array([[[1.0, 0.0], [1.0, 0.0]]])
    vel = action_velocities(state, learned, forward, "human")
    to_target = state.human_target[0, :2] - state.human_pos[0, :2]
    unit = to_target / np.linalg.norm(to_target, axis=-1, keepdims=True)
    np.testing.assert_allclose(vel[0], unit * state.human_pref_speed[0, :2, None], atol=1e-12)
    np.testing.assert_allclose(
        action_velocities(state, learned, forward, "world")[0], [[1.0, 0.0], [1.0, 0.0]]
    )
    # The action scale multiplies the desired velocity (EnvConfig.human_action_scale).
    np.testing.assert_allclose(
        action_velocities(state, learned, forward, "human", 1.25)[0], 1.25 * vel[0], atol=1e-12
    )
    # The frame is the observation's: the waypoint lies on its +x axis.
    assert np.allclose(np.sin(human_frames(state, learned)[0] - np.arctan2(unit[:, 1], unit[:, 0])), 0.0)


def test_config_fields_are_checked_and_the_old_penalty_name_is_refused():
    with pytest.raises(ValueError, match=r"HumanRewardConfig\.speed"):
        HumanRewardConfig(speed=-1.0)
    with pytest.raises(ValueError, match=r"HumanRewardConfig\.contact_distance"):
        HumanRewardConfig(contact_distance=0.0)
    with pytest.raises(ValueError, match="human_collision_penalty was renamed human_reward"):
        EnvConfig().replace(human_collision_penalty=2.0)
    with pytest.raises(ValueError, match="human_action_frame"):
        EnvConfig(human_action_frame="robot")
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="human_action_scale"):
            EnvConfig(human_action_scale=bad)
    config = EnvConfig().replace(human_reward={"waypoint_bonus": 2.0}, human_action_frame="human")
    assert config.human_reward.waypoint_bonus == 2.0 and config.human_reward.progress == 1.0
    assert EnvConfig.from_dict(config.to_dict()) == config


def test_action_scale_lets_a_learner_ask_for_more_but_never_walk_faster_than_its_preferred_speed():
    # Two humans walking up the room, both asking for the most their action allows: under scale 1
    # that is the preferred speed, under 1.5 half as much again. The one asking for more gets up
    # to speed sooner, and neither walks faster than its preferred speed (the motion model's cap).
    s = scenario([[3.0, 1.0]], [[3.0, 9.0]])
    speeds = {}
    for scale in (1.0, 1.5):
        config = EnvConfig(map="open_room", num_learned_humans=1, human_action_scale=scale)
        task = ActionSelectionTask(config, 1)
        task.reset_rows([0], [s])
        trace = []
        for _ in range(80):
            task.step(np.array([[1]]), np.array([[[0.0, 1.0]]]))
            trace.append(float(np.linalg.norm(task.core.state.human_vel[0, 0])))
        speeds[scale] = np.array(trace)
    assert (speeds[1.5][:10] > speeds[1.0][:10] + 1e-6).all()
    assert speeds[1.5].max() <= 1.0 + 1e-9 and speeds[1.0].max() <= 1.0 + 1e-9
    assert speeds[1.5][-1] == pytest.approx(1.0, abs=1e-6)


def test_wall_clearance_warns_before_the_contact():
    # Standing humans 0.15, 0.3 and 0.6 m off the left wall (and far from each other and the robot):
    # full penalty in contact, half at 0.3 m (halfway from the 0.4 m margin to the 0.2 m contact),
    # none beyond the margin. The humans drift a little in the step, so compare with their distance after it.
    s = scenario([[0.15, 3.0], [0.3, 5.0], [0.6, 7.0]], [[0.15, 3.5], [0.3, 5.5], [0.6, 7.5]])
    task = task_for(s, progress=0.0, human_contact=0.0, robot_contact=0.0, wall_clearance=2.0)
    result = task.step(np.array([[1]]), np.zeros((1, 4, 2))).detail
    x = task.core.state.human_pos[0, :3, 0]
    expected = np.clip((0.4 - x) / 0.2, 0.0, 1.0)
    np.testing.assert_allclose(result.human.wall_clearance[0, :3], expected, atol=1e-9)
    assert result.human.wall_clearance[0, 0] == 1.0 and 0.3 < result.human.wall_clearance[0, 1] < 0.7
    assert result.human.wall_clearance[0, 2] == 0.0 and result.human.wall_clearance[0, 3] == 0.0
    np.testing.assert_allclose(result.human_reward[0, :3], -2.0 * expected, atol=1e-9)
    with pytest.raises(ValueError, match=r"wall_margin \(0\.2\) must exceed wall_distance"):
        HumanRewardConfig(wall_margin=0.2)


def test_mirror_signs_give_the_observation_of_the_mirror_image():
    # Human 0 walks up the middle of the room; a second human stands on its left in one world and
    # on its right in the other (mirrored about x = 5, the first human's axis; the robot on it too).
    from socialzoo.env.human_agents import human_mirror_signs, human_observations

    obs = []
    for side in (4.0, 6.0):
        s = scenario([[5.0, 2.0], [side, 3.0]], [[5.0, 8.0], [side, 8.0]], robot=(5.0, 9.0, np.pi / 2))
        task = task_for(s)
        obs.append(
            human_observations(
                task.core.state, task.core.walls, np.arange(1), task.config.num_human_neighbours
            )[0, 0]
        )
    signs = human_mirror_signs(task.config.num_human_neighbours)
    assert obs[0][9] != 0 and (signs == -1).sum() == 3 + 2 * task.config.num_human_neighbours
    np.testing.assert_allclose(obs[1], obs[0] * signs, atol=1e-6)
