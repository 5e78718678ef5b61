"""The episode viewer's data: a recorded episode as arrays (EpisodeTrace), the scene it plays in
(ReplayScene), and their compact JSON form that the HTML viewer reads."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from socialzoo.core.metrics import added_names, metric, registered
from socialzoo.core.validation import check_fields, check_int
from socialzoo.nav.subpolicies import ACTION_NAMES

REPLAY_FORMAT = "socialzoo-replay/1"

# Sub-policy colours of the timeline, in ACTION_NAMES order (GoAlone, Halt, Follow, Pass).
ACTION_COLORS = ("#3a9d5d", "#d6404e", "#3f78d0", "#a25ad0")
NO_ACTION_COLOR = "#9a9a9a"
# The time between the states a page keeps by default, s (Encoding.stride None).
FRAME_SECONDS = 0.05
# The metrics the viewer's table shows under a panel, in order, where the episode has them (the
# action-selection task's and the CrowdNav task's); their labels, units and digits come from the
# metric registry (socialzoo.core.metrics).
VIEWER_METRICS = registered(
    "success",
    "collision",
    "time_to_goal",
    "navigation_time",
    "human_collisions",
    "wall_collisions",
    "mean_force",
    "mean_blame",
    "total_reward",
    "return",
    "min_human_distance",
    "min_separation",
    "distance_travelled",
    "path_length",
    "path_length_ratio",
)


def _array(value: Any, dtype: type, shape: tuple[int | None, ...], what: str) -> np.ndarray:
    """`value` as a read-only array of `dtype`, checked against `shape` (None = any length)."""
    arr: np.ndarray = np.array(value, dtype=dtype)
    if arr.size == 0 and len(shape) > 1 and arr.ndim != len(shape):
        arr = arr.reshape((0, *(s or 0 for s in shape[1:])))
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape, strict=True)):
        want = str(tuple("*" if s is None else s for s in shape)).replace("'", "")  # (*, 2), (3,)
        raise ValueError(f"EpisodeTrace.{what} must have shape {want}, got {arr.shape}")
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, kw_only=True, eq=False)
class EpisodeTrace:
    """One episode of one policy, step by step, as the viewer plays it (robot 0 of the world).

    States are indexed 0..T (state 0 before the first step, state t after step t); per-step
    values 0..T-1 (value k belongs to the step from state k to state k+1). Positions are in the
    world frame, metres; headings in radians; velocities in m/s.

    Attributes:
        label: the panel's title, e.g. the policy's name.
        dt: duration of a step, s.
        robot_pose: (T+1, 3) x, y, heading.
        robot_vel: (T+1, 2) linear speed v (m/s), angular speed omega (rad/s).
        goal: (3,) goal pose.
        human_pos: (T+1, H, 2) the H humans present in the scenario.
        human_vel: (T+1, H, 2) their velocities.
        human_present: (T+1, H) bool, whether each human is in the scene in each state (people
            of a recorded scene enter and leave); None: all of them in every state.
        other_robots: (T+1, K, 3) x, y, heading of the world's other robots (robots 1..K of a
            multi-robot task); None: none.
        carrot: (T+1, 2) the local target on the global plan.
        plans: the distinct global plans of the episode, each (L, 2) waypoints.
        plan_index: (T+1,) int, which of `plans` the robot follows in each state.
        laser_angles: (M,) ray angles relative to the heading, rad.
        laser_steps: (K,) the states that were scanned, increasing from 0 (scanning is the costly
            part of recording, so a recorder may scan only the states a file keeps).
        laser_ranges: (K, M) ranges of the robot's scan in those states, m.
        laser_max_range: the scan's range, m (rays at this range hit nothing).
        action: (T,) int action chosen at each step (an index into the scene's action_names: the
            sub-policies of the action-selection task), -1 for actions without a name (velocities).
        target_human: (T,) int index into the H humans of the human followed or passed, -1 none.
        reward: (T,) reward of each step.
        force: (T,) social force term of each step, in [0, 1].
        blame: (T,) blame of each step, in [0, 1].
        human_collisions: (T,) int humans in collision after each step.
        wall_collision: (T,) bool footprint touching a wall after each step.
        metrics: the episode's metrics (socialzoo.env.metrics.SUMMARY_KEYS).
        outcome: one word for the end: "success", "collision", "timeout", ... (free text).
    """

    label: str
    dt: float
    robot_pose: np.ndarray
    robot_vel: np.ndarray
    goal: np.ndarray
    human_pos: np.ndarray
    human_vel: np.ndarray
    human_present: np.ndarray | None = None
    other_robots: np.ndarray | None = None
    carrot: np.ndarray
    plans: tuple[np.ndarray, ...]
    plan_index: np.ndarray
    laser_angles: np.ndarray
    laser_steps: np.ndarray
    laser_ranges: np.ndarray
    laser_max_range: float
    action: np.ndarray
    target_human: np.ndarray
    reward: np.ndarray
    force: np.ndarray
    blame: np.ndarray
    human_collisions: np.ndarray
    wall_collision: np.ndarray
    metrics: Mapping[str, Any] = field(default_factory=dict)
    outcome: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.label, str):
            raise ValueError(f"EpisodeTrace.label must be a string, got {self.label!r}")
        check_fields(self)  # dt and laser_max_range: finite and > 0
        pose = _array(self.robot_pose, np.float64, (None, 3), "robot_pose")
        states = len(pose)
        if states < 1:
            raise ValueError("EpisodeTrace.robot_pose must hold at least the start state")
        steps = states - 1
        humans = np.asarray(self.human_pos).shape[1] if np.ndim(self.human_pos) == 3 else 0
        rays = np.asarray(self.laser_angles).reshape(-1).shape[0]
        set_ = object.__setattr__
        set_(self, "robot_pose", pose)
        set_(self, "robot_vel", _array(self.robot_vel, np.float64, (states, 2), "robot_vel"))
        set_(self, "goal", _array(self.goal, np.float64, (3,), "goal"))
        set_(self, "human_pos", _array(self.human_pos, np.float64, (states, humans, 2), "human_pos"))
        set_(self, "human_vel", _array(self.human_vel, np.float64, (states, humans, 2), "human_vel"))
        present = np.ones((states, humans), bool) if self.human_present is None else self.human_present
        set_(self, "human_present", _array(present, bool, (states, humans), "human_present"))
        others = np.zeros((states, 0, 3)) if self.other_robots is None else self.other_robots
        set_(self, "other_robots", _array(others, np.float64, (states, None, 3), "other_robots"))
        set_(self, "carrot", _array(self.carrot, np.float64, (states, 2), "carrot"))
        plans = tuple(_array(p, np.float64, (None, 2), f"plans[{i}]") for i, p in enumerate(self.plans))
        set_(self, "plans", plans)
        index = _array(self.plan_index, np.int64, (states,), "plan_index")
        if len(index) and (index.min() < 0 or index.max() >= max(len(plans), 1) or not plans):
            raise ValueError(
                f"EpisodeTrace.plan_index must index the {len(plans)} plans, got values "
                f"{int(index.min())}..{int(index.max())}"
            )
        set_(self, "plan_index", index)
        set_(self, "laser_angles", _array(self.laser_angles, np.float64, (rays,), "laser_angles"))
        scanned = _array(self.laser_steps, np.int64, (None,), "laser_steps")
        if len(scanned) == 0 or scanned[0] != 0 or scanned[-1] > steps or np.any(np.diff(scanned) <= 0):
            raise ValueError(
                f"EpisodeTrace.laser_steps must increase from 0 to at most {steps}, got {scanned.tolist()[:8]}"
            )
        set_(self, "laser_steps", scanned)
        ranges = _array(self.laser_ranges, np.float64, (len(scanned), rays), "laser_ranges")
        set_(self, "laser_ranges", ranges)
        action = _array(self.action, np.int64, (steps,), "action")
        if len(action) and action.min() < -1:
            raise ValueError(
                f"EpisodeTrace.action values must be -1 or action indices, got {int(action.min())}"
            )
        set_(self, "action", action)
        target = _array(self.target_human, np.int64, (steps,), "target_human")
        if len(target) and (target.min() < -1 or target.max() >= humans):
            raise ValueError(
                f"EpisodeTrace.target_human values must be -1 or human indices 0..{humans - 1}, "
                f"got {int(target.min())}..{int(target.max())}"
            )
        set_(self, "target_human", target)
        for name in ("reward", "force", "blame"):
            set_(self, name, _array(getattr(self, name), np.float64, (steps,), name))
        set_(self, "human_collisions", _array(self.human_collisions, np.int64, (steps,), "human_collisions"))
        set_(self, "wall_collision", _array(self.wall_collision, bool, (steps,), "wall_collision"))
        set_(self, "metrics", dict(self.metrics))

    @property
    def num_steps(self) -> int:
        """T, the steps taken."""
        return len(self.robot_pose) - 1

    @property
    def num_humans(self) -> int:
        """H, the humans present."""
        return self.human_pos.shape[1]


@dataclass(frozen=True, kw_only=True, eq=False)
class ReplayScene:
    """What every panel of a replay shares: the map, the bodies' sizes and the title.

    Attributes:
        title: the page's title line.
        map_name: the map's name.
        walls: (W, 4) wall segments x1, y1, x2, y2, m.
        bounds: (xmin, ymin, xmax, ymax) of the map view, m.
        robot_length: footprint length along the heading, m.
        robot_width: footprint width, m.
        human_radius: radius of a human's disc, m.
        goal_radius: success distance to the goal, m.
        subtitle: a second line (scenario, seed, env config), may be empty.
        action_names: the names of the task's discrete actions, drawn on the action timeline and
            in the legend (the sub-policies by default; empty for a velocity task: no legend).
        robot_radius: a round robot's radius, m (drawn as the square of its diameter, the
            footprint above); None: a box footprint. The episode log of a trace takes it as the
            robot's disc (socialzoo.bench.episode_log.trace_episode_log).
    """

    title: str
    map_name: str
    walls: np.ndarray
    bounds: tuple[float, float, float, float]
    robot_length: float
    robot_width: float
    human_radius: float
    goal_radius: float
    subtitle: str = ""
    action_names: tuple[str, ...] = ACTION_NAMES
    robot_radius: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "action_names", tuple(str(n) for n in self.action_names))
        walls = (
            np.array(self.walls, dtype=np.float64).reshape(-1, 4) if np.size(self.walls) else np.zeros((0, 4))
        )
        if not np.isfinite(walls).all():
            raise ValueError("ReplayScene.walls must be finite")
        walls.flags.writeable = False
        object.__setattr__(self, "walls", walls)
        bounds = tuple(float(v) for v in self.bounds)
        if (
            len(bounds) != 4
            or not all(map(math.isfinite, bounds))
            or bounds[0] >= bounds[2]
            or bounds[1] >= bounds[3]
        ):
            raise ValueError(
                f"ReplayScene.bounds must be finite (xmin, ymin, xmax, ymax), got {self.bounds!r}"
            )
        object.__setattr__(self, "bounds", bounds)
        check_fields(self)  # the bodies' sizes and the goal radius: finite and > 0


@dataclass(frozen=True, kw_only=True)
class Encoding:
    """How an episode is written into the file: what is kept, and to how many decimals.

    Attributes:
        stride: keep one state every `stride` steps (and always the last state); None: the steps
            of FRAME_SECONDS in the episode's own step (`default_stride`).
        laser_rays: keep at most this many evenly spaced laser rays (0 drops the scan).
        position_decimals: decimals of positions, headings and lengths (3: millimetres).
        velocity_decimals: decimals of velocities and laser ranges.
        value_decimals: decimals of rewards, forces and blames.
    """

    stride: int | None = None
    laser_rays: int = 60
    position_decimals: int = 3
    velocity_decimals: int = 2
    value_decimals: int = 4

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.name != "stride" or self.stride is not None:
                check_int("Encoding", f.name, getattr(self, f.name), low=1 if f.name == "stride" else 0)


def default_stride(dt: float) -> int:
    """Steps between the states a page keeps by default: those of FRAME_SECONDS, at least 1 (2 of
    the action-selection task's 25 ms steps; every one of the CrowdNav task's 0.25 s steps)."""
    return max(1, round(FRAME_SECONDS / dt))


def frame_steps(num_steps: int, stride: int) -> np.ndarray:
    """(F,) the states kept: 0, stride, 2 stride, ... and always the last one, num_steps."""
    steps = np.arange(0, num_steps + 1, stride)
    if steps[-1] != num_steps:
        steps = np.append(steps, num_steps)
    return steps


def _flat(values: np.ndarray, decimals: int) -> list[Any]:
    """Rounded values as one flat list of JSON numbers (integers where the rounding gives one)."""
    rounded = np.round(np.asarray(values, dtype=np.float64).reshape(-1), decimals)
    if decimals == 0:
        return [int(v) for v in rounded.tolist()]
    return [int(v) if v.is_integer() else v for v in rounded.tolist()]


def _json_value(value: Any) -> Any:
    """A metric as a JSON value: NaN and infinities become None."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return str(value)


def encode_episode(trace: EpisodeTrace, encoding: Encoding | None = None) -> dict[str, Any]:
    """The JSON object of one episode (see socialzoo/render/viewer/replay.js for the reader).

    States are kept every `encoding.stride` steps (by default those of 50 ms); per-step series
    (actions, rewards, forces, blames) are kept at every step.
    """
    enc = encoding or Encoding()
    kept = frame_steps(trace.num_steps, enc.stride or default_stride(trace.dt))
    pd, vd = enc.position_decimals, enc.velocity_decimals
    rays = len(trace.laser_angles)
    if enc.laser_rays and rays:
        ray_index = np.unique(np.linspace(0, rays - 1, min(rays, enc.laser_rays)).round().astype(int))
    else:
        ray_index = np.zeros(0, dtype=int)
    # Both are arrays once the trace is built (None at construction stands for "nobody").
    assert trace.human_present is not None and trace.other_robots is not None
    # The latest scan at or before each kept state.
    scan = np.searchsorted(trace.laser_steps, kept, side="right") - 1
    present = trace.human_present[kept]
    return {
        "label": trace.label,
        "outcome": trace.outcome,
        "metrics": {k: _json_value(v) for k, v in trace.metrics.items()},
        "dt": trace.dt,
        "steps": trace.num_steps,
        "frameSteps": kept.tolist(),
        "robot": _flat(trace.robot_pose[kept], pd),
        "robotVel": _flat(trace.robot_vel[kept], vd),
        "goal": _flat(trace.goal, pd),
        "humans": trace.num_humans,
        # An absent person's values are whatever its slot holds (maybe NaN): written as 0.
        "humanPos": _flat(np.where(present[..., None], trace.human_pos[kept], 0.0), pd),
        "humanVel": _flat(np.where(present[..., None], trace.human_vel[kept], 0.0), vd),
        # Only where someone is absent in a kept state (people who enter or leave the scene).
        **({} if present.all() else {"humanPresent": present.astype(int).reshape(-1).tolist()}),
        "carrot": _flat(trace.carrot[kept], pd),
        # Only where the world has other robots: K poses per kept state.
        **({"others": _flat(trace.other_robots[kept], pd)} if trace.other_robots.shape[1] else {}),
        "plans": [_flat(p, pd) for p in trace.plans],
        "planIndex": trace.plan_index[kept].tolist(),
        "laser": {
            "angles": _flat(trace.laser_angles[ray_index], 4),
            "maxRange": float(trace.laser_max_range),
            "ranges": _flat(trace.laser_ranges[scan][:, ray_index], vd),
        },
        "action": trace.action.tolist(),
        "target": trace.target_human.tolist(),
        "reward": _flat(trace.reward, enc.value_decimals),
        "force": _flat(trace.force, enc.value_decimals),
        "blame": _flat(trace.blame, enc.value_decimals),
        "collisions": trace.human_collisions.tolist(),
        "wall": trace.wall_collision.astype(int).tolist(),
    }


def metric_rows(names: Sequence[str] | None = None) -> list[list[Any]]:
    """The viewer's metric table: [name, heading, digits, kind] per metric, from the registry
    (default: VIEWER_METRICS, then the metrics of tasks written outside the package, which
    socialzoo.core.metrics.register_metric added)."""
    chosen = (*VIEWER_METRICS, *added_names()) if names is None else names
    return [[m.name, m.heading, m.digits, m.kind] for m in map(metric, chosen)]


def encode_replay(
    scene: ReplayScene,
    traces: Sequence[EpisodeTrace],
    *,
    encoding: Encoding | None = None,
    view: str = "follow",
) -> dict[str, Any]:
    """The JSON object the viewer plays: the scene and one entry per episode (panel).

    Args:
        scene: the map and sizes shared by every panel.
        traces: the episodes, one panel each, in order.
        encoding: what is kept and how precisely (default Encoding()).
        view: the camera the page opens with, "follow" or "map".

    Raises:
        ValueError: no traces, or a bad view.
    """
    if not traces:
        raise ValueError("encode_replay: at least one episode is needed")
    if view not in ("follow", "map"):
        raise ValueError(f"encode_replay: view must be 'follow' or 'map', got {view!r}")
    enc = encoding or Encoding()
    names = scene.action_names
    for t in traces:
        if len(t.action) and t.action.max() >= len(names):
            raise ValueError(
                f"encode_replay: {t.label} took action {int(t.action.max())}, but the scene names "
                f"{len(names)} actions {list(names)}"
            )
    # The legend shows what the page draws: the task's actions, the bodies, and the carrot, the scan and
    # the followed person only where an episode has them (without a navigator the recorder keeps the
    # goal as the carrot: a velocity task in the open has none).
    legend = ["robot", "humans", "goal"]
    if any(not np.array_equal(t.carrot, np.broadcast_to(t.goal[:2], t.carrot.shape)) for t in traces):
        legend.append("carrot")
    if any(t.other_robots is not None and t.other_robots.shape[1] for t in traces):
        legend.insert(1, "other robots")
    if any(t.laser_ranges.shape[1] for t in traces):
        legend.append("laser")
    if any((t.target_human >= 0).any() for t in traces):
        legend.append("followed / passed")
    return {
        "format": REPLAY_FORMAT,
        "title": scene.title,
        "subtitle": scene.subtitle,
        "view": view,
        "scene": {
            "map": scene.map_name,
            "walls": _flat(scene.walls, enc.position_decimals),
            "bounds": list(scene.bounds),
            "robotLength": scene.robot_length,
            "robotWidth": scene.robot_width,
            "humanRadius": scene.human_radius,
            "goalRadius": scene.goal_radius,
        },
        "actions": {
            "names": list(names),
            "colors": [ACTION_COLORS[i % len(ACTION_COLORS)] for i in range(len(names))],
            "none": NO_ACTION_COLOR,
        },
        "legend": legend,
        "metricRows": metric_rows(),
        "episodes": [encode_episode(t, enc) for t in traces],
    }
