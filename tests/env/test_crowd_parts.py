"""The CrowdNav task's parts against hand-worked cases: the joint-state observation and the step's
judgement (collision along the step, goal, time limit, discomfort), in CrowdNav's order."""

import math

import numpy as np

from socialzoo.env.crowd_observation import flat_size, joint_state
from socialzoo.env.crowd_outcome import (
    CrowdNavMetrics,
    CrowdRewardConfig,
    judge_step,
    track_approach,
)


def test_joint_state_is_robot_centred_with_x_towards_the_goal():
    state = joint_state(
        robot_pos=np.array([[0.0, -4.0]]),
        robot_goal=np.array([[0.0, 4.0]]),
        robot_vel=np.array([[0.0, 1.0]]),
        robot_heading=np.array([math.pi / 2]),
        robot_radius=0.3,
        preferred_speed=1.0,
        unicycle=False,
        human_pos=np.array([[[1.0, -4.0], [0.0, 0.0]]]),
        human_vel=np.array([[[0.0, -1.0], [0.0, 0.0]]]),
        human_radius=0.3,
        human_mask=np.array([[True, False]]),
    )
    np.testing.assert_allclose(state.robot[0], [8.0, 1.0, 0.0, 0.3, 1.0, 0.0], atol=1e-6)
    # The person to the robot's right (world +x) is at robot-frame y = -1, walking towards it.
    np.testing.assert_allclose(state.humans[0, 0], [0.0, -1.0, -1.0, 0.0, 0.3, 1.0, 0.6], atol=1e-6)
    np.testing.assert_array_equal(state.humans[0, 1], 0.0)
    flat = state.flat()
    assert flat.shape == (1, flat_size(2)) == (1, 6 + 16) and flat[0, -2:].tolist() == [1.0, 0.0]


def test_closest_distance_along_the_step_catches_a_pass_through():
    # At the start and end of the step they are 1.2 m apart, but they cross in between.
    closest, moved = np.full(2, np.inf), np.zeros(2)
    track_approach(
        closest,
        moved,
        robot_before=np.zeros((2, 2)),
        robot_after=np.zeros((2, 2)),
        human_pos=np.array([[[-0.6, 0.0]], [[0.0, 0.0]]]),
        human_vel=np.array([[[4.8, 0.0]], [[0.0, 0.0]]]),
        radius_sum=np.full((2, 1), 0.6),
        human_mask=np.array([[True], [False]]),  # row 1: nobody
        dt=0.25,
    )
    assert math.isclose(closest[0], -0.6) and closest[1] == math.inf
    assert moved.tolist() == [0.0, 0.0]


def test_judgement_follows_crowdnavs_order_and_reward():
    cfg = CrowdRewardConfig()
    out = judge_step(
        closest=np.array([-0.1, -0.1, 0.5, 0.1, 0.5]),
        goal_distance_after=np.array([0.1, 1.0, 0.2, 3.0, 3.0]),
        robot_radius=0.3,
        step_start_time=np.array([24.0, 1.0, 1.0, 1.0, 1.0]),
        time_limit=25.0,
        cfg=cfg,
        dt=0.25,
    )
    assert out.timeout.tolist() == [True, False, False, False, False]  # the limit wins over everything
    assert out.collision.tolist() == [False, True, False, False, False]
    assert out.success.tolist() == [False, False, True, False, False]
    np.testing.assert_allclose(out.reward, [0.0, -0.25, 1.0, (0.1 - 0.2) * 0.5 * 0.25, 0.0])
    assert out.terminated.tolist() == [False, True, True, False, False] and out.truncated.tolist()[0]
    metrics = CrowdNavMetrics(5, 0.25, 1.0, cfg)
    metrics.update(out, moved=np.full(5, 0.25))
    rows = metrics.summaries(np.arange(5), out)
    assert (
        rows[2]["success"] == 1.0
        and rows[2]["navigation_time"] == 0.25
        and rows[3]["discomfort_frequency"] == 1.0
    )
    assert (
        math.isnan(rows[1]["navigation_time"]) and rows[1]["collision"] == 1.0 and rows[0]["timeout"] == 1.0
    )


def test_an_episode_s_danger_and_intrusion_counts_worked_by_hand():
    # Three steps: clear (0.5 m), in the danger zone (0.1 m), a collision (-0.05 m). CrowdNav counts
    # the middle one as danger; the intrusion ratio counts the collision step too.
    cfg = CrowdRewardConfig()
    metrics = CrowdNavMetrics(1, 0.25, 1.0, cfg)
    for k, gap in enumerate((0.5, 0.1, -0.05)):
        out = judge_step(np.array([gap]), np.array([5.0]), 0.3, np.array([0.25 * k]), 25.0, cfg, 0.25)
        metrics.update(out, moved=np.array([0.25]))
    (row,) = metrics.summaries(np.array([0]), out)
    assert row["collision"] == 1.0 and row["steps"] == 3 and row["discomfort_steps"] == 1
    assert row["discomfort_frequency"] == 1 / 3 and row["intrusion_ratio"] == 2 / 3
    assert row["min_separation"] == -0.05 and row["path_length"] == 0.75
    danger = (0.1 - 0.2) * 0.5 * 0.25
    assert math.isclose(row["return"], danger - 0.25)
    # CrowdNav's total reward: gamma ** (t dt v_pref) r_t, t counted from 0.
    assert math.isclose(row["discounted_return"], 0.9**0.25 * danger + 0.9**0.5 * -0.25)
