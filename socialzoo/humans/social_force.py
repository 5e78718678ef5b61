"""The social force model of PedSim (Helbing-Molnar with Moussaid's agent interaction).

One implementation for every use: arrays carry a batch axis B and a human axis H, and the
robots are just more agents seen by the humans (their position difference scaled by 1/1.5).
Moussaid's pair force is antisymmetric between two humans (swapping them negates both the
position and the velocity difference), so each human pair is computed once.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from socialzoo.core.config import HumanConfig
from socialzoo.core.walls import WallIndex

# Distances below this are treated as coincident agents (metres).
_TINY = 1e-9
# Exponents are floored here: exp() of far smaller numbers underflows into denormals, which
# are many times slower, while exp(-60) ~ 1e-26 is already no force at all.
_EXP_FLOOR = -60.0


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
    dist = np.sqrt(to_target[..., 0:1] * to_target[..., 0:1] + to_target[..., 1:2] * to_target[..., 1:2])
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

    Written with in-place operations: on batched inputs the temporaries are large, and fresh
    allocations (and their page faults) cost as much as the arithmetic. Inputs are not modified.

    Args:
        dx, dy: position of the other agent minus this agent's, m.
        dvx, dvy: this agent's velocity minus the other's, m/s.
        valid: pairs that interact; others get zero force.
        cfg: lambda, gamma, n and n' of the model.

    Returns:
        (fx, fy) before the social strength factor, m/s^2, in the dtype of dx.
    """
    # sqrt(x*x + y*y) rather than np.hypot: no overflow is possible here, and hypot's careful
    # float32 loop is several times slower.
    dist = dx * dx
    dist += dy * dy
    np.sqrt(dist, out=dist)
    # Coincident or invalid pairs are zeroed by one multiplication at the end; flooring the
    # distance keeps their intermediate values finite (boolean-mask writes cost more).
    weight = (valid & (dist > _TINY)).astype(dx.dtype)
    np.maximum(dist, _TINY, out=dist)
    ex = dx / dist
    ey = dy / dist
    ix = dvx * cfg.social_lambda
    ix += ex
    iy = dvy * cfg.social_lambda
    iy += ey
    inter_len = ix * ix
    inter_len += iy * iy
    np.sqrt(inter_len, out=inter_len)
    np.maximum(inter_len, _TINY, out=inter_len)
    ix /= inter_len
    iy /= inter_len
    # Signed angle from the interaction direction to the direction of the other agent.
    cross = ix * ey
    cross -= iy * ex
    dot = ix * ex
    dot += iy * ey
    theta = np.arctan2(cross, dot, out=cross)
    b = inter_len
    b *= cfg.social_gamma
    base = np.divide(dist, b, out=dist)
    np.negative(base, out=base)
    bt2 = b
    bt2 *= theta
    bt2 *= bt2
    speed_amount = np.multiply(bt2, -(cfg.social_n_prime**2), out=dot)
    speed_amount += base
    np.maximum(speed_amount, _EXP_FLOOR, out=speed_amount)
    np.exp(speed_amount, out=speed_amount)
    angle_amount = np.multiply(bt2, -(cfg.social_n**2), out=ex)
    angle_amount += base
    np.maximum(angle_amount, _EXP_FLOOR, out=angle_amount)
    np.exp(angle_amount, out=angle_amount)
    angle_amount *= np.sign(theta, out=theta)
    speed_amount *= weight
    angle_amount *= weight
    # Both amounts carry a minus sign in the model; the angle force acts along the left normal:
    # f = -speed * i - angle * (-iy, ix).
    fx = angle_amount * iy
    fx -= speed_amount * ix
    fy = speed_amount * iy
    fy += angle_amount * ix
    np.negative(fy, out=fy)
    return fx, fy


@dataclass(frozen=True)
class _PairLayout:
    """Which agent pairs one batched force evaluation covers.

    Pairs are the human pairs i < j, then every (human, robot) pair. Agents are indexed in the
    concatenation [humans, robots].

    Attributes:
        this: (P,) the human the pair force acts on.
        other: (P,) the agent exerting it.
        difference: (H + R, P) float32 with +1 at `other` and -1 at `this`, so that
            values (.., H + R) @ difference gives other - this for every pair exactly (two
            non-zero terms per column: the sum has a single rounding whatever the BLAS kernel).
        robot_pairs: (P_r,) columns of the (human, robot) pairs.
        human_pairs: number of human pairs (the first columns).
    """

    this: np.ndarray
    other: np.ndarray
    difference: np.ndarray
    robot_pairs: np.ndarray
    human_pairs: int


@lru_cache(maxsize=64)
def _pair_layout(num_humans: int, num_robots: int) -> _PairLayout:
    first, second = np.triu_indices(num_humans, k=1)
    this = np.concatenate((first, np.repeat(np.arange(num_humans), num_robots)))
    other = np.concatenate((second, num_humans + np.tile(np.arange(num_robots), num_humans)))
    difference = np.zeros((num_humans + num_robots, len(this)), dtype=np.float32)
    difference[other, np.arange(len(this))] = 1.0
    difference[this, np.arange(len(this))] = -1.0
    return _PairLayout(
        this=this,
        other=other,
        difference=difference,
        robot_pairs=np.arange(len(first), len(this)),
        human_pairs=len(first),
    )


def social_pair_force(
    pos: np.ndarray,
    vel: np.ndarray,
    mask: np.ndarray,
    robot_pos: np.ndarray,
    robot_vel: np.ndarray,
    cfg: HumanConfig,
) -> np.ndarray:
    """Sum of Moussaid forces on every human from the other humans and from the robots.

    Robot offsets are divided by cfg.robot_scale before the force (SPEC: the robot as an agent
    like the others, its position difference scaled by 1/1.5). Robots feel no force here.

    Args:
        pos, vel: (B, H, 2) humans, world frame.
        mask: (B, H) present humans.
        robot_pos, robot_vel: (B, R, 2) robots, world frame.

    Returns:
        (B, H, 2) m/s^2 before the social strength factor.
    """
    batch, num_humans = pos.shape[:2]
    num_robots = robot_pos.shape[1]
    layout = _pair_layout(num_humans, num_robots)
    # Pair terms are evaluated in float32: half the memory traffic of the (B, P) temporaries,
    # relative error ~1e-6 on forces that the 0.025 s Euler step integrates far more coarsely.
    agents = np.empty((4, batch, num_humans + num_robots), dtype=np.float32)
    agents[0, :, :num_humans] = pos[..., 0]
    agents[1, :, :num_humans] = pos[..., 1]
    agents[2, :, :num_humans] = vel[..., 0]
    agents[3, :, :num_humans] = vel[..., 1]
    agents[0, :, num_humans:] = robot_pos[..., 0]
    agents[1, :, num_humans:] = robot_pos[..., 1]
    agents[2, :, num_humans:] = robot_vel[..., 0]
    agents[3, :, num_humans:] = robot_vel[..., 1]
    # One matmul gives every pair's (other - this) position and velocity difference.
    diff = agents @ layout.difference  # (4, B, P)
    diff[:2, :, layout.robot_pairs] *= np.float32(1.0 / cfg.robot_scale)
    present = np.concatenate((mask, np.ones((batch, num_robots), dtype=bool)), axis=1)
    valid = np.take(present, layout.this, axis=1) & np.take(present, layout.other, axis=1)
    fx, fy = pair_force(diff[0], diff[1], -diff[2], -diff[3], valid, cfg)
    # Scatter into (B, H, H + R) and sum each human's row: the summation order is fixed per
    # row, so a world steps bit for bit the same alone or in any batch.
    num_pairs = layout.human_pairs
    human_this, human_other = layout.this[:num_pairs], layout.other[:num_pairs]
    out = np.empty(pos.shape)
    for axis, f in enumerate((fx, fy)):
        table = np.zeros((batch, num_humans, num_humans + num_robots), dtype=np.float32)
        table[:, layout.this, layout.other] = f
        table[:, human_other, human_this] = -f[:, :num_pairs]
        out[..., axis] = table.sum(axis=2)
    return out


def obstacle_force(pos: np.ndarray, closest: np.ndarray, dist: np.ndarray, cfg: HumanConfig) -> np.ndarray:
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
    exponent = np.maximum(-(safe - cfg.force_radius) / cfg.obstacle_sigma, _EXP_FLOOR)
    amount = np.where(near, np.exp(exponent) / safe, 0.0)
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
    social = social_pair_force(pos, vel, mask, robot_pos, robot_vel, cfg)
    closest, wall_dist = walls.nearest(pos)
    wall = obstacle_force(pos, closest, wall_dist, cfg)
    accel = cfg.desired_factor * drive + cfg.social_strength * social + cfg.obstacle_strength * wall
    return np.where(mask[..., None], accel, 0.0), wall_dist
