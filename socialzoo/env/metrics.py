"""Per-episode metrics of B worlds, accumulated step by step (SPEC section 9, plus the usual
social-navigation guideline metrics), with rows reset on their own as episodes end."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from socialzoo.core.geometry import wrap_angle
from socialzoo.core.jit import kernel
from socialzoo.core.metrics import names as metric_names
from socialzoo.core.validation import check_fields, check_int

# Columns of the per-row running sums.
_SUM_COLUMNS = (
    "steps",
    "duration",
    "distance_travelled",
    "force",
    "blame",
    "reward",
    "human_collisions",
    "human_contacts",
    "wall_collisions",
    "intrusion_time",
    "rotation",
    "jerk",
)
_S = {name: i for i, name in enumerate(_SUM_COLUMNS)}


@kernel
def _accumulate(
    live, pose, speed, travelled, rotation, force, blame, reward, contacts, wall, min_dist, reached, done,
    left, halted, rerouted, dt, intrusion_distance, stuck_progress,
    sums, max_force, max_blame, min_human_distance, time_to_goal, is_reached, finished, last_pose,
    last_speed, last_accel, best_route_left, without_progress, max_without_progress,
):  # fmt: skip
    """`EpisodeMetrics.update` of every row (B,) in place, from the step's values (travelled: the
    step's length, rotation: its absolute heading change). Each value is computed as the numpy
    expressions it replaces computed it (np.where of the row's live flag, NaN-propagating
    np.maximum / np.minimum), so the sums and extremes are the same bit for bit."""
    for i in range(live.shape[0]):
        accel = (speed[i] - last_speed[i]) / dt
        best = left[i] if (rerouted[i] and live[i]) else best_route_left[i]
        progress = left[i] <= best - stuck_progress
        clock = 0.0 if progress else without_progress[i] + (0.0 if halted[i] else 1.0) * dt
        if not live[i]:
            best_route_left[i] = best
            continue
        c = contacts[i]
        row = sums[i]
        row[0] += 1.0
        row[1] += 1.0 * dt
        row[2] += travelled[i]
        row[3] += force[i]
        row[4] += blame[i]
        row[5] += reward[i]
        row[6] += 1.0 if c > 0 else 0.0
        row[7] += c
        row[8] += wall[i]
        row[9] += (1.0 if min_dist[i] < intrusion_distance else 0.0) * dt
        row[10] += rotation[i]
        row[11] += abs(accel - last_accel[i]) / dt
        best_route_left[i] = left[i] if progress else best
        without_progress[i] = clock
        max_without_progress[i] = _maximum(max_without_progress[i], clock)
        max_force[i] = _maximum(max_force[i], force[i])
        max_blame[i] = _maximum(max_blame[i], blame[i])
        min_human_distance[i] = _minimum(min_human_distance[i], min_dist[i])
        if reached[i] and not is_reached[i]:
            time_to_goal[i] = row[1]
            is_reached[i] = True
        last_pose[i, 0] = pose[i, 0]
        last_pose[i, 1] = pose[i, 1]
        last_pose[i, 2] = pose[i, 2]
        last_speed[i] = speed[i]
        last_accel[i] = accel
        if done[i]:
            finished[i] = True


@kernel
def _maximum(a, b):
    """np.maximum of two scalars (a NaN wins)."""
    return a if (a >= b or a != a) else b


@kernel
def _minimum(a, b):
    """np.minimum of two scalars (a NaN wins)."""
    return a if (a <= b or a != a) else b


# Keys of a summary, in order: the registry's metrics of this task (socialzoo.core.metrics).
SUMMARY_KEYS = metric_names("action_selection")
_BOOL_KEYS = metric_names("action_selection", kind="bool")
_INT_KEYS = metric_names("action_selection", kind="int")


@dataclass(frozen=True, kw_only=True)
class MetricsConfig:
    """Parameters of the guideline metrics.

    Attributes:
        personal_space: radius of a human's intimate zone around its body, m (Hall: 0.45).
        human_radius: body radius of a human, m.
        stuck_time: an episode is stuck after this long without progress while not halting, s.
        stuck_progress: progress is the route length left coming this far below its least
            value so far, m.
    """

    personal_space: float = 0.45
    human_radius: float = 0.2
    stuck_time: float = 10.0
    stuck_progress: float = 0.25

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("personal_space", "human_radius"))

    @property
    def intrusion_distance(self) -> float:
        """Centre distance below which the robot intrudes, m."""
        return self.personal_space + self.human_radius


class EpisodeMetrics:
    """Running metrics of the current episode of each of B rows.

    Call `reset` for rows whose episode starts, `update` once per step with the batch's
    per-step values, and `summaries` when episodes end. A row stops accumulating
    after the step flagged `done` until it is reset.

    Every distance is between centres, in metres; times are in seconds. Beyond each metric's
    description in the registry (socialzoo.core.metrics):

    - success: the env ends an episode at the goal, a wall or the time limit, so a reached goal is
      reached within the time limit.
    - time_to_goal: NaN if the goal was not reached (collisions or not; filter on success for the
      benchmark's figure).
    - personal_space_intrusion_time: the intimate zone is measured from the human's body and not
      the centre because the collision distance is already 0.4 m between centres, where a
      centre-based 0.45 m zone would only count near-hits.
    - path_irregularity: Guzzi et al. 2013, as listed by Gao and Huang 2022 and Francis et al.
      2023: "the amount of rotation that is not needed to reach the goal", in rad; Guzzi et al.
      divide it by the path length (rad/m), which distance_travelled gives.
    - stuck: the Halt action, or Follow and Pass without a target, pause the clock. Progress is
      the route length left (the distance to the global plan plus the plan's length from there to
      the goal, socialzoo.nav.navigator.Navigator.route_left; the straight distance to the goal
      where no plan is given) coming `stuck_progress` (0.25 m) below its least value so far: a
      robot pressed against a wall, turning on the spot or rocking in a doorway makes none, one
      driving a long way round along its plan does. When the navigator's recovery gives the robot
      another route, progress counts along that route from then on (the clock runs on: a robot
      that keeps recovering without getting anywhere is stuck). max_time_without_progress: the
      longest such stretch, s.

    Args:
        batch_size: B.
        config: parameters of the guideline metrics.
    """

    def __init__(self, batch_size: int, config: MetricsConfig | None = None) -> None:
        check_int("EpisodeMetrics", "batch_size", batch_size, low=1)
        self.batch_size = batch_size
        self.config = config or MetricsConfig()
        b = batch_size
        self.sums = np.zeros((b, len(_SUM_COLUMNS)))
        self.max_force = np.zeros(b)
        self.max_blame = np.zeros(b)
        self.min_human_distance = np.full(b, np.inf)
        self.time_to_goal = np.full(b, np.nan)
        self.reached = np.zeros(b, dtype=bool)
        self.finished = np.zeros(b, dtype=bool)
        self.goal = np.zeros((b, 2))
        self.last_pose = np.zeros((b, 3))
        self.last_speed = np.zeros(b)
        self.last_accel = np.zeros(b)
        self.straight_distance = np.zeros(b)
        self.needed_rotation = np.zeros(b)
        # Least route length left so far (inf before the first step), and the time since it last
        # fell by stuck_progress, counted while not halting, s.
        self.best_route_left = np.full(b, np.inf)
        self.without_progress = np.zeros(b)
        self.max_without_progress = np.zeros(b)

    def reset(
        self,
        rows: np.ndarray | slice | int | None,
        robot_pose: np.ndarray,
        goal: np.ndarray,
        robot_vel: np.ndarray | None = None,
    ) -> None:
        """Start new episodes in `rows`.

        Args:
            rows: index array, bool mask (B,), slice, int, or None for every row.
            robot_pose: (n, 3) start poses of those rows, world frame (x, y in m, heading rad).
            goal: (n, 2) goals of those rows, m, world frame.
            robot_vel: (n, 2) start velocities (v in m/s, omega in rad/s); default at rest.
        """
        r = slice(None) if rows is None else rows
        pose = np.asarray(robot_pose, dtype=np.float64)
        goal = np.asarray(goal, dtype=np.float64)
        self.sums[r] = 0.0
        self.max_force[r] = 0.0
        self.max_blame[r] = 0.0
        self.min_human_distance[r] = np.inf
        self.time_to_goal[r] = np.nan
        self.reached[r] = False
        self.finished[r] = False
        self.goal[r] = goal
        self.last_pose[r] = pose
        self.last_speed[r] = 0.0 if robot_vel is None else np.asarray(robot_vel, dtype=np.float64)[..., 0]
        self.last_accel[r] = 0.0
        to_goal = goal - pose[..., :2]
        self.straight_distance[r] = np.hypot(to_goal[..., 0], to_goal[..., 1])
        bearing = np.arctan2(to_goal[..., 1], to_goal[..., 0])
        self.needed_rotation[r] = np.abs(wrap_angle(bearing - pose[..., 2]))
        self.best_route_left[r] = np.inf
        self.without_progress[r] = 0.0
        self.max_without_progress[r] = 0.0

    def update(
        self,
        *,
        robot_pose: np.ndarray,
        robot_vel: np.ndarray,
        reward: np.ndarray,
        force: np.ndarray,
        blame: np.ndarray,
        human_collisions: np.ndarray,
        wall_collision: np.ndarray,
        min_human_distance: np.ndarray,
        reached: np.ndarray,
        done: np.ndarray,
        dt: float,
        route_left: np.ndarray | None = None,
        halted: np.ndarray | None = None,
        rerouted: np.ndarray | None = None,
    ) -> None:
        """Add one step of every row.

        Args:
            robot_pose: (B, 3) pose after the step, world frame.
            robot_vel: (B, 2) velocity after the step: v (m/s), omega (rad/s).
            reward: (B,) reward of the step.
            force: (B,) social force term of the step.
            blame: (B,) blame of the step.
            human_collisions: (B,) int, humans in collision with the robot after the step.
            wall_collision: (B,) bool, the footprint touches a wall after the step.
            min_human_distance: (B,) distance to the nearest present human, m (inf for none).
            reached: (B,) bool, the goal is reached after the step.
            done: (B,) bool, the episode ended with this step (terminated or truncated).
            dt: step duration, s. Rows that finished and were not reset are skipped.
            route_left: (B,) route length left to the goal after the step, m (default: the
                straight distance to the goal); progress for `stuck` is counted on it.
            halted: (B,) bool, the policy halted the robot this step (default: none): the
                stuck clock pauses.
            rerouted: (B,) bool, the robot took another route this step (the navigator's
                recovery): progress counts from its length left now on; the clock runs on.
        """
        live = ~self.finished
        pose = np.asarray(robot_pose, dtype=np.float64)
        step = pose[:, :2] - self.last_pose[:, :2]
        if route_left is None:
            route_left = np.hypot(*(self.goal - pose[:, :2]).T)
        none = np.zeros(self.batch_size, dtype=bool)
        # numpy's hypot and the angle wrap stay numpy's; the rest is one compiled pass.
        _accumulate(
            live,
            pose,
            np.asarray(robot_vel, dtype=np.float64)[:, 0],
            np.hypot(step[:, 0], step[:, 1]),
            np.abs(wrap_angle(pose[:, 2] - self.last_pose[:, 2])),
            np.asarray(force, dtype=np.float64),
            np.asarray(blame, dtype=np.float64),
            np.asarray(reward, dtype=np.float64),
            np.asarray(human_collisions, dtype=np.float64),
            np.asarray(wall_collision, dtype=np.float64),
            np.asarray(min_human_distance, dtype=np.float64),
            np.asarray(reached, dtype=bool),
            np.asarray(done, dtype=bool),
            np.asarray(route_left, dtype=np.float64),
            none if halted is None else np.asarray(halted, dtype=bool),
            none if rerouted is None else np.asarray(rerouted, dtype=bool),
            dt,
            self.config.intrusion_distance,
            self.config.stuck_progress,
            self.sums,
            self.max_force,
            self.max_blame,
            self.min_human_distance,
            self.time_to_goal,
            self.reached,
            self.finished,
            self.last_pose,
            self.last_speed,
            self.last_accel,
            self.best_route_left,
            self.without_progress,
            self.max_without_progress,
        )

    def arrays(self, rows: np.ndarray | slice | None = None) -> dict[str, np.ndarray]:
        """Every summary metric of `rows` (default all) as arrays, keyed as in SUMMARY_KEYS."""
        r = slice(None) if rows is None else rows
        sums = self.sums[r]
        steps = sums[:, _S["steps"]]
        per_step = np.where(steps > 0, steps, np.nan)
        human_collisions = sums[:, _S["human_collisions"]]
        wall_collisions = sums[:, _S["wall_collisions"]]
        reached = self.reached[r]
        travelled = sums[:, _S["distance_travelled"]]
        to_goal = self.goal[r] - self.last_pose[r][:, :2]
        min_dist = self.min_human_distance[r]
        return {
            "success": reached & (human_collisions == 0) & (wall_collisions == 0),
            "reached": reached.copy(),
            "time_to_goal": self.time_to_goal[r].copy(),
            "distance_from_goal": np.hypot(to_goal[:, 0], to_goal[:, 1]),
            "distance_travelled": travelled,
            "steps": steps.astype(np.int64),
            "duration": sums[:, _S["duration"]],
            "mean_force": sums[:, _S["force"]] / per_step,
            "max_force": self.max_force[r].copy(),
            "mean_blame": sums[:, _S["blame"]] / per_step,
            "max_blame": self.max_blame[r].copy(),
            "human_collisions": human_collisions.astype(np.int64),
            "human_contacts": sums[:, _S["human_contacts"]].astype(np.int64),
            "wall_collisions": wall_collisions.astype(np.int64),
            "average_step_reward": sums[:, _S["reward"]] / per_step,
            "total_reward": sums[:, _S["reward"]],
            "min_human_distance": np.where(np.isfinite(min_dist), min_dist, np.nan),
            "personal_space_intrusion_time": sums[:, _S["intrusion_time"]],
            "path_irregularity": np.maximum(sums[:, _S["rotation"]] - self.needed_rotation[r], 0.0),
            "path_length_ratio": self.straight_distance[r] / np.where(travelled > 0, travelled, np.nan),
            "jerk": sums[:, _S["jerk"]] / per_step,
            "stuck": self.max_without_progress[r] >= self.config.stuck_time - 1e-9,
            "max_time_without_progress": self.max_without_progress[r].copy(),
        }

    def summaries(self, rows: np.ndarray | list[int] | None = None) -> list[dict[str, Any]]:
        """One plain dict of Python scalars per row of `rows` (index array; default all)."""
        index = np.arange(self.batch_size) if rows is None else np.asarray(rows, dtype=np.intp).reshape(-1)
        arrays = self.arrays(index)
        kinds = {
            key: bool if key in _BOOL_KEYS else int if key in _INT_KEYS else float for key in SUMMARY_KEYS
        }
        return [{key: kind(arrays[key][i]) for key, kind in kinds.items()} for i in range(len(index))]


# The outcome of an episode: success or one failure cause, in order of precedence.
FAILURE_CAUSES = ("success", "wall_collision", "human_collision", "stuck", "timeout")


def failure_cause(metrics: Mapping[str, Any]) -> str:
    """The outcome of one episode's metrics (a summary dict): one of FAILURE_CAUSES.

    "success"; else "wall_collision" (the footprint touched a wall: the episode ended there),
    "human_collision" (at least one step in collision with a human), "stuck" (see the module
    docstring), else "timeout": the time limit ended an episode in which the robot kept making
    progress. Summaries stored before `stuck` existed count as not stuck. The `stuck` rule is
    EpisodeMetrics'.
    """
    for cause, key in zip(
        FAILURE_CAUSES, ("success", "wall_collisions", "human_collisions", "stuck"), strict=False
    ):
        if _flag(metrics.get(key)):
            return cause
    return "timeout"


def _flag(value: Any) -> bool:
    """A stored flag or count as a bool: None and NaN (a value never stored) are False."""
    return value is not None and value == value and bool(value)
