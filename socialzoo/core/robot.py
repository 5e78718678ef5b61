"""Differential-drive robot motion model (SPEC section 3), vectorised over any leading axes.

Commands are a linear speed v and an angular speed omega; a constant-curvature arc c is the
command (v, v * c). The update follows the reference simulator: accelerations are limited, and the
position advances by the mean of the old and new speed along the current heading.
"""

from __future__ import annotations

import numpy as np

from socialzoo.core.config import RobotConfig
from socialzoo.core.geometry import wrap_angle


def limit_command(vel: np.ndarray, command: np.ndarray, dt: float, cfg: RobotConfig) -> np.ndarray:
    """Velocities reached after one step of acceleration-limited tracking of a command.

    Args:
        vel: current (v, omega), shape (..., 2), m/s and rad/s.
        command: requested (v, omega), shape (..., 2).
        dt: time step, s.
        cfg: robot limits.

    Returns:
        New (v, omega), shape (..., 2).
    """
    dv_max = cfg.max_linear_accel * dt
    dw_max = cfg.max_angular_accel * dt
    # np.minimum/np.maximum rather than np.clip: the same result at a fraction of the call cost.
    out = np.minimum(np.maximum(command, vel - (dv_max, dw_max)), vel + (dv_max, dw_max))
    limit = (cfg.max_speed, cfg.max_angular_speed)
    return np.minimum(np.maximum(out, np.negative(limit)), limit)


def step_robot(
    pose: np.ndarray,
    vel: np.ndarray,
    command: np.ndarray,
    halt: np.ndarray,
    dt: float,
    cfg: RobotConfig,
) -> tuple[np.ndarray, np.ndarray]:
    """Advance robots one step.

    Args:
        pose: (..., 3) x, y (m), theta (rad), world frame.
        vel: (..., 2) previous (v, omega).
        command: (..., 2) requested (v, omega).
        halt: (...,) bool; a halting robot's velocity is set to zero at once (the Halt
            sub-policy), bypassing the deceleration limit.
        dt: s.
        cfg: robot limits.

    Returns:
        (new_pose, new_vel) with the shapes of pose and vel.
    """
    new_vel = limit_command(vel, command, dt, cfg)
    new_vel = np.where(halt[..., None], 0.0, new_vel)
    # Reference update: dx = v_prev*dt + 0.5*(v - v_prev)*dt along the heading, same for theta.
    dist = 0.5 * (vel[..., 0] + new_vel[..., 0]) * dt
    dtheta = 0.5 * (vel[..., 1] + new_vel[..., 1]) * dt
    theta = pose[..., 2]
    new_pose = np.empty(pose.shape)
    new_pose[..., 0] = pose[..., 0] + dist * np.cos(theta)
    new_pose[..., 1] = pose[..., 1] + dist * np.sin(theta)
    new_pose[..., 2] = wrap_angle(theta + dtheta)
    return new_pose, new_vel
