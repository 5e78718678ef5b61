"""The robot's per-step outcome: who force and blame skip, the reward, and how episodes end."""

from __future__ import annotations

import math

import numpy as np
import pytest

from socialzoo.core.state import WorldState
from socialzoo.env.config import EnvConfig
from socialzoo.env.outcome import episode_end, followed_human, goal_reached, robot_outcome
from socialzoo.env.reward import RewardConfig
from socialzoo.env.world import StepEvents

GO_ALONE, HALT, FOLLOW, PASS = 0, 1, 2, 3


def test_only_follow_skips_its_target():
    action = np.array([[GO_ALONE, HALT, FOLLOW, PASS, FOLLOW]])
    target = np.array([[-1, -1, 4, 2, -1]])
    assert followed_human(action, target, "subpolicy").tolist() == [[-1, -1, 4, -1, -1]]
    velocity = np.zeros((1, 5, 2))
    assert followed_human(velocity, target, "velocity").tolist() == [[-1] * 5]


def test_goal_reached_and_episode_end():
    pos = np.array([[0.0, 0.0], [0.0, 0.0]])
    assert goal_reached(pos, np.array([[0.49, 0.0], [0.5, 0.0]]), 0.5).tolist() == [True, False]
    reached = np.array([True, False, False, False, True])
    wall = np.array([False, True, False, False, False])
    late = np.array([True, True, True, False, True])
    was_done = np.array([False, False, False, False, True])
    terminated, truncated = episode_end(reached, wall, late, was_done)
    assert terminated.tolist() == [True, True, False, False, False]
    assert truncated.tolist() == [False, False, True, False, False]


def two_robot_world(human_pos, robot_pos=((0.0, 0.0), (5.0, 0.0)), v=1.0, steps=10):
    """One world, two robots heading +x at speed v, goals 4 m ahead; humans as given."""
    h = len(human_pos)
    return WorldState(
        robot_pose=np.array([[[*p, 0.0] for p in robot_pos]]),
        robot_vel=np.array([[[v, 0.0]] * 2]),
        robot_goal=np.array([[[p[0] + 4.0, p[1], 0.0] for p in robot_pos]]),
        human_pos=np.asarray(human_pos, dtype=float).reshape(1, h, 2),
        human_vel=np.zeros((1, h, 2)),
        human_pref_speed=np.ones((1, h)),
        human_mask=np.ones((1, h), bool),
        human_route=np.zeros((1, h, 1, 2)),
        human_route_len=np.ones((1, h), np.intp),
        human_waypoint=np.zeros((1, h), np.intp),
        human_direction=np.ones((1, h), np.intp),
        step_count=np.array([steps]),
        noise_key=np.zeros(1, np.uint64),
    )


def events(h, wall=(False, False), contacts=None):
    contact = np.zeros((1, 2, h), bool) if contacts is None else np.asarray(contacts, bool).reshape(1, 2, h)
    return StepEvents(robot_wall=np.array([wall]), robot_human=contact, human_blocked=np.zeros((1, h), bool))


def test_robot_outcome_by_hand():
    cfg = EnvConfig(map="open_room")
    humans = [(0.6, 0.0), (5.0, 0.8)]
    before = two_robot_world(humans, robot_pos=((-0.025, 0.0), (4.975, 0.0)))
    after = two_robot_world(humans)
    visible = np.ones((2, 2), bool)
    skip = np.array([[-1, -1]])
    out = robot_outcome(
        before, after, events(2), visible, skip, np.zeros((1, 2), bool), np.zeros((1, 2), bool), cfg
    )
    assert out.force.shape == (1, 2)
    np.testing.assert_allclose(out.progress, [[0.025, 0.025]], atol=1e-12)
    assert out.force[0, 0] == pytest.approx(math.exp(-(0.6**4)), rel=1e-12)
    assert out.force[0, 1] == pytest.approx(math.exp(-(0.8**4)), rel=1e-12)
    # Robot 0 drives straight at the human 0.6 m ahead: its 0.5 m segment ends 0.1 m short.
    assert out.blame[0, 0] == pytest.approx(1.0 - math.erf(0.1), rel=1e-9)
    w = RewardConfig()
    expected = w.w_progress * 0.025 + w.w_blame * out.blame[0, 0] + w.w_force * out.force[0, 0]
    assert out.reward[0, 0] == pytest.approx(expected, rel=1e-12)
    assert not out.terminated.any() and not out.truncated.any() and not out.reached.any()

    # Robot 0 sees only human 0; skipping it leaves no one to count. Robot 1 is unaffected.
    visible0 = np.array([[True, False], [True, True]])
    skipped = robot_outcome(
        before,
        after,
        events(2),
        visible0,
        np.array([[0, -1]]),
        np.zeros((1, 2), bool),
        np.zeros((1, 2), bool),
        cfg,
    )
    assert skipped.force[0, 0] == 0.0 and skipped.blame[0, 0] == 0.0
    assert skipped.force[0, 1] == out.force[0, 1]


def test_robot_outcome_ends_episodes_and_zeroes_finished_robots():
    cfg = EnvConfig(map="open_room", max_steps=10)
    humans = [(20.0, 20.0)]
    after = two_robot_world(humans, steps=10)
    after.robot_goal[0, 0, :2] = (0.3, 0.0)  # robot 0 is within 0.5 m of its goal
    was_done = np.array([[False, True]])
    contacts = [[True], [False]]
    out = robot_outcome(
        after,
        after,
        events(1, wall=(False, True), contacts=contacts),
        np.ones((2, 1), bool),
        np.array([[-1, -1]]),
        np.zeros((1, 2), bool),
        was_done,
        cfg,
    )
    assert out.reached.tolist() == [[True, False]]
    assert out.terminated.tolist() == [[True, False]]  # robot 1 had already ended
    assert out.truncated.tolist() == [[False, False]]
    assert out.human_collisions.tolist() == [[1, 0]] and out.wall_collision.tolist() == [[False, True]]
    assert out.reward[0, 0] == pytest.approx(RewardConfig().success_bonus, abs=1e-3)
    assert out.reward[0, 1] == 0.0
    late = robot_outcome(
        after,
        after,
        events(1),
        np.ones((2, 1), bool),
        np.array([[-1, -1]]),
        np.zeros((1, 2), bool),
        np.zeros((1, 2), bool),
        cfg.replace(goal_radius=0.1),
    )
    assert late.truncated.tolist() == [[True, True]] and not late.terminated.any()


def test_halted_robots_carry_no_blame():
    cfg = EnvConfig(map="open_room")
    state = two_robot_world([(0.6, 0.0)])
    halted = np.array([[True, False]])
    out = robot_outcome(
        state,
        state,
        events(1),
        np.ones((2, 1), bool),
        np.array([[-1, -1]]),
        halted,
        np.zeros((1, 2), bool),
        cfg,
    )
    assert out.blame[0, 0] == 0.0 and out.force[0, 0] > 0.0
