"""The social force model of PedSim (Helbing-Molnar with Moussaid's agent interaction).

One implementation for every use: arrays carry a batch axis B and a human axis H, and the
robots are just more agents seen by the humans (their position difference scaled by 1/1.5).
Moussaid's pair force is antisymmetric between two humans (swapping them negates both the
position and the velocity difference), so each human pair is computed once.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from socialzoo.core.config import HumanConfig
from socialzoo.core.walls import WallIndex

# Distances below this are treated as coincident agents (metres).
_TINY = 1e-9


def desired_force(
    pos: np.ndarray, vel: np.ndarray, target: np.ndarray, pref_speed: np.ndarray, cfg: HumanConfig
) -> np.ndarray:
    """Relaxation towards walking at the preferred speed straight to the target.

    Args:
        pos, vel, target: (B, H, 2) world frame.
        pref_speed: (B, H) m/s.

    Returns:
        (B, H, 2) acceleration, m/s^2.
    """
    to_target = target - pos
    dist = np.sqrt((to_target**2).sum(-1, keepdims=True))
    direction = to_target / np.maximum(dist, _TINY)
    return (direction * pref_speed[..., None] - vel) / cfg.relaxation_time


def pair_force(
    dx: np.ndarray,
    dy: np.ndarray,
    dvx: np.ndarray,
    dvy: np.ndarray,
    valid: np.ndarray,
    cfg: HumanConfig,
) -> tuple[np.ndarray, np.ndarray]:
    """Moussaid's force on an agent from another, elementwise over any shape.

    Args:
        dx, dy: position of the other agent minus this agent's, m.
        dvx, dvy: this agent's velocity minus the other's, m/s.
        valid: pairs that interact; others get zero force.
        cfg: lambda, gamma, n and n' of the model.

    Returns:
        (fx, fy) before the social strength factor, m/s^2.
    """
    dist = np.sqrt(dx * dx + dy * dy)
    valid = valid & (dist > _TINY)
    dist = np.where(valid, dist, 1.0)
    ex, ey = dx / dist, dy / dist
    ix = cfg.social_lambda * dvx + ex
    iy = cfg.social_lambda * dvy + ey
    inter_len = np.sqrt(ix * ix + iy * iy)
    inter_len = np.where(inter_len > _TINY, inter_len, 1.0)
    ix = ix / inter_len
    iy = iy / inter_len
    # Signed angle from the interaction direction to the direction of the other agent.
    theta = np.arctan2(ix * ey - iy * ex, ix * ex + iy * ey)
    b = cfg.social_gamma * inter_len
    base = -dist / b
    bt = b * theta
    speed_amount = np.exp(base - (cfg.social_n_prime * bt) ** 2)
    angle_amount = np.sign(theta) * np.exp(base - (cfg.social_n * bt) ** 2)
    # Both amounts carry a minus sign in the model; the angle force acts along the left normal.
    speed_amount = np.where(valid, -speed_amount, 0.0)
    angle_amount = np.where(valid, -angle_amount, 0.0)
    return speed_amount * ix - angle_amount * iy, speed_amount * iy + angle_amount * ix


@lru_cache(maxsize=64)
def _pair_incidence(num_humans: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Index pairs i < j and the (P, H) matrix that adds +F_ij to i and -F_ij to j."""
    first, second = np.triu_indices(num_humans, k=1)
    incidence = np.zeros((len(first), num_humans))
    incidence[np.arange(len(first)), first] = 1.0
    incidence[np.arange(len(first)), second] = -1.0
    return first, second, incidence


def human_pair_force(pos: np.ndarray, vel: np.ndarray, mask: np.ndarray, cfg: HumanConfig) -> np.ndarray:
    """Sum of Moussaid forces on every human from every other human, (B, H, 2)."""
    first, second, incidence = _pair_incidence(pos.shape[1])
    d = pos[:, second] - pos[:, first]
    dv = vel[:, first] - vel[:, second]
    fx, fy = pair_force(d[..., 0], d[..., 1], dv[..., 0], dv[..., 1], mask[:, first] & mask[:, second], cfg)
    return np.stack((fx @ incidence, fy @ incidence), axis=-1)


def robot_force(
    pos: np.ndarray, vel: np.ndarray, mask: np.ndarray, robot_pos: np.ndarray, robot_vel: np.ndarray, cfg: HumanConfig
) -> np.ndarray:
    """Sum of Moussaid forces on every human from the robots, whose offset is scaled by 1/robot_scale.

    Args:
        pos, vel: (B, H, 2) humans.
        mask: (B, H) present humans.
        robot_pos, robot_vel: (B, R, 2) robots, world frame.

    Returns:
        (B, H, 2) m/s^2 before the social strength factor.
    """
    d = (robot_pos[:, None, :, :] - pos[:, :, None, :]) / cfg.robot_scale
    dv = vel[:, :, None, :] - robot_vel[:, None, :, :]
    valid = np.broadcast_to(mask[:, :, None], d.shape[:-1])
    fx, fy = pair_force(d[..., 0], d[..., 1], dv[..., 0], dv[..., 1], valid, cfg)
    return np.stack((fx.sum(-1), fy.sum(-1)), axis=-1)


def obstacle_force(
    pos: np.ndarray, closest: np.ndarray, dist: np.ndarray, cfg: HumanConfig
) -> np.ndarray:
    """Repulsion from the nearest wall point, exp(-(d - r) / sigma) along the wall normal.

    Args:
        pos: (B, H, 2) world frame.
        closest: (B, H, 2) nearest wall point (WallIndex.nearest).
        dist: (B, H) its distance, inf where no wall is within the index reach.

    Returns:
        (B, H, 2) acceleration before the obstacle strength factor, m/s^2.
    """
    near = np.isfinite(dist) & (dist > _TINY)
    safe = np.where(near, dist, 1.0)
    amount = np.where(near, np.exp(-(safe - cfg.force_radius) / cfg.obstacle_sigma) / safe, 0.0)
    return amount[..., None] * (pos - closest)


def human_acceleration(
    pos: np.ndarray,
    vel: np.ndarray,
    target: np.ndarray,
    pref_speed: np.ndarray,
    mask: np.ndarray,
    robot_pos: np.ndarray,
    robot_vel: np.ndarray,
    walls: WallIndex,
    cfg: HumanConfig,
    desired_vel: np.ndarray | None = None,
    learned: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Total social-force acceleration on every human.

    Args:
        pos, vel, target: (B, H, 2) human state and current waypoint, world frame.
        pref_speed: (B, H) m/s.
        mask: (B, H) present humans.
        robot_pos, robot_vel: (B, R, 2) robot positions and world-frame velocity vectors.
        walls: the map's wall index.
        cfg: parameters.
        desired_vel: (B, H, 2) desired velocity given by a learner, used where `learned`.
        learned: (B, H) bool, humans whose desired velocity comes from `desired_vel`.

    Returns:
        (accel, wall_dist): (B, H, 2) acceleration in m/s^2, zero for absent humans, and (B, H)
        distance to the nearest wall (inf beyond the index reach), reused by the motion step.
    """
    drive = desired_force(pos, vel, target, pref_speed, cfg)
    if desired_vel is not None and learned is not None:
        drive = np.where(learned[..., None], (desired_vel - vel) / cfg.relaxation_time, drive)
    social = human_pair_force(pos, vel, mask, cfg) + robot_force(pos, vel, mask, robot_pos, robot_vel, cfg)
    closest, wall_dist = walls.nearest(pos)
    wall = obstacle_force(pos, closest, wall_dist, cfg)
    accel = cfg.desired_factor * drive + cfg.social_strength * social + cfg.obstacle_strength * wall
    return np.where(mask[..., None], accel, 0.0), wall_dist
