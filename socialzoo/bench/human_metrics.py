"""Per-episode metrics of the humans of B worlds (learned or social-force alike), step by step: does a learned crowd
walk its routes as the social-force crowd does, and with no more collisions?"""

from __future__ import annotations

from typing import Any

import numpy as np

from socialzoo.core.metrics import metric
from socialzoo.core.metrics import names as metric_names
from socialzoo.core.state import WorldState
from socialzoo.core.walls import WallIndex
from socialzoo.env.human_agents import CONTACT_DISTANCE

# Keys of a summary, in order (the prefix keeps them apart from the robot's metrics): the
# registry's humans' metrics (socialzoo.core.metrics).
HUMAN_METRIC_KEYS = metric_names("humans")
# A human's body radius, m: a wall closer than this to its centre touches it.
HUMAN_RADIUS = 0.2


class HumanEpisodeMetrics:
    """Running human metrics of the current episode of each of B rows.

    Every human present in the scenario counts; distances are between centres, m, and times in s (each
    metric's definition: the registry's "humans" metrics, socialzoo.core.metrics). A goal counts as
    reached within the waypoint radius, so the route's length is taken up to that circle: a human
    walking straight along a one-segment route has a path ratio of 1.

    Rows are independent: a row is reset when its episode starts and stops accumulating once its
    episode is done, so the runner reads a finished row's summary before refilling it.

    Args:
        batch_size: B.
        max_humans: H, the human slots.
        num_robots: R.
        walls: the map's wall index.
        robot_distance: human-robot centre distance counted as a collision, m.
        waypoint_radius: the distance within which a waypoint counts as reached, m
            (HumanConfig.waypoint_radius); the route length of the path ratio stops there.
    """

    def __init__(
        self,
        batch_size: int,
        max_humans: int,
        num_robots: int,
        walls: WallIndex,
        robot_distance: float,
        waypoint_radius: float = 0.0,
    ) -> None:
        self.walls = walls
        self.robot_distance = float(robot_distance)
        self.waypoint_radius = float(waypoint_radius)
        b, h, r = batch_size, max_humans, num_robots
        self.present = np.zeros((b, h), dtype=bool)
        self.route_length = np.zeros((b, h))
        self.walked = np.zeros((b, h))
        self.walked_to_goal = np.full((b, h), np.nan)
        self.waypoints = np.zeros((b, h))
        self.speed_sum = np.zeros(b)
        self.steps = np.zeros(b)
        self.hh = np.zeros(b, dtype=np.int64)
        self.hw = np.zeros(b, dtype=np.int64)
        self.hr = np.zeros(b, dtype=np.int64)
        self.min_human = np.full(b, np.inf)
        self.min_wall = np.full(b, np.inf)
        self.min_robot = np.full(b, np.inf)
        self.touch_hh = np.zeros((b, h, h), dtype=bool)
        self.touch_hw = np.zeros((b, h), dtype=bool)
        self.touch_hr = np.zeros((b, h, r), dtype=bool)
        self.active = np.zeros(b, dtype=bool)
        self.dt = 0.0

    def reset(self, rows: np.ndarray, state: WorldState) -> None:
        """Start the episodes of `rows` from `state` (the core's state right after its reset)."""
        rows = np.asarray(rows, dtype=np.intp)
        self.present[rows] = state.human_mask[rows]
        self.route_length[rows] = _route_lengths(state, rows, self.waypoint_radius)
        for name in ("walked", "waypoints", "speed_sum", "steps", "hh", "hw", "hr"):
            getattr(self, name)[rows] = 0
        self.walked_to_goal[rows] = np.nan
        for name in ("min_human", "min_wall", "min_robot"):
            getattr(self, name)[rows] = np.inf
        for touch in (self.touch_hh, self.touch_hw, self.touch_hr):
            touch[rows] = False
        self.active[rows] = True
        self._measure(state, rows, count=False)

    def update(
        self, before: WorldState, after: WorldState, blocked: np.ndarray, dt: float, done: np.ndarray
    ) -> None:
        """Add one step of every active row; rows flagged `done` (B,) stop after it."""
        rows = np.flatnonzero(self.active)
        if len(rows) == 0:
            return
        self.dt = dt
        mask = self.present[rows]
        step = np.linalg.norm(after.human_pos[rows] - before.human_pos[rows], axis=-1)
        self.walked[rows] += np.where(mask, step, 0.0)
        self.waypoints[rows] += (after.human_waypoint[rows] != before.human_waypoint[rows]) & mask
        turned = (before.human_direction[rows] > 0) & (after.human_direction[rows] < 0) & mask
        first = turned & np.isnan(self.walked_to_goal[rows])
        self.walked_to_goal[rows] = np.where(first, self.walked[rows], self.walked_to_goal[rows])
        speed = np.linalg.norm(after.human_vel[rows], axis=-1)
        count = np.maximum(mask.sum(-1), 1)
        self.speed_sum[rows] += np.where(mask, speed, 0.0).sum(-1) / count
        self.steps[rows] += 1
        self._measure(after, rows, count=True, blocked=blocked[rows])
        self.active[rows] &= ~np.asarray(done, dtype=bool)[rows]

    def _measure(
        self, state: WorldState, rows: np.ndarray, count: bool, blocked: np.ndarray | None = None
    ) -> None:
        """Distances and contacts of `rows` in `state`; new contacts are counted when `count`."""
        mask = self.present[rows]
        pos = state.human_pos[rows]
        h = pos.shape[1]
        pair = mask[:, :, None] & mask[:, None, :] & np.triu(np.ones((h, h), dtype=bool), 1)
        d_hh = np.sqrt(((pos[:, :, None, :] - pos[:, None, :, :]) ** 2).sum(-1))
        d_hh = np.where(pair, d_hh, np.inf)
        _, d_hw = self.walls.nearest(pos)
        d_hw = np.where(mask, d_hw, np.inf)
        robots = state.robot_pose[rows, :, :2]
        d_hr = np.sqrt(((pos[:, :, None, :] - robots[:, None, :, :]) ** 2).sum(-1))
        d_hr = np.where(mask[..., None], d_hr, np.inf)
        self.min_human[rows] = np.minimum(self.min_human[rows], d_hh.min(axis=(1, 2), initial=np.inf))
        self.min_wall[rows] = np.minimum(self.min_wall[rows], d_hw.min(axis=1, initial=np.inf))
        self.min_robot[rows] = np.minimum(self.min_robot[rows], d_hr.min(axis=(1, 2), initial=np.inf))
        touch_hh = d_hh < CONTACT_DISTANCE
        touch_hw = d_hw < HUMAN_RADIUS
        if blocked is not None:
            touch_hw |= blocked & mask
        touch_hr = d_hr < self.robot_distance
        if count:
            self.hh[rows] += (touch_hh & ~self.touch_hh[rows]).sum(axis=(1, 2))
            self.hw[rows] += (touch_hw & ~self.touch_hw[rows]).sum(axis=1)
            self.hr[rows] += (touch_hr & ~self.touch_hr[rows]).sum(axis=(1, 2))
        self.touch_hh[rows] = touch_hh
        self.touch_hw[rows] = touch_hw
        self.touch_hr[rows] = touch_hr

    def rows(self, index: np.ndarray | list[int]) -> HumanEpisodeMetrics:
        """A tracker of the rows `index` (copies), for a core compacted to those rows."""
        index = np.asarray(index, dtype=np.intp)
        new = HumanEpisodeMetrics(
            len(index),
            self.present.shape[1],
            self.touch_hr.shape[2],
            self.walls,
            self.robot_distance,
            self.waypoint_radius,
        )
        for name, value in vars(self).items():
            if isinstance(value, np.ndarray):
                setattr(new, name, value[index].copy())
        new.dt = self.dt
        return new

    def summaries(self, rows: np.ndarray | list[int]) -> list[dict[str, Any]]:
        """The metrics of `rows`' episodes (keys HUMAN_METRIC_KEYS, plain Python values)."""
        out = []
        for row in np.asarray(rows, dtype=np.intp).tolist():
            mask = self.present[row]
            routes = mask & (self.route_length[row] > 0)
            reached = ~np.isnan(self.walked_to_goal[row]) & routes
            minutes = self.steps[row] * self.dt / 60.0 * max(int(mask.sum()), 1)
            ratio = self.walked_to_goal[row][reached] / self.route_length[row][reached]
            values = {
                "humans_goal_rate": float(reached.sum() / routes.sum()) if routes.any() else float("nan"),
                "humans_waypoints_per_min": float(self.waypoints[row][mask].sum() / minutes)
                if minutes > 0
                else float("nan"),
                "humans_hh_collisions": int(self.hh[row]),
                "humans_hw_collisions": int(self.hw[row]),
                "humans_hr_collisions": int(self.hr[row]),
                "humans_min_human_distance": _finite(self.min_human[row]),
                "humans_min_wall_distance": _finite(self.min_wall[row]),
                "humans_min_robot_distance": _finite(self.min_robot[row]),
                "humans_mean_speed": float(self.speed_sum[row] / self.steps[row])
                if self.steps[row]
                else float("nan"),
                "humans_path_ratio": float(ratio.mean()) if len(ratio) else float("nan"),
            }
            out.append(values)
        return out


def _finite(value: float) -> float:
    return float(value) if np.isfinite(value) else float("nan")


def _route_lengths(state: WorldState, rows: np.ndarray, radius: float) -> np.ndarray:
    """(len(rows), H) length from the spawn through the route's waypoints to the circle of
    `radius` around its goal end, m; 0 for routes of one waypoint (no goal to walk to)."""
    route = state.human_route[rows]
    seg = np.linalg.norm(np.diff(route, axis=2), axis=-1)  # padded repeats add 0
    index = np.arange(route.shape[2] - 1)
    first = state.human_waypoint[rows]
    # From the spawn to its first waypoint, then along the route from there on.
    along = np.where(index[None, None, :] >= first[..., None], seg, 0.0).sum(-1)
    target = np.take_along_axis(route, first[..., None, None].repeat(2, axis=-1), axis=2)[:, :, 0]
    to_first = np.linalg.norm(target - state.human_pos[rows], axis=-1)
    length = np.maximum(to_first + along - radius, 0.0)
    return np.where((state.human_route_len[rows] > 1) & (length > 0), length, 0.0)


# ---------------------------------------------------------------------------- tables
# Descriptions of the metrics in the tables (with their units), their digits, and the counts
# whose means get a bootstrap interval: from the metric registry.
HUMAN_METRIC_LABELS: dict[str, tuple[str, int]] = {
    key: (metric(key).heading, metric(key).digits) for key in HUMAN_METRIC_KEYS
}
_COUNT_KEYS = tuple(key for key in HUMAN_METRIC_KEYS if metric(key).count)


def summarize_humans(
    rows: list[dict[str, Any]],
    *,
    policies: tuple[str, ...] | list[str],
    maps: list[str],
    confidence: float = 0.9,
) -> list[dict[str, Any]]:
    """One entry per (policy, map): the mean of every human metric over the trials with a 90%
    interval (bootstrap for the collision counts, Student-t otherwise).

    Args:
        rows: trial dicts (ResultsStore.rows) holding the HUMAN_METRIC_KEYS.
        policies: the order of the policies.
        maps: the order of the maps.
        confidence: two-sided level.
    """
    from socialzoo.bench.aggregates import cell_generator
    from socialzoo.bench.stats import count_interval, mean_interval
    from socialzoo.bench.tables import ordered_groups

    out = []
    for policy, map_name, group in ordered_groups(rows, policies, maps):
        entry: dict[str, Any] = {"policy": policy, "map": map_name, "trials": len(group)}
        for key in HUMAN_METRIC_KEYS:
            values = np.array([np.nan if r.get(key) is None else float(r[key]) for r in group])
            if key in _COUNT_KEYS:
                ci = count_interval(values, confidence, rng=cell_generator(0, policy, map_name, key))
            else:
                ci = mean_interval(values, confidence)
            entry |= ci.entry(key)
        out.append(entry)
    return out


def write_humans_tables(summary: list[dict[str, Any]], out_dir: Any, *, title: str) -> list[Any]:
    """humans.csv (every column) and humans.md (a table per map, metrics as rows) in out_dir."""
    from pathlib import Path

    from socialzoo.bench.tables import interval_text, markdown_table, write_csv
    from socialzoo.core.files import write_text_atomic

    out = Path(out_dir)
    columns = ["policy", "map", "trials"] + [
        f"{k}_{s}" for k in HUMAN_METRIC_KEYS for s in ("mean", "ci_low", "ci_high")
    ]
    files = [write_csv(summary, out / "humans.csv", columns, blank_nan=False, lineterminator="\n")]
    lines = [f"# {title}", "", "Means over trials with 90% intervals (bootstrap for collision counts).", ""]
    for map_name in dict.fromkeys(e["map"] for e in summary):
        entries = [e for e in summary if e["map"] == map_name]
        header = ["metric", *(f"{e['policy']} ({e['trials']})" for e in entries)]
        cells = [
            [
                label,
                *(interval_text(e, key, digits) if np.isfinite(e[f"{key}_mean"]) else "-" for e in entries),
            ]
            for key, (label, digits) in HUMAN_METRIC_LABELS.items()
        ]
        lines += [f"## {map_name}", "", *markdown_table(header, cells), ""]
    files.append(write_text_atomic(out / "humans.md", "\n".join(lines)))
    return files
