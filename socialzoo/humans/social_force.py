"""The social force model of PedSim (Helbing-Molnar with Moussaid's agent interaction)."""

from __future__ import annotations

import math

import numpy as np

from socialzoo.core.config import HumanConfig
from socialzoo.core.jit import kernel
from socialzoo.core.walls import WallIndex

# Distances below this are treated as coincident agents (metres).
_TINY = 1e-9
# Exponents are floored here: exp() of far smaller numbers underflows into denormals, which
# are many times slower, while exp(-60) ~ 1e-26 is already no force at all.
_EXP_FLOOR = -60.0


# Rows of the per-pair work table filled by the kernels below.
_DIST, _IX, _IY, _INTER, _CROSS, _DOT = range(6)


@kernel
def _pair_directions(pos, vel, mask, robot_pos, robot_vel, lam, inv_scale, work):
    """First part of Moussaid's force for every pair: distance and interaction direction.

    A world's P pairs are listed human by human: for human i, the humans j > i, then every
    robot; pair p of world b is column b * P + p of work (6, B * P). The force on `this` human from the `other` agent
    uses dx = other - this (robot offsets scaled by 1 / robot_scale) and dv = v_this - v_other.
    Absent or coincident pairs get distance 0, which the last kernel reads as "no force".
    """
    batch, num_humans = mask.shape
    num_robots = robot_pos.shape[1]
    col = 0
    for b in range(batch):
        for i in range(num_humans):
            for j in range(i + 1, num_humans + num_robots):
                if j < num_humans:
                    valid = mask[b, i] and mask[b, j]
                    dx, dy = pos[b, j, 0] - pos[b, i, 0], pos[b, j, 1] - pos[b, i, 1]
                    dvx, dvy = vel[b, i, 0] - vel[b, j, 0], vel[b, i, 1] - vel[b, j, 1]
                else:
                    r = j - num_humans
                    valid = mask[b, i]
                    dx = (robot_pos[b, r, 0] - pos[b, i, 0]) * inv_scale
                    dy = (robot_pos[b, r, 1] - pos[b, i, 1]) * inv_scale
                    dvx, dvy = vel[b, i, 0] - robot_vel[b, r, 0], vel[b, i, 1] - robot_vel[b, r, 1]
                dist = math.sqrt(dx * dx + dy * dy)
                if not valid or dist <= _TINY:
                    # Finite placeholders: the numpy passes run over these columns too.
                    work[_DIST, col] = 0.0
                    work[_INTER, col] = 1.0
                    work[_CROSS, col] = 0.0
                    work[_DOT, col] = 1.0
                    col += 1
                    continue
                ex, ey = dx / dist, dy / dist
                ix, iy = lam * dvx + ex, lam * dvy + ey
                inter_len = max(math.sqrt(ix * ix + iy * iy), _TINY)
                ix /= inter_len
                iy /= inter_len
                work[_DIST, col] = dist
                work[_IX, col] = ix
                work[_IY, col] = iy
                work[_INTER, col] = inter_len
                # atan2 of these is the signed angle from the interaction direction to the
                # direction of the other agent (numpy's vectorised atan2 is far faster).
                work[_CROSS, col] = ix * ey - iy * ex
                work[_DOT, col] = ix * ex + iy * ey
                col += 1


@kernel
def _pair_exponents(work, theta, gamma, n2, np2, exponents):
    """Exponents of the speed and angle terms, floored: (2, N) from work (6, N) and theta (N,)."""
    for col in range(theta.shape[0]):
        b = gamma * work[_INTER, col]
        base = -work[_DIST, col] / b
        bt2 = (b * theta[col]) ** 2
        exponents[0, col] = max(base - np2 * bt2, _EXP_FLOOR)
        exponents[1, col] = max(base - n2 * bt2, _EXP_FLOOR)


@kernel
def _accelerations(
    pos, vel, target, pref_speed, mask, closest, wall_dist, desired_vel, learned,
    num_robots, work, theta, amounts, params, out,
):  # fmt: skip
    """Fill out (B, H, 2) with every human's total acceleration; see human_acceleration.

    amounts: (2, B * P) exp of the pair exponents (speed, angle). params: relaxation_time,
    desired_factor, social_strength, obstacle_strength, obstacle_sigma, force_radius, 1.0 when
    the forces act on learned people too (HumanConfig.learned_forces) else 0.0, and the learned
    people's relaxation time (HumanConfig.learned_tau).
    """
    tau, k_desired, k_social, k_wall, sigma, radius, learned_forces, learned_tau = params
    batch, num_humans = mask.shape
    pairs_per_world = theta.shape[0] // batch
    social = np.zeros((num_humans, 2))
    for b in range(batch):
        social[:] = 0.0
        # Pairs in _pair_directions' fixed order (see human_acceleration's docstring); robots feel no force here.
        col = b * pairs_per_world
        for i in range(num_humans):
            for j in range(i + 1, num_humans + num_robots):
                if work[_DIST, col] > 0.0:
                    t = theta[col]
                    speed = amounts[0, col]
                    angle = amounts[1, col] if t > 0.0 else (-amounts[1, col] if t < 0.0 else 0.0)
                    ix, iy = work[_IX, col], work[_IY, col]
                    # Both amounts carry a minus sign in the model; the angle force acts along
                    # the left normal: f = -speed * i - angle * (-iy, ix).
                    fx = angle * iy - speed * ix
                    fy = -(speed * iy + angle * ix)
                    social[i, 0] += fx
                    social[i, 1] += fy
                    if j < num_humans:
                        social[j, 0] -= fx
                        social[j, 1] -= fy
                col += 1
        for i in range(num_humans):
            if not mask[b, i]:
                out[b, i, 0] = 0.0
                out[b, i, 1] = 0.0
                continue
            px, py = pos[b, i, 0], pos[b, i, 1]
            vx, vy = vel[b, i, 0], vel[b, i, 1]
            # Relaxation towards the desired velocity: the preferred speed straight to the route
            # target, or the learner's desired velocity.
            relax = tau
            if learned[b, i]:
                relax = learned_tau
                wx, wy = desired_vel[b, i, 0], desired_vel[b, i, 1]
                if learned_forces == 0.0:
                    out[b, i, 0] = k_desired * ((wx - vx) / relax)
                    out[b, i, 1] = k_desired * ((wy - vy) / relax)
                    continue
            else:
                tx, ty = target[b, i, 0] - px, target[b, i, 1] - py
                scale = pref_speed[b, i] / max(math.sqrt(tx * tx + ty * ty), _TINY)
                wx, wy = tx * scale, ty * scale
            ax = k_desired * ((wx - vx) / relax) + k_social * social[i, 0]
            ay = k_desired * ((wy - vy) / relax) + k_social * social[i, 1]
            # Repulsion from the nearest wall point, exp(-(d - r) / sigma) along the wall normal.
            d = wall_dist[b, i]
            if math.isfinite(d) and d > _TINY:
                amount = k_wall * math.exp(max(-(d - radius) / sigma, _EXP_FLOOR)) / d
                ax += amount * (px - closest[b, i, 0])
                ay += amount * (py - closest[b, i, 1])
            out[b, i, 0] = ax
            out[b, i, 1] = ay


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

    One implementation for every use: arrays carry a batch axis B and a human axis H, and the
    robots are just more agents seen by the humans (their position difference scaled by 1/1.5).
    Moussaid's pair force is antisymmetric between two humans (swapping them negates both the
    position and the velocity difference), so each human pair is computed once.

    The forces are compiled kernels (socialzoo.core.jit) that loop over worlds, pairs and humans;
    only atan2 and exp run as numpy calls over all pairs at once, because numpy's vectorised versions
    are several times faster per element than scalar ones. Pairs are laid out and summed per world
    in a fixed order, so a world steps bit for bit the same alone or in any batch.

    Args:
        pos: (B, H, 2) human positions, world frame, m.
        vel: (B, H, 2) human velocities, world frame, m/s.
        target: (B, H, 2) each human's current waypoint, world frame, m.
        pref_speed: (B, H) m/s.
        mask: (B, H) present humans.
        robot_pos: (B, R, 2) robot positions, world frame, m.
        robot_vel: (B, R, 2) robot velocity vectors, world frame, m/s.
        walls: the map's wall index.
        cfg: parameters.
        desired_vel: (B, H, 2) desired velocity given by a learner, used where `learned`.
        learned: (B, H) bool, humans whose desired velocity comes from `desired_vel`.

    Returns:
        (accel, wall_dist): (B, H, 2) acceleration in m/s^2, zero for absent humans, and (B, H)
        distance to the nearest wall (inf beyond the index reach), reused by the motion step.
    """
    batch, num_humans = mask.shape
    num_robots = robot_pos.shape[1]
    if learned is None or desired_vel is None:
        learned = np.zeros((batch, num_humans), dtype=bool)
        desired_vel = pos
    closest, wall_dist = walls.nearest(pos)
    # Moussaid's pair force in three compiled passes around numpy's atan2 and exp (human_acceleration's docstring).
    num_pairs = batch * (num_humans * (num_humans - 1) // 2 + num_humans * num_robots)
    work = np.empty((6, num_pairs))
    _pair_directions(pos, vel, mask, robot_pos, robot_vel, cfg.social_lambda, 1.0 / cfg.robot_scale, work)
    theta = np.arctan2(work[_CROSS], work[_DOT])
    amounts = np.empty((2, num_pairs))
    _pair_exponents(work, theta, cfg.social_gamma, cfg.social_n**2, cfg.social_n_prime**2, amounts)
    np.exp(amounts, out=amounts)
    params = (
        cfg.relaxation_time, cfg.desired_factor, cfg.social_strength, cfg.obstacle_strength,
        cfg.obstacle_sigma, cfg.force_radius, 1.0 if cfg.learned_forces else 0.0, cfg.learned_tau,
    )  # fmt: skip
    accel = np.empty((batch, num_humans, 2))
    _accelerations(
        pos, vel, target, pref_speed, mask, closest, wall_dist, desired_vel, learned,
        num_robots, work, theta, amounts, params, accel,
    )  # fmt: skip
    return accel, wall_dist
