"""Integration of human motion: v += dt * a with a speed cap, p += dt * v, walls are solid."""

from __future__ import annotations

import math

import numpy as np

from socialzoo.core.jit import kernel
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

    A move whose segment would touch a wall is cancelled and the human stops, so no human ever
    passes through a wall even where the wall force is too weak (sharp corners, thin walls).

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
    batch, num = mask.shape
    new_pos = np.empty((batch, num, 2))
    new_vel = np.empty((batch, num, 2))
    near = np.empty((batch, num), dtype=bool)
    chosen = direct is not None and velocity is not None
    # wall_dist is inf where no wall is within the index's reach: a step that long may still reach one.
    reach = walls.reach if walls.num_walls else math.inf
    num_near = _euler(
        pos, vel, accel, max_speed, mask, wall_dist, reach, dt,
        velocity if chosen else vel, direct if chosen else mask, chosen, new_pos, new_vel, near,
    )  # fmt: skip
    blocked = np.zeros(mask.shape, dtype=bool)
    if num_near:
        blocked[near] = walls.crosses(pos[near], new_pos[near])
        new_pos = np.where(blocked[..., None], pos, new_pos)
        new_vel = np.where(blocked[..., None], 0.0, new_vel)
    return new_pos, new_vel, blocked


@kernel
def _euler(
    pos, vel, accel, max_speed, mask, wall_dist, reach, dt, velocity, direct, use_direct, new_pos, new_vel, near,
):  # fmt: skip
    """`integrate_humans` up to the wall test, in one pass: fills new_pos, new_vel (B, H, 2) and
    near (B, H) (present humans whose step is at least their distance to a wall, or at least `reach`,
    beyond which wall_dist does not see); returns how
    many are near. The operations are numpy's, in its order (a speed is capped as
    np.where(speed > cap, cap / np.maximum(speed, 1e-12), 1.0) scales it, a NaN propagates as in
    np.minimum), so the results are the same bit for bit."""
    count = 0
    for b in range(mask.shape[0]):
        for h in range(mask.shape[1]):
            vx = vel[b, h, 0] + dt * accel[b, h, 0]
            vy = vel[b, h, 1] + dt * accel[b, h, 1]
            speed = math.sqrt(vx * vx + vy * vy)
            cap = max_speed[b, h]
            if speed > cap:
                scale = cap / max(speed, 1e-12)
                vx, vy = vx * scale, vy * scale
            capped = speed if (speed < cap or math.isnan(speed)) else cap
            step_len = dt * capped
            if not mask[b, h]:
                vx, vy = 0.0, 0.0
            elif use_direct and direct[b, h]:
                vx, vy = velocity[b, h, 0], velocity[b, h, 1]
                step_len = dt * math.sqrt(vx * vx + vy * vy)
            new_vel[b, h, 0] = vx
            new_vel[b, h, 1] = vy
            new_pos[b, h, 0] = pos[b, h, 0] + dt * vx
            new_pos[b, h, 1] = pos[b, h, 1] + dt * vy
            near[b, h] = mask[b, h] and min(wall_dist[b, h], reach) <= step_len
            if near[b, h]:
                count += 1
    return count


@kernel
def _pressing(prev_pos, pos, mask, robot_pos, distance, nearest):
    """The robot each human presses into (`keep_off_robots`): nearest (B, H) is the index of the
    nearest robot (at the start of the step) among those it began closer than `distance` to and
    came closer still, -1 for none; returns how many humans press into one."""
    count = 0
    for b in range(mask.shape[0]):
        for h in range(mask.shape[1]):
            nearest[b, h] = -1
            if not mask[b, h]:
                continue
            best = math.inf
            for r in range(robot_pos.shape[1]):
                rx, ry = prev_pos[b, h, 0] - robot_pos[b, r, 0], prev_pos[b, h, 1] - robot_pos[b, r, 1]
                d0 = math.sqrt(rx * rx + ry * ry)
                qx, qy = pos[b, h, 0] - robot_pos[b, r, 0], pos[b, h, 1] - robot_pos[b, r, 1]
                d1 = math.sqrt(qx * qx + qy * qy)
                if d0 < distance and d1 < d0 and d0 > 1e-9 and d0 < best:
                    best = d0
                    nearest[b, h] = r
            if nearest[b, h] >= 0:
                count += 1
    return count


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
    nearest = np.empty(mask.shape, dtype=np.int64)
    if _pressing(prev_pos, pos, mask, robot_pos, distance, nearest) == 0:
        return pos, vel
    # The robot the human presses into most (the nearest one) decides its bounce.
    b, h = np.nonzero(nearest >= 0)
    rel = prev_pos[b, h] - robot_pos[b, nearest[b, h]]
    n = rel / np.sqrt((rel**2).sum(-1))[:, None]
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
