"""Integration of human motion: v += dt * a with a speed cap, p += dt * v, walls are solid.

A move whose segment would touch a wall is cancelled and the human stops, so no human ever
passes through a wall even where the wall force is too weak (sharp corners, thin walls).
A human already in contact with a robot does not press deeper into it (`keep_off_robots`).
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
    velocity: np.ndarray | None = None,
    direct: np.ndarray | None = None,
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
        velocity: (B, H, 2) velocities taken as they are, m/s, by the humans `direct` marks
            (ORCA people choose their velocity rather than an acceleration).
        direct: (B, H) humans that take `velocity`; None: none.

    Returns:
        (pos, vel, blocked): new position and velocity, and (B, H) bool for humans whose move a
        wall stopped this step.
    """
    new_vel = vel + dt * accel
    speed = np.sqrt(new_vel[..., 0] * new_vel[..., 0] + new_vel[..., 1] * new_vel[..., 1])
    scale = np.where(speed > max_speed, max_speed / np.maximum(speed, 1e-12), 1.0)
    new_vel = np.where(mask[..., None], new_vel * scale[..., None], 0.0)
    # A wall can only be crossed by a move at least as long as the distance to it.
    step_len = dt * np.minimum(speed, max_speed)
    if direct is not None and velocity is not None:
        chosen = mask & direct
        new_vel = np.where(chosen[..., None], velocity, new_vel)
        step_len = np.where(chosen, dt * np.sqrt(velocity[..., 0] ** 2 + velocity[..., 1] ** 2), step_len)
    new_pos = pos + dt * new_vel
    near = mask & (wall_dist <= step_len)
    blocked = np.zeros(mask.shape, dtype=bool)
    if near.any():
        blocked[near] = walls.crosses(pos[near], new_pos[near])
        new_pos = np.where(blocked[..., None], pos, new_pos)
        new_vel = np.where(blocked[..., None], 0.0, new_vel)
    return new_pos, new_vel, blocked


def keep_off_robots(
    prev_pos: np.ndarray,
    pos: np.ndarray,
    vel: np.ndarray,
    mask: np.ndarray,
    robot_pos: np.ndarray,
    distance: float,
    walls: WallIndex,
) -> tuple[np.ndarray, np.ndarray]:
    """Humans in contact with a robot bounce off it instead of pressing into it.

    A human that began the step closer than `distance` (the collision distance) to a robot and
    whose move would take it closer still has the part of its move and of its velocity towards
    that robot mirrored: it steps back out, as off a wall it touched. The social force model has
    no body force: the agent force of a robot standing beside a person's way is weak (Moussaid's
    force fades for an agent beside the walker), so a person whose straight route grazes a wall
    corner next to a waiting robot kept pressing into it (docs/benchmark.md). Entering the
    collision distance is not prevented: a person who walks into the robot still counts as a
    collision, as in the paper. A mirrored move that would touch a wall is cancelled (the human
    stops), as every move is.

    Args:
        prev_pos: (B, H, 2) positions before the step, m.
        pos: (B, H, 2) positions after it, m.
        vel: (B, H, 2) velocities after it, m/s.
        mask: (B, H) present humans.
        robot_pos: (B, R, 2) robot positions after the step, m.
        distance: the contact (collision) distance between centres, m.
        walls: the map's wall index.

    Returns:
        (pos, vel) with the bounces applied.
    """
    if robot_pos.shape[1] == 0 or pos.shape[1] == 0:
        return pos, vel
    rel = prev_pos[:, :, None, :] - robot_pos[:, None, :, :]  # (B, H, R, 2)
    d0 = np.sqrt((rel**2).sum(-1))
    d1 = np.sqrt(((pos[:, :, None, :] - robot_pos[:, None, :, :]) ** 2).sum(-1))
    pressing = mask[..., None] & (d0 < distance) & (d1 < d0) & (d0 > 1e-9)
    if not pressing.any():
        return pos, vel
    # The robot the human presses into most (the nearest one) decides its bounce.
    d0_pressing = np.where(pressing, d0, np.inf)
    nearest = np.argmin(d0_pressing, axis=-1)  # (B, H)
    rows = np.flatnonzero(np.isfinite(d0_pressing.min(axis=-1)).ravel())
    b, h = np.unravel_index(rows, mask.shape)
    r = nearest[b, h]
    n = rel[b, h, r] / d0[b, h, r][:, None]
    step = pos[b, h] - prev_pos[b, h]
    into = np.minimum((step * n).sum(-1), 0.0)
    new_pos = prev_pos[b, h] + step - 2.0 * into[:, None] * n
    v_into = np.minimum((vel[b, h] * n).sum(-1), 0.0)
    new_vel = vel[b, h] - 2.0 * v_into[:, None] * n
    hit = walls.crosses(prev_pos[b, h], new_pos) if walls.num_walls else np.zeros(len(b), dtype=bool)
    pos, vel = pos.copy(), vel.copy()
    pos[b, h] = np.where(hit[:, None], prev_pos[b, h], new_pos)
    vel[b, h] = np.where(hit[:, None], 0.0, new_vel)
    return pos, vel
