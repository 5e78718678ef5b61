"""Recovery of robots that make no progress along their plans: when, how they back off, which edge
they avoid afterwards."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.core.validation import check_fields
from socialzoo.nav.distance_field import DistanceField


@dataclass(frozen=True, kw_only=True)
class RecoveryConfig:
    """How a robot that makes no progress recovers (see `RecoveryState`).

    Attributes:
        after: a robot driving its plan (GoAlone, not halted) that goes this long without
            progress recovers, s. Progress: its route length left
            (socialzoo.nav.navigator.Navigator.route_left) coming `progress` below its least value
            since the episode's start or its last recovery.
        progress: m.
        backoff_time: the robot backs off for this long, s.
        backoff_speed: straight backwards at this speed, m/s, where the line behind it keeps
            its wall distance and no human is within `human_gap` of it; else it stands.
        human_gap: m.
        crowd_radius: when a human is this close as the robot starts to recover, people block
            it, not the building: it replans as usual; otherwise it replans avoiding the graph
            edge where it stopped (at most `max_avoided` edges per episode, then none), m.
        max_avoided: edges a robot avoids at most in one episode.
    """

    after: float = 3.0
    progress: float = 0.25
    backoff_time: float = 1.0
    backoff_speed: float = 0.3
    human_gap: float = 0.6
    crowd_radius: float = 1.5
    max_avoided: int = 4

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("backoff_speed", "max_avoided"))


def backoff_commands(
    pose: np.ndarray,
    field: DistanceField,
    need: float,
    cfg: RecoveryConfig,
    human_pos: np.ndarray,
    human_mask: np.ndarray,
) -> np.ndarray:
    """(N, 2) commands (v, omega) of backing-off robots: straight backwards at cfg.backoff_speed
    where the line behind the robot (as long as the back-off drives) keeps min(need, the robot's
    own wall distance) from walls and cfg.human_gap from every present human; else standing.

    Args:
        pose: (N, 3) robot poses x, y (m), theta (rad), world frame.
        field: the map's wall distance field.
        need: the wall distance wanted, m (the local planner's wall distance).
        cfg: the recovery settings.
        human_pos: (N, H, 2) human positions, world frame, m.
        human_mask: (N, H) present humans.
    """
    n = len(pose)
    out = np.zeros((n, 2))
    if n == 0 or cfg.backoff_speed <= 0.0:
        return out
    reach = cfg.backoff_speed * cfg.backoff_time
    dist = np.arange(1, max(1, math.ceil(reach / 0.05)) + 1) * min(0.05, reach)  # (M,)
    back = -np.stack((np.cos(pose[:, 2]), np.sin(pose[:, 2])), axis=-1)  # (N, 2)
    points = pose[:, None, :2] + dist[None, :, None] * back[:, None, :]  # (N, M, 2)
    here = field.lookup(pose[:, :2])
    clear = (field.lookup(points) >= np.minimum(need, here)[:, None] - 1e-3).all(axis=1)
    if human_pos.shape[1]:
        gap = np.sqrt(((points[:, :, None, :] - human_pos[:, None, :, :]) ** 2).sum(-1))  # (N, M, H)
        clear &= ~((gap < cfg.human_gap) & human_mask[:, None, :]).any(axis=(1, 2))
    out[:, 0] = np.where(clear, -cfg.backoff_speed, 0.0)
    return out


@kernel
def _recovery_step(
    left, moving, dt, progress, after, backoff_time, best_left, idle, backoff_left, recoveries, started, ended,
):  # fmt: skip
    """`RecoveryState.step` of every robot (B, R) in place; the numpy expressions it replaces,
    value for value (np.maximum's NaN included)."""
    for b in range(left.shape[0]):
        for r in range(left.shape[1]):
            best = best_left[b, r]
            gained = left[b, r] <= best - progress
            if gained or not math.isfinite(best):
                best = left[b, r]
            count = 0.0 if gained else idle[b, r] + (dt if moving[b, r] else 0.0)
            was = backoff_left[b, r] > 0.0
            rest = backoff_left[b, r] - dt
            rest = rest if (rest >= 0.0 or rest != rest) else 0.0
            end = was and rest <= 0.0
            start = moving[b, r] and not was and count >= after
            if start:
                rest = backoff_time
                recoveries[b, r] += 1
            if start or end:  # a recovery starts the count afresh: a detour is longer
                count = 0.0
                best = math.inf
            best_left[b, r] = best
            idle[b, r] = count
            backoff_left[b, r] = rest
            started[b, r] = start
            ended[b, r] = end


class RecoveryState:
    """Per-robot recovery bookkeeping of a batch: progress, back-offs, avoided graph edges.

    A robot wedged beside a door, in a crack of the plan, or pressed against a person drives its plan
    without getting closer to its goal. This notices (no progress for `RecoveryConfig.after`
    seconds), starts a back-off (the caller drives it with `backoff_commands`), and when the back-off
    ends says which robots need a new plan; unless people stood around it, the graph edge where the
    robot stopped is avoided for the rest of the episode. The Navigator (socialzoo.nav.navigator)
    owns one and does the replanning.

    Args:
        cfg: the recovery settings.
        batch_size: B.
        num_robots: R robots per batch row.
    """

    def __init__(self, cfg: RecoveryConfig, batch_size: int, num_robots: int) -> None:
        self.cfg = cfg
        b, r = batch_size, num_robots
        # Per robot: least route left since the last recovery (m), time without progress (s),
        # back-off time left (s), recoveries this episode, avoided edges (-1: none).
        self.best_left = np.full((b, r), np.inf)
        self.idle = np.zeros((b, r))
        self.backoff_left = np.zeros((b, r))
        self.recoveries = np.zeros((b, r), dtype=np.int64)
        self.avoid = np.full((b, r, max(1, cfg.max_avoided)), -1, dtype=np.int64)

    def reset(self, rows: np.ndarray) -> None:
        """Forget everything of batch rows (a new episode)."""
        self.best_left[rows] = np.inf
        self.idle[rows] = 0.0
        self.backoff_left[rows] = 0.0
        self.recoveries[rows] = 0
        self.avoid[rows] = -1

    @property
    def backing_off(self) -> np.ndarray:
        """(B, R) bool: robots backing off."""
        return self.backoff_left > 0.0

    def step(
        self,
        left: np.ndarray,
        moving: np.ndarray,
        dt: float,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Progress bookkeeping on the route left; start and end back-offs.

        Args:
            left: (B, R) route length left, m.
            moving: (B, R) bool, robots that drove their plan this step.
            dt: the step, s.

        Returns:
            (started, ended): (B, R) bool, robots whose back-off starts this step (the caller
            marks the edge they stand on with `avoid_edge_at` unless `in_crowd`) and robots whose
            back-off ended (they need a new plan).
        """
        cfg = self.cfg
        started = np.empty(self.idle.shape, dtype=bool)
        ended = np.empty(self.idle.shape, dtype=bool)
        _recovery_step(
            np.asarray(left, dtype=np.float64), np.asarray(moving, dtype=bool), dt, cfg.progress,
            cfg.after - 1e-9, cfg.backoff_time, self.best_left, self.idle, self.backoff_left,
            self.recoveries, started, ended,
        )  # fmt: skip
        return started, ended

    def in_crowd(
        self, pos: np.ndarray, human_pos: np.ndarray | None, human_mask: np.ndarray | None
    ) -> np.ndarray:
        """(M,) bool: a present human within cfg.crowd_radius of pos (M, 2), given the humans of
        the same rows, human_pos (M, H, 2) and human_mask (M, H); people, not the building, block
        such a robot."""
        if human_pos is None or human_mask is None or human_pos.shape[1] == 0:
            return np.zeros(len(pos), dtype=bool)
        gap = np.hypot(*(human_pos - pos[:, None, :]).transpose(2, 0, 1))
        return np.asarray((np.where(human_mask, gap, np.inf) < self.cfg.crowd_radius).any(axis=1))

    def avoid_edge_at(
        self, nodes: np.ndarray, edges: np.ndarray, row: int, robot: int, pos: np.ndarray
    ) -> None:
        """Add the graph edge (edges (E, 2) into nodes (N, 2)) nearest to pos (within 1 m) to the
        robot's avoided edges, while it has room for one."""
        avoided = self.avoid[row, robot]
        slots = np.flatnonzero(avoided < 0)
        if len(edges) == 0 or len(slots) == 0:
            return
        a, b = nodes[edges[:, 0]], nodes[edges[:, 1]]
        ab = b - a
        t = np.clip(((pos - a) * ab).sum(-1) / np.maximum((ab**2).sum(-1), 1e-12), 0.0, 1.0)
        gap = np.hypot(*(a + t[:, None] * ab - pos).T)
        gap[avoided[avoided >= 0]] = np.inf
        edge = int(np.argmin(gap))
        if gap[edge] <= 1.0:
            avoided[slots[0]] = edge
