"""The Social Action Selection reward (SPEC section 9): progress, blame, social force, success.

Pure batched functions over B worlds; the weights live in RewardConfig.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from socialzoo.core.geometry import closest_point_on_segment
from socialzoo.core.validation import check_fields
from socialzoo.env.quirks import ReferenceQuirks

try:
    from scipy.special import erf as _scipy_erf
except ImportError:  # scipy is optional: fall back on a numpy approximation
    _scipy_erf = None

# Abramowitz and Stegun 7.1.26: erf(x) = 1 - t (a1 + t (a2 + ...)) exp(-x^2), t = 1 / (1 + p x),
# for x >= 0, absolute error below 1.5e-7.
_AS_P = 0.3275911
_AS_A = (0.254829592, -0.284496736, 1.421413741, -1.453152027, 1.061405429)


def erf_approx(x: np.ndarray) -> np.ndarray:
    """The error function by Abramowitz and Stegun 7.1.26 (numpy only), |error| < 1.5e-7."""
    x = np.asarray(x, dtype=np.float64)
    ax = np.abs(x)
    t = 1.0 / (1.0 + _AS_P * ax)
    a1, a2, a3, a4, a5 = _AS_A
    poly = t * (a1 + t * (a2 + t * (a3 + t * (a4 + t * a5))))
    return np.copysign(1.0 - poly * np.exp(-ax * ax), x)


def erf(x: np.ndarray) -> np.ndarray:
    """The error function, elementwise: scipy.special.erf when scipy is installed, else
    `erf_approx` (the two differ by less than 1.5e-7)."""
    if _scipy_erf is not None:
        return np.asarray(_scipy_erf(x), dtype=np.float64)
    return erf_approx(x)


@dataclass(frozen=True, kw_only=True)
class RewardConfig:
    """Weights of r = w1 * d_g + w_blame * b + w_force * f + (c if success) + w_collision * n_c.

    Attributes:
        w_progress: w1 when the distance gained d_g >= 0, per metre.
        w_progress_negative: w1 when d_g < 0 (moving away costs more), per metre.
        w_blame: weight of the blame b in [0, 1].
        w_force: weight of the social force term f in [0, 1].
        success_bonus: c, paid on the step the episode succeeds.
        w_collision: weight of the number of humans in collision this step. The reference code
            computed this penalty but never added it (SPEC section 11), hence the default 0.
        blame_horizon: the blame segment covers the robot's next blame_horizon seconds at its
            current velocity, s.
    """

    w_progress: float = 5.0
    w_progress_negative: float = 10.0
    w_blame: float = -0.1
    w_force: float = -0.01
    success_bonus: float = 100.0
    w_collision: float = 0.0
    blame_horizon: float = 0.5

    def __post_init__(self) -> None:
        check_fields(self, signed=[f.name for f in fields(self) if f.name != "blame_horizon"])


def _nearest_distance2(
    robot_pos: np.ndarray, human_pos: np.ndarray, visible: np.ndarray, skip: np.ndarray
) -> np.ndarray:
    """(B, H) squared robot-human distances, inf for humans not visible or skipped."""
    rel = human_pos - robot_pos[:, None, :]
    dist2 = rel[..., 0] ** 2 + rel[..., 1] ** 2
    counted = visible & (np.arange(human_pos.shape[1]) != np.asarray(skip)[:, None])
    return np.where(counted, dist2, np.inf)


def social_force_term(
    robot_pos: np.ndarray, human_pos: np.ndarray, visible: np.ndarray, skip: np.ndarray
) -> np.ndarray:
    """Force f = exp(-d^4), d the distance to the nearest visible human, 0 if none (SPEC 9).

    Args:
        robot_pos: (B, 2) robot centre, m, world frame.
        human_pos: (B, H, 2) human centres, m, world frame.
        visible: (B, H) bool, humans the robot sees.
        skip: (B,) int index of a human left out (the followed one in Follow), -1 for none.

    Returns:
        (B,) in [0, 1].
    """
    d2 = _nearest_distance2(robot_pos, human_pos, visible, skip).min(axis=1, initial=np.inf)
    return np.exp(-(d2 * d2))


def blame_term(
    robot_pos: np.ndarray,
    robot_vel_world: np.ndarray,
    halted_or_still: np.ndarray,
    human_pos: np.ndarray,
    visible: np.ndarray,
    skip: np.ndarray,
    horizon: float,
) -> np.ndarray:
    """Blame b = 1 - erf(dist(h, S)) (SPEC section 9).

    S is the segment from the robot to where its current velocity takes it in `horizon` seconds,
    h the visible human nearest to the robot (the skipped one left out). b is 0 for a halted or
    still robot and when no human counts.

    Args:
        robot_pos: (B, 2) robot centre, m, world frame.
        robot_vel_world: (B, 2) robot velocity vector, m/s, world frame.
        halted_or_still: (B,) bool, robots that chose Halt or do not move (the caller decides
            what counts as still).
        human_pos: (B, H, 2) human centres, m, world frame.
        visible: (B, H) bool.
        skip: (B,) int index of a human left out (the followed one), -1 for none.
        horizon: s.

    Returns:
        (B,) in [0, 1].
    """
    batch = robot_pos.shape[0]
    if human_pos.shape[1] == 0:
        return np.zeros(batch)
    d2 = _nearest_distance2(robot_pos, human_pos, visible, skip)
    nearest = np.argmin(d2, axis=1)
    rows = np.arange(batch)
    counted = np.isfinite(d2[rows, nearest]) & ~np.asarray(halted_or_still, dtype=bool)
    _, dist = closest_point_on_segment(
        human_pos[rows, nearest], robot_pos, robot_pos + horizon * robot_vel_world
    )
    return np.where(counted, 1.0 - erf(dist), 0.0)


def progress(prev_pos: np.ndarray, pos: np.ndarray, goal: np.ndarray, x_only: bool = False) -> np.ndarray:
    """Distance gained towards the goal d_g = |p_{t-1} - g| - |p_t - g|, Euclidean (SPEC 11).

    Args:
        prev_pos: (B, 2) robot position before the step, m, world frame.
        pos: (B, 2) after the step.
        goal: (B, 2) goal position.
        x_only: the reference code's distance, |x - x_g| along the world x axis only
            (ReferenceQuirks.goal_distance_x_only).

    Returns:
        (B,) m; negative when the robot moved away.
    """
    if x_only:
        return np.abs(prev_pos[:, 0] - goal[:, 0]) - np.abs(pos[:, 0] - goal[:, 0])
    before = prev_pos - goal
    after = pos - goal
    return np.sqrt(before[:, 0] ** 2 + before[:, 1] ** 2) - np.sqrt(after[:, 0] ** 2 + after[:, 1] ** 2)


def compute_reward(
    d_g: np.ndarray,
    blame: np.ndarray,
    force: np.ndarray,
    success: np.ndarray,
    collisions: np.ndarray,
    cfg: RewardConfig,
    quirks: ReferenceQuirks | None = None,
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """r = w1 * d_g + w_blame * b + w_force * f + (c if success) + w_collision * collisions.

    With `quirks` (socialzoo.env.quirks), the reference code's reward: collision_penalty_dropped
    leaves the collision term out, reward_distance_plus_bonus leaves out every term but progress
    and success. A term left out is 0 in `terms`, so the terms still sum to the reward.

    Args:
        d_g: (B,) distance gained, m (from `progress`).
        blame: (B,) from `blame_term`.
        force: (B,) from `social_force_term`.
        success: (B,) bool, the episode succeeds on this step.
        collisions: (B,) int, humans in collision with the robot this step.
        cfg: weights.
        quirks: the reference code's quirks (None: none).

    Returns:
        (reward, terms): reward (B,) float64, and the weighted terms (B,) each, keyed "progress",
        "blame", "force", "success", "collision", whose sum in that order is the reward.
    """
    terms = {
        "progress": np.where(d_g >= 0.0, cfg.w_progress, cfg.w_progress_negative) * d_g,
        "blame": cfg.w_blame * np.asarray(blame, dtype=np.float64),
        "force": cfg.w_force * np.asarray(force, dtype=np.float64),
        "success": np.where(success, cfg.success_bonus, 0.0),
        "collision": cfg.w_collision * np.asarray(collisions, dtype=np.float64),
    }
    if quirks is not None and quirks.reward_distance_plus_bonus:
        for name in ("blame", "force"):
            terms[name] = np.zeros_like(terms[name])
    if quirks is not None and quirks.drops_collision:
        terms["collision"] = np.zeros_like(terms["collision"])
    reward = terms["progress"] + terms["blame"] + terms["force"] + terms["success"] + terms["collision"]
    return reward, terms
