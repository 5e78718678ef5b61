"""What a step of the CrowdNav task means: collision, goal, time limit, reward and the episode metrics
of that line of work (CrowdNav's crowd_sim.py step() and explorer.py)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.core.metrics import names as metric_names
from socialzoo.core.validation import check_fields

# The per-episode metrics of the task (CrowdNavMetrics.summaries keys, in order): the registry's
# metrics of this task (socialzoo.core.metrics).
METRIC_KEYS: tuple[str, ...] = metric_names("crowdnav")


@dataclass(frozen=True, kw_only=True)
class CrowdRewardConfig:
    """CrowdNav's reward ([reward] of env.config).

    Attributes:
        success_reward: at the goal.
        collision_penalty: on a collision (negative).
        discomfort_dist: boundary distance below which the robot is penalised, m.
        discomfort_penalty_factor: the penalty's weight, per second.
        gamma: the discount of the reported discounted return, per second at the preferred speed
            (CrowdNav's rl gamma 0.9, applied as gamma ** (t * dt * v_pref)).
    """

    success_reward: float = 1.0
    collision_penalty: float = -0.25
    discomfort_dist: float = 0.2
    discomfort_penalty_factor: float = 0.5
    gamma: float = 0.9

    def __post_init__(self) -> None:
        check_fields(
            self, nonnegative=("discomfort_dist", "discomfort_penalty_factor"), signed=("collision_penalty",)
        )


def track_approach(
    closest: np.ndarray,
    moved: np.ndarray,
    robot_before: np.ndarray,
    robot_after: np.ndarray,
    human_pos: np.ndarray,
    human_vel: np.ndarray,
    radius_sum: np.ndarray,
    human_mask: np.ndarray,
    dt: float,
) -> None:
    """Add one world step of the robots' moves from `robot_before` to `robot_after` (B, 2): the
    smallest distance between the robot's and a person's boundaries during it (the robot at its
    velocity through the step; inf where nobody is present, negative where they overlapped) into the
    running minimum `closest` (B,), and the distance each robot moved into `moved` (B,), in place.
    human_pos, human_vel: (B, H, 2) the people's positions and velocities at the start of the step;
    radius_sum: (B, H) robot radius + person radius; human_mask: (B, H); dt: s."""
    _track_approach(
        robot_before, robot_after, human_pos, human_vel, radius_sum, human_mask, dt, closest, moved
    )


@kernel
def _track_approach(robot_before, robot_after, human_pos, human_vel, radius, human_mask, dt, closest, moved):
    """track_approach: the numpy expressions it replaced per robot (the shift after - before, np.hypot
    of it, the velocity shift / dt, np.minimum's NaN kept)."""
    for i in range(closest.shape[0]):
        sx, sy = robot_after[i, 0] - robot_before[i, 0], robot_after[i, 1] - robot_before[i, 1]
        moved[i] += np.hypot(sx, sy)
        rx, ry = robot_before[i, 0], robot_before[i, 1]
        gap = _row_gap(i, rx, ry, sx / dt, sy / dt, human_pos, human_vel, radius, human_mask, dt)
        closest[i] = nan_min(closest[i], gap)


@kernel
def nan_min(a: float, b: float) -> float:
    """np.minimum of two floats: the smaller, a NaN of either wins (scalar kernel)."""
    return a if a < b or a != a else b


@kernel
def _row_gap(i, rx, ry, vx, vy, human_pos, human_vel, radius, human_mask, dt):
    """Row i's closest boundary distance for a robot at (rx, ry) moving at (vx, vy), present people
    only: per person the numpy expressions it replaced (the relative move over the step, its
    closest_gap), and a NaN gap wins the minimum as it does in np.min."""
    best = np.inf
    for h in range(human_pos.shape[1]):
        if not human_mask[i, h]:
            continue
        sx, sy = human_pos[i, h, 0] - rx, human_pos[i, h, 1] - ry
        mx, my = (human_vel[i, h, 0] - vx) * dt, (human_vel[i, h, 1] - vy) * dt
        gap = closest_gap(sx, sy, mx, my, radius[i, h])
        if gap != gap:
            return gap
        best = min(best, gap)
    return best


@kernel
def closest_gap(sx: float, sy: float, mx: float, my: float, radius: float) -> float:
    """The closest boundary distance during a step of a person at (sx, sy) from the robot at its
    start, moving (mx, my) relative to the robot through the step, m, with `radius` the two radii
    (scalar kernel): the point of the relative move nearest the robot (np.clip's NaN kept)."""
    length2 = mx * mx + my * my
    t = -(sx * mx + sy * my) / (length2 if length2 > 0 else 1.0)
    if t < 0.0:
        t = 0.0
    elif t > 1.0:
        t = 1.0
    return np.hypot(sx + t * mx, sy + t * my) - radius


@dataclass(frozen=True)
class CrowdOutcome:
    """One step's judgement for B rows.

    Attributes:
        reward: (B,) float64.
        success, collision, timeout: (B,) bool; at most one is true.
        terminated: (B,) success or collision.
        truncated: (B,) timeout.
        closest: (B,) the closest boundary distance during the step, m (inf with nobody).
        discomfort: (B,) 0 <= closest < discomfort_dist (and no collision, no end).
    """

    reward: np.ndarray
    success: np.ndarray
    collision: np.ndarray
    timeout: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    closest: np.ndarray
    discomfort: np.ndarray


def judge_step(
    closest: np.ndarray,
    goal_distance_after: np.ndarray,
    robot_radius: float,
    step_start_time: np.ndarray,
    time_limit: np.ndarray | float,
    cfg: CrowdRewardConfig,
    dt: float,
    done: np.ndarray | None = None,
) -> CrowdOutcome:
    """Judge a step in CrowdNav's order (below).

    A step is judged as CrowdNav judges it, in CrowdNav's order:
    1. time limit: a step that starts at time >= time_limit - 1 s ends the episode (truncated,
       reward 0);
    2. collision: the closest distance between the robot's and a person's boundaries while both
       move through the step (the robot at its new velocity, the person at its velocity at the
       start of the step: the relative segment against the origin) is below 0: terminated,
       `collision_penalty`;
    3. goal: the robot's position after the step is within its radius of the goal: terminated,
       `success_reward`;
    4. discomfort: closest boundary distance d below `discomfort_dist`: (d - discomfort_dist) *
       discomfort_penalty_factor * dt.
    A row whose episode had already ended (`done`) gets no reward and no flags.

    Args:
        closest: (B,) closest boundary distance during the step (track_approach).
        goal_distance_after: (B,) robot-goal distance after the step, m.
        robot_radius: m (the goal tolerance).
        step_start_time: (B,) episode time at the start of the step, s.
        time_limit: the episode's time limit, s, one for all or (B,).
        cfg: the reward.
        dt: s.
        done: (B,) bool, rows whose episode had already ended (None: none).
    """
    n = len(closest)
    limit = time_limit if isinstance(time_limit, np.ndarray) else np.full(n, float(time_limit))
    ended = np.zeros(n, dtype=bool) if done is None else done
    reward = np.empty(n)
    flags = np.empty((5, n), dtype=bool)
    success, collision, timeout, terminated, discomfort = flags[0], flags[1], flags[2], flags[3], flags[4]
    _judge(
        closest, goal_distance_after, float(robot_radius), step_start_time, limit, ended,
        cfg.collision_penalty, cfg.success_reward, cfg.discomfort_dist, cfg.discomfort_penalty_factor, dt,
        reward, flags,
    )  # fmt: skip
    return CrowdOutcome(
        reward=reward,
        success=success,
        collision=collision,
        timeout=timeout,
        terminated=terminated,
        truncated=timeout,
        closest=closest,
        discomfort=discomfort,
    )


@kernel
def _judge(
    closest, goal, radius, start, limit, done, penalty, success_reward, comfort, factor, dt, reward, flags
):
    """judge_step into reward (B,) and flags (5, B): success, collision, timeout, terminated and
    discomfort, each robot's by the numpy expressions it replaced."""
    for i in range(closest.shape[0]):
        timeout = start[i] >= limit[i] - 1.0 - 1e-9
        collision = not timeout and closest[i] < 0
        success = not timeout and not collision and goal[i] < radius
        discomfort = not (timeout or collision or success) and closest[i] < comfort
        value = 0.0
        if collision:
            value = penalty
        elif success:
            value = success_reward
        elif discomfort:
            value = (closest[i] - comfort) * factor * dt
        if done[i]:
            value, timeout, collision, success, discomfort = 0.0, False, False, False, False
        reward[i] = value
        flags[0, i], flags[1, i], flags[2, i] = success, collision, timeout
        flags[3, i], flags[4, i] = success or collision, discomfort


class CrowdNavMetrics:
    """Per-episode accumulators of B rows: CrowdNav's test metrics and ours.

    success / collision / timeout; navigation_time (s, at the end of a successful episode, as
    CrowdNav's success_times; NaN otherwise); path_length (m the robot moved); discomfort_steps
    and steps; discomfort_frequency (share of the episode's steps in discomfort, CrowdNav's
    "frequency of being in danger"); min_separation (smallest boundary distance of the episode,
    m); intrusion_ratio (share of steps with a person's boundary within discomfort_dist of the
    robot's, a collision step included: CrowdNav's danger zone on the present positions, not
    CrowdNav++'s intrusion, which tests the people's true positions over the next 5 steps);
    return and discounted_return (gamma ** (t * dt * v_pref) per step t, as CrowdNav's total
    reward); mean_force and mean_blame, the benchmark's social force and blame
    terms (SPEC section 9, socialzoo.env.reward) averaged over the episode's steps, so the task's
    policies compare with the Social Action Selection policies.
    """

    def __init__(self, batch_size: int, dt: float, preferred_speed: float, cfg: CrowdRewardConfig) -> None:
        self.dt, self.v_pref, self.cfg = dt, preferred_speed, cfg
        self.steps = np.zeros(batch_size, dtype=np.int64)
        self.path = np.zeros(batch_size)
        self.discomfort = np.zeros(batch_size, dtype=np.int64)
        self.intrusion = np.zeros(batch_size, dtype=np.int64)
        self.min_gap = np.full(batch_size, np.inf)
        self.ret = np.zeros(batch_size)
        self.discounted = np.zeros(batch_size)
        self.force = np.zeros(batch_size)
        self.blame = np.zeros(batch_size)

    def reset_rows(self, rows: np.ndarray) -> None:
        """Start new episodes in `rows`."""
        for total in (self.steps, self.path, self.discomfort, self.intrusion, self.ret, self.discounted):
            total[rows] = 0
        self.force[rows] = self.blame[rows] = 0.0
        self.min_gap[rows] = np.inf

    def update(
        self,
        outcome: CrowdOutcome,
        moved: np.ndarray,
        force: np.ndarray | None = None,
        blame: np.ndarray | None = None,
    ) -> None:
        """Add one step: its outcome, the distance (B,) each robot moved, and the step's social
        force and blame terms (B,) (0 when not given)."""
        zeros = np.zeros(len(moved))
        _count_step(
            outcome.reward, outcome.discomfort, outcome.closest, moved,
            zeros if force is None else force, zeros if blame is None else blame,
            self.cfg.gamma, self.dt, self.v_pref, self.cfg.discomfort_dist,
            self.steps, self.path, self.discomfort, self.intrusion, self.min_gap, self.ret, self.discounted,
            self.force, self.blame,
        )  # fmt: skip

    def summaries(self, rows: np.ndarray, outcome: CrowdOutcome) -> list[dict[str, float]]:
        """The ending episodes' metrics (METRIC_KEYS), one dict per row of `rows`."""
        rows = np.asarray(rows, dtype=np.intp)
        # One table of the rows' metrics, then one dict a row: per-row numpy scalars cost more than the sums.
        table = np.empty((len(rows), len(_SUMMARY_COLUMNS)))
        _summary_table(
            rows, outcome.success, outcome.collision, outcome.timeout, self.steps, self.path, self.discomfort,
            self.intrusion, self.min_gap, self.ret, self.discounted, self.force, self.blame, self.dt, table,
        )  # fmt: skip
        return [dict(zip(_SUMMARY_COLUMNS, row, strict=True)) for row in table.tolist()]


# The columns of _summary_table, in the order it writes them (METRIC_KEYS' order).
_SUMMARY_COLUMNS: tuple[str, ...] = (
    "success", "collision", "timeout", "navigation_time", "path_length", "discomfort_steps", "steps",
    "discomfort_frequency", "min_separation", "intrusion_ratio", "return", "discounted_return", "mean_force",
    "mean_blame",
)  # fmt: skip


@kernel
def _summary_table(
    rows, success, collision, timeout, steps, path, discomfort, intrusion, min_gap, ret, discounted, force, blame,
    dt, out,
):  # fmt: skip
    """CrowdNavMetrics.summaries' values of each row of `rows`, into out (rows, _SUMMARY_COLUMNS):
    flags as 0/1, navigation_time only on success (else NaN), min_separation NaN for nobody met,
    the counts and sums per step of the episode (at least 1)."""
    for j in range(rows.shape[0]):
        i = rows[j]
        per_step = max(steps[i], 1)
        out[j, 0] = 1.0 if success[i] else 0.0
        out[j, 1] = 1.0 if collision[i] else 0.0
        out[j, 2] = 1.0 if timeout[i] else 0.0
        out[j, 3] = steps[i] * dt if success[i] else np.nan
        out[j, 4] = path[i]
        out[j, 5] = discomfort[i]
        out[j, 6] = steps[i]
        out[j, 7] = discomfort[i] / per_step
        out[j, 8] = min_gap[i] if np.isfinite(min_gap[i]) else np.nan
        out[j, 9] = intrusion[i] / per_step
        out[j, 10] = ret[i]
        out[j, 11] = discounted[i]
        out[j, 12] = force[i] / per_step
        out[j, 13] = blame[i] / per_step


@kernel
def _count_step(
    reward, in_discomfort, closest, moved, force, blame, gamma, dt, v_pref, comfort,
    steps, path, discomfort, intrusion, min_gap, ret, discounted, force_sum, blame_sum,
):  # fmt: skip
    """CrowdNavMetrics.update in place, each robot's by the numpy expressions it replaced (the
    discount gamma ** (steps * dt * v_pref) before the step counts, np.minimum's NaN kept)."""
    for i in range(reward.shape[0]):
        force_sum[i] += force[i]
        blame_sum[i] += blame[i]
        discount = gamma ** (steps[i] * dt * v_pref)
        ret[i] += reward[i]
        discounted[i] += discount * reward[i]
        steps[i] += 1
        path[i] += moved[i]
        discomfort[i] += in_discomfort[i]
        intrusion[i] += closest[i] < comfort
        min_gap[i] = nan_min(min_gap[i], closest[i])
