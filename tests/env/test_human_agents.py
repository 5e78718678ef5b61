"""Learned humans: reward terms and weights, the action frame, and their config fields."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.env.config import EnvConfig
from socialzoo.env.core import SocialNavCore
from socialzoo.env.human_agents import HumanRewardConfig, action_velocities, human_frames
from socialzoo.nav.scenarios import Scenario


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


def core_for(s: Scenario, **reward) -> SocialNavCore:
    config = EnvConfig(map="open_room", num_learned_humans=4, human_reward=HumanRewardConfig(**reward))
    core = SocialNavCore(config, 1)
    core.reset_rows([0], [s])
    return core


def test_contact_terms_name_who_is_touched():
    # human 0 and 1 touch each other; human 2 stands 0.15 m off the left wall; human 3 next to the robot.
    s = scenario(
        [[3.0, 5.0], [3.3, 5.0], [0.15, 7.0], [5.2, 1.2]], [[3.0, 9.0], [3.3, 9.0], [0.15, 9.0], [5.2, 9.0]]
    )
    core = core_for(s, human_contact=1.0, robot_contact=10.0, wall_contact=100.0, progress=0.0)
    result = core.step(np.array([[1]]), np.zeros((1, 4, 2)))
    step = result.human
    assert step.human_contact[0].tolist() == [True, True, False, False]
    assert step.robot_contact[0].tolist() == [False, False, False, True]
    assert step.wall_contact[0].tolist() == [False, False, True, False]
    assert step.contact[0].tolist() == [True, True, False, True]
    np.testing.assert_allclose(result.human_reward[0], [-1.0, -1.0, -100.0, -10.0])
    # Standing still but pushed by the social forces: the speed term is the relative deviation.
    speed = np.linalg.norm(core.state.human_vel[0, :4], axis=-1)
    np.testing.assert_allclose(step.speed_error[0], np.abs(speed - 1.0))
    assert (step.speed_error[0] > 0.5).all()


def test_progress_waypoint_bonus_and_speed_penalty_add_up():
    s = scenario([[2.0, 5.0]], [[2.6, 5.0]])  # the goal is within the 1 m waypoint radius: reached at once
    core = core_for(s, progress=2.0, waypoint_bonus=3.0, speed=0.5, human_contact=0.0, robot_contact=0.0)
    toward = np.zeros((1, 4, 2))
    toward[0, 0] = [1.0, 0.0]
    result = core.step(np.array([[1]]), toward)
    step = result.human
    assert step.waypoint_reached[0, 0] and not step.waypoint_reached[0, 1:].any()
    expected = 2.0 * step.progress[0, 0] + 3.0 - 0.5 * step.speed_error[0, 0]
    assert result.human_reward[0, 0] == pytest.approx(expected)
    assert step.progress[0, 0] > 0
    # Absent slots: zero everything.
    assert not result.human_reward[0, 1:].any() and not step.speed_error[0, 1:].any()


def test_human_frame_actions_point_at_the_waypoint():
    s = scenario([[2.0, 2.0], [8.0, 8.0]], [[2.0, 8.0], [2.0, 2.0]])
    core = core_for(s)
    state = core.state
    learned = np.arange(2)
    forward = np.array([[[1.0, 0.0], [1.0, 0.0]]])
    vel = action_velocities(state, learned, forward, "human")
    to_target = state.human_target[0, :2] - state.human_pos[0, :2]
    unit = to_target / np.linalg.norm(to_target, axis=-1, keepdims=True)
    np.testing.assert_allclose(vel[0], unit * state.human_pref_speed[0, :2, None], atol=1e-12)
    np.testing.assert_allclose(
        action_velocities(state, learned, forward, "world")[0], [[1.0, 0.0], [1.0, 0.0]]
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
    config = EnvConfig().replace(human_reward={"waypoint_bonus": 2.0}, human_action_frame="human")
    assert config.human_reward.waypoint_bonus == 2.0 and config.human_reward.progress == 1.0
    assert EnvConfig.from_dict(config.to_dict()) == config
