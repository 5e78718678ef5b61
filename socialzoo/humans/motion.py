"""Integration of human motion: v += dt * a with a speed cap, p += dt * v, walls are solid.

A move whose segment would touch a wall is cancelled and the human stops, so no human ever
passes through a wall even where the wall force is too weak (sharp corners, thin walls).
"""

from __future__ import annotations

import numpy as np

from socialzoo.core.walls import WallIndex


def integrate_humans(
    pos: np.ndarray,
    vel: np.ndarray,
    accel: np.ndarray,
    max_speed: np.ndarray,
    mask: np.ndarray,
    walls: WallIndex,
    wall_dist: np.ndarray,
    dt: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One explicit Euler step of every human.

    Args:
        pos: (B, H, 2) positions, world frame, m.
        vel: (B, H, 2) velocities, world frame, m/s.
        accel: (B, H, 2) accelerations, world frame, m/s^2.
        max_speed: (B, H) speed cap, m/s.
        mask: (B, H) present humans; absent ones do not move.
        walls: the map's wall index.
        wall_dist: (B, H) distance from pos to the nearest wall (inf if beyond the index reach).
        dt: s.

    Returns:
        (pos, vel, blocked): new position and velocity, and (B, H) bool for humans whose move a
        wall stopped this step.
    """
    new_vel = vel + dt * accel
    speed = np.sqrt(new_vel[..., 0] * new_vel[..., 0] + new_vel[..., 1] * new_vel[..., 1])
    scale = np.where(speed > max_speed, max_speed / np.maximum(speed, 1e-12), 1.0)
    new_vel = np.where(mask[..., None], new_vel * scale[..., None], 0.0)
    new_pos = pos + dt * new_vel
    # A wall can only be crossed by a move at least as long as the distance to it.
    step_len = dt * np.minimum(speed, max_speed)
    near = mask & (wall_dist <= step_len)
    blocked = np.zeros(mask.shape, dtype=bool)
    if near.any():
        blocked[near] = walls.crosses(pos[near], new_pos[near])
        new_pos = np.where(blocked[..., None], pos, new_pos)
        new_vel = np.where(blocked[..., None], 0.0, new_vel)
    return new_pos, new_vel, blocked
