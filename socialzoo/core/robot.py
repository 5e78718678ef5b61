"""Robot motion models, vectorised over any leading axes: the benchmark's differential drive
(SPEC section 3) and the holonomic and unicycle robots of the CrowdNav line of work."""

from __future__ import annotations

import numpy as np

from socialzoo.core.config import RobotConfig
from socialzoo.core.geometry import wrap_angle
from socialzoo.core.jit import kernel


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
    """Advance robots one step with the motion model cfg.kinematics names.

    Differential drive: commands are a linear speed v and an angular speed omega (a
    constant-curvature arc c is the command (v, v * c)); as in the reference simulator,
    accelerations are limited and the position advances by the mean of the old and new speed
    along the current heading. Holonomic and unicycle robots take their command at once, as
    CrowdNav's agents do (RobotConfig says which).

    Args:
        pose: (..., 3) x, y (m), theta (rad), world frame.
        vel: (..., 2) previous velocity: (v, omega), or (vx, vy) world frame for a holonomic robot.
        command: (..., 2) requested velocity, in the same terms as `vel`.
        halt: (...,) bool; a halting robot's velocity is set to zero at once (the Halt
            sub-policy), bypassing the deceleration limit.
        dt: s.
        cfg: robot limits and kinematics.

    Returns:
        (new_pose, new_vel) with the shapes of pose and vel.
    """
    if cfg.kinematics == "holonomic":
        return _step_holonomic(pose, command, halt, dt, cfg)
    if cfg.kinematics == "unicycle":
        return _step_unicycle(pose, command, halt, dt, cfg)
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


def _step_holonomic(
    pose: np.ndarray, command: np.ndarray, halt: np.ndarray, dt: float, cfg: RobotConfig
) -> tuple[np.ndarray, np.ndarray]:
    """CrowdNav's holonomic agent: the velocity (vx, vy) is the command, its norm capped at
    max_speed; the position moves by velocity * dt; the heading is left as it is."""
    new_pose = np.array(pose, dtype=np.float64)
    new_vel = np.empty(command.shape)
    halt = np.asarray(halt, dtype=bool)
    if halt.shape != command.shape[:-1]:
        halt = np.broadcast_to(halt, command.shape[:-1])
    _holonomic(
        new_pose.reshape(-1, 3),
        np.asarray(command, dtype=np.float64).reshape(-1, 2),
        halt.reshape(-1),
        dt,
        cfg.max_speed,
        new_vel.reshape(-1, 2),
    )
    return new_pose, new_vel


@kernel
def _holonomic(pose, command, halt, dt, max_speed, vel):  # type: ignore[no-untyped-def]
    """_step_holonomic's numpy expressions per robot (np.maximum's and np.minimum's NaN kept): vel
    (N, 2) the command capped at max_speed (0 for a halting robot), pose (N, 3) moved by vel * dt
    in place."""
    for i in range(pose.shape[0]):
        speed = np.hypot(command[i, 0], command[i, 1])
        floor = speed if speed >= 1e-12 or speed != speed else 1e-12
        ratio = max_speed / floor
        scale = 1.0 if 1.0 < ratio else ratio
        for k in range(2):
            vel[i, k] = 0.0 if halt[i] else command[i, k] * scale
            pose[i, k] += vel[i, k] * dt


def _step_unicycle(
    pose: np.ndarray, command: np.ndarray, halt: np.ndarray, dt: float, cfg: RobotConfig
) -> tuple[np.ndarray, np.ndarray]:
    """CrowdNav's unicycle agent: the heading turns by omega * dt (at most max_rotation), then the
    robot moves v * dt along the new heading (0 <= v <= max_speed)."""
    v = np.clip(command[..., 0], 0.0, cfg.max_speed)
    turn = np.clip(command[..., 1] * dt, -cfg.max_rotation, cfg.max_rotation)
    v = np.where(halt, 0.0, v)
    turn = np.where(halt, 0.0, turn)
    theta = wrap_angle(pose[..., 2] + turn)
    new_pose = np.empty(pose.shape)
    new_pose[..., 0] = pose[..., 0] + v * dt * np.cos(theta)
    new_pose[..., 1] = pose[..., 1] + v * dt * np.sin(theta)
    new_pose[..., 2] = theta
    new_vel = np.stack((v, turn / dt), axis=-1)
    return new_pose, new_vel


def world_velocity(pose: np.ndarray, vel: np.ndarray, cfg: RobotConfig) -> np.ndarray:
    """(..., 2) the robots' velocity in the world frame, m/s: vel itself for a holonomic robot,
    v along the heading otherwise."""
    if cfg.kinematics == "holonomic":  # the velocity state is a world-frame (vx, vy)
        return np.asarray(vel, dtype=np.float64)[..., :2].copy()
    out = np.empty(pose.shape[:-1] + (2,))
    out[..., 0] = vel[..., 0] * np.cos(pose[..., 2])
    out[..., 1] = vel[..., 0] * np.sin(pose[..., 2])
    return out
