"""The Social Action Selection reward (SPEC section 9): progress, blame, social force, success."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from socialzoo.core.jit import kernel
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


@kernel
def _nearest_visible(robot_pos, human_pos, visible, skip, nearest2, nearest):  # type: ignore[no-untyped-def]
    """Fill nearest2 (B,), the squared distance to the nearest counted human (visible, not the
    skipped one; inf for none), and nearest (B,), its index (0 for none)."""
    for b in range(human_pos.shape[0]):
        nearest2[b], nearest[b] = _nearest_in_row(b, robot_pos, human_pos, visible, skip)


@kernel
def _nearest_in_row(b, robot_pos, human_pos, visible, skip):  # type: ignore[no-untyped-def]
    """(squared distance, index) of row b's nearest counted human: inf and 0 for none, the first
    of equals, and the first NaN distance as numpy's argmin gives it."""
    best, at = np.inf, 0
    for h in range(human_pos.shape[1]):
        if not visible[b, h] or h == skip[b]:
            continue
        dx, dy = human_pos[b, h, 0] - robot_pos[b, 0], human_pos[b, h, 1] - robot_pos[b, 1]
        d2 = dx * dx + dy * dy
        if d2 != d2:
            return d2, h
        if d2 < best:
            best, at = d2, h
    return best, at


@kernel
def _blame_parts(  # type: ignore[no-untyped-def]
    robot_pos, robot_vel, still, human_pos, visible, skip, horizon, nearest2, dist, counted
):
    """force_and_blame's parts per row: nearest2 (B,) as _nearest_visible's, dist (B,) the nearest
    human's distance to the robot's segment [p, p + horizon v] (closest_point_on_segment's numpy
    expressions; human 0 for none) and counted (B,), someone counted and the robot not still."""
    for b in range(human_pos.shape[0]):
        d2, h = _nearest_in_row(b, robot_pos, human_pos, visible, skip)
        nearest2[b] = d2
        counted[b] = np.isfinite(d2) and not still[b]
        ax, ay = robot_pos[b, 0], robot_pos[b, 1]
        abx, aby = (ax + horizon * robot_vel[b, 0]) - ax, (ay + horizon * robot_vel[b, 1]) - ay
        apx, apy = human_pos[b, h, 0] - ax, human_pos[b, h, 1] - ay
        denom = abx * abx + aby * aby
        t = (apx * abx + apy * aby) / (denom if denom > 0.0 else 1.0)
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
        dx, dy = human_pos[b, h, 0] - (ax + t * abx), human_pos[b, h, 1] - (ay + t * aby)
        dist[b] = np.sqrt(dx * dx + dy * dy)


def nearest_visible(
    robot_pos: np.ndarray, human_pos: np.ndarray, visible: np.ndarray, skip: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """((B,) squared distance to the nearest visible human other than the skipped one, inf for
    none; (B,) its index, 0 for none): one pass over the people for both reward terms."""
    batch = robot_pos.shape[0]
    nearest2, nearest = np.empty(batch), np.empty(batch, dtype=np.intp)
    _nearest_visible(
        robot_pos, human_pos, np.asarray(visible, dtype=bool), _skips(skip, batch), nearest2, nearest
    )
    return nearest2, nearest


def _skips(skip: np.ndarray, batch: int) -> np.ndarray:
    """(B,) int64 the skipped human of each row (one index for all rows is broadcast)."""
    skip = np.asarray(skip, dtype=np.int64)
    return skip if skip.shape == (batch,) else np.broadcast_to(skip, (batch,))


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
    d2, _ = nearest_visible(robot_pos, human_pos, visible, skip)
    return _force(d2)


def _force(nearest2: np.ndarray) -> np.ndarray:
    """exp(-d^4) of the squared distances d^2 (0 for inf: nobody counted)."""
    return np.exp(-(nearest2 * nearest2))


def force_and_blame(
    robot_pos: np.ndarray,
    robot_vel_world: np.ndarray,
    halted_or_still: np.ndarray,
    human_pos: np.ndarray,
    visible: np.ndarray,
    skip: np.ndarray,
    horizon: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The social force term (social_force_term) and the blame b = 1 - erf(dist(h, S)) (SPEC
    section 9), from one pass over the people.

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
        (force, blame), each (B,) in [0, 1].
    """
    batch = robot_pos.shape[0]
    if human_pos.shape[1] == 0:
        return np.zeros(batch), np.zeros(batch)
    d2, dist, counted = np.empty(batch), np.empty(batch), np.empty(batch, dtype=bool)
    _blame_parts(
        robot_pos, robot_vel_world, np.asarray(halted_or_still, dtype=bool), human_pos,
        np.asarray(visible, dtype=bool), _skips(skip, batch), float(horizon), d2, dist, counted,
    )  # fmt: skip
    return _force(d2), np.where(counted, 1.0 - erf(dist), 0.0)


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
        blame: (B,) from `force_and_blame`.
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
