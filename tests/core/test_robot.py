"""Differential-drive motion model against hand-computed reference updates (SPEC section 3)."""

import math

import numpy as np

from socialzoo.core.config import RobotConfig
from socialzoo.core.robot import limit_command, step_robot

DT = 0.025
CFG = RobotConfig()


def test_acceleration_limit_from_rest():
    pose = np.zeros(3)
    new_pose, vel = step_robot(pose, np.zeros(2), np.array([1.5, 0.0]), np.array(False), DT, CFG)
    # v may rise by 6.0 m/s^2 * 0.025 s = 0.15 m/s in one step.
    assert math.isclose(vel[0], 0.15)
    # dx = v_prev*dt + 0.5*(v - v_prev)*dt = 0 + 0.5 * 0.15 * 0.025
    assert math.isclose(new_pose[0], 0.5 * 0.15 * DT)
    assert new_pose[1] == 0.0


def test_position_update_along_heading():
    pose = np.array([1.0, 2.0, math.pi / 2])
    new_pose, vel = step_robot(pose, np.array([1.0, 0.0]), np.array([1.0, 0.0]), np.array(False), DT, CFG)
    assert math.isclose(vel[0], 1.0)
    assert math.isclose(new_pose[0], 1.0, abs_tol=1e-12)
    assert math.isclose(new_pose[1], 2.0 + 1.0 * DT)


def test_deceleration_and_speed_cap():
    vel = limit_command(np.array([2.0, 0.0]), np.array([0.0, 0.0]), DT, CFG)
    assert math.isclose(vel[0], 2.0 - 6.0 * DT)
    vel = limit_command(np.array([2.25, 0.0]), np.array([5.0, 0.0]), DT, CFG)
    assert vel[0] == CFG.max_speed


def test_angular_limits():
    vel = limit_command(np.array([0.0, 0.0]), np.array([0.0, 10.0]), DT, CFG)
    assert math.isclose(vel[1], 5.0 * DT)
    vel = limit_command(np.array([0.0, 2.99]), np.array([0.0, 10.0]), DT, CFG)
    assert vel[1] == CFG.max_angular_speed


def test_heading_update_uses_mean_angular_speed():
    pose = np.zeros(3)
    new_pose, vel = step_robot(pose, np.array([0.0, 1.0]), np.array([0.0, 1.0]), np.array(False), DT, CFG)
    assert math.isclose(new_pose[2], 1.0 * DT)
    new_pose, vel = step_robot(pose, np.array([0.0, 1.0]), np.array([0.0, 2.0]), np.array(False), DT, CFG)
    # omega 1.0 -> 1.125 (limit 5 rad/s^2), heading += mean * dt
    assert math.isclose(vel[1], 1.125)
    assert math.isclose(new_pose[2], 0.5 * (1.0 + 1.125) * DT)


def test_halt_stops_at_once():
    pose = np.zeros(3)
    new_pose, vel = step_robot(pose, np.array([1.5, 0.5]), np.array([1.5, 0.5]), np.array(True), DT, CFG)
    np.testing.assert_array_equal(vel, [0.0, 0.0])
    # The step still covers half the previous speed's distance (mean of old and new speed).
    assert math.isclose(new_pose[0], 0.5 * 1.5 * DT)


def test_batched_equals_single():
    rng = np.random.default_rng(0)
    pose = rng.normal(size=(7, 2, 3))
    vel = rng.normal(size=(7, 2, 2))
    cmd = rng.normal(size=(7, 2, 2))
    halt = rng.random((7, 2)) < 0.3
    bp, bv = step_robot(pose, vel, cmd, halt, DT, CFG)
    for i in range(7):
        for r in range(2):
            p, v = step_robot(pose[i, r], vel[i, r], cmd[i, r], halt[i, r], DT, CFG)
            np.testing.assert_array_equal(p, bp[i, r])
            np.testing.assert_array_equal(v, bv[i, r])


# ---------------------------------------------------------------- CrowdNav's holonomic and unicycle robots
HOLONOMIC = RobotConfig(kinematics="holonomic", radius=0.3, max_speed=1.0)
UNICYCLE = RobotConfig(kinematics="unicycle", radius=0.3, max_speed=1.0)


def test_holonomic_takes_its_velocity_at_once_and_keeps_its_heading():
    pose = np.array([[0.0, -4.0, math.pi / 2], [1.0, 1.0, 0.3]])
    command = np.array([[0.6, 0.8], [3.0, 4.0]])  # the second is capped to speed 1
    new_pose, vel = step_robot(pose, np.zeros((2, 2)), command, np.array([False, False]), 0.25, HOLONOMIC)
    np.testing.assert_allclose(vel, [[0.6, 0.8], [0.6, 0.8]])
    np.testing.assert_allclose(new_pose[:, :2], [[0.15, -3.8], [1.15, 1.2]])
    np.testing.assert_array_equal(new_pose[:, 2], pose[:, 2])
    halted, halted_vel = step_robot(pose, vel, command, np.array([True, False]), 0.25, HOLONOMIC)
    np.testing.assert_array_equal(halted[0], pose[0])
    np.testing.assert_array_equal(halted_vel[0], 0.0)


def test_unicycle_turns_then_moves_along_its_new_heading():
    pose = np.array([0.0, 0.0, 0.0])
    # Asks for a quarter turn in one step: CrowdNav's unicycle turns at most pi/4 a step.
    new_pose, vel = step_robot(
        pose, np.zeros(2), np.array([1.0, math.pi / 2 / 0.25]), np.array(False), 0.25, UNICYCLE
    )
    assert math.isclose(new_pose[2], math.pi / 4)
    assert math.isclose(new_pose[0], 0.25 * math.cos(math.pi / 4)) and math.isclose(new_pose[1], new_pose[0])
    assert math.isclose(vel[0], 1.0) and math.isclose(vel[1], (math.pi / 4) / 0.25)
    # Never backwards, never faster than max_speed.
    _, vel = step_robot(pose, np.zeros(2), np.array([-1.0, 0.0]), np.array(False), 0.25, UNICYCLE)
    assert vel[0] == 0.0
    _, vel = step_robot(pose, np.zeros(2), np.array([5.0, 0.0]), np.array(False), 0.25, UNICYCLE)
    assert vel[0] == 1.0


def test_world_velocity_of_each_kinematics():
    from socialzoo.core.robot import world_velocity

    pose = np.array([[0.0, 0.0, math.pi / 2]])
    np.testing.assert_allclose(world_velocity(pose, np.array([[2.0, 0.5]]), CFG), [[0.0, 2.0]], atol=1e-12)
    np.testing.assert_allclose(world_velocity(pose, np.array([[0.3, -0.4]]), HOLONOMIC), [[0.3, -0.4]])


def test_bad_kinematics_are_refused():
    import pytest

    with pytest.raises(ValueError, match="kinematics"):
        RobotConfig(kinematics="tank")
    with pytest.raises(ValueError, match="radius"):
        RobotConfig(radius=0.0)
    with pytest.raises(ValueError, match="max_rotation"):
        RobotConfig(max_rotation=4.0)
