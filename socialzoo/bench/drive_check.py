"""A map that checks itself by driving: GoAlone, alone (no people), over pose pairs in one batched world, and a
report of every route it cannot complete, where it stopped and why."""

from __future__ import annotations

import math
from collections import Counter, deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.runner import SHRINK
from socialzoo.core.geometry import closest_point_on_segment
from socialzoo.env.config import EnvConfig
from socialzoo.maps.map_file import Map
from socialzoo.nav.subpolicies import GO_ALONE
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario import Scenario

# The causes of a route that was not completed, in the order the report lists them.
DRIVE_CAUSES = (
    "wall_collision",
    "goal_unreachable",
    "start_unleavable",
    "blocked_doorway",
    "oscillation",
    "stuck",
    "timeout",
)
# How far along the plan past the stopping point a narrow gap counts as blocking it, m.
LOOK_AHEAD = 2.0
# A robot that stayed within this of its final position over the last stuck_time seconds
# stopped; one that went farther oscillated, m.
STILL_RADIUS = 1.0


@dataclass(frozen=True)
class RouteDrive:
    """One driven route.

    The causes of a route that was not completed:

    - "wall_collision": the footprint touched a wall (the episode ended there);
    - "goal_unreachable": it stopped on the last leg of its plan, the straight join from the graph to
      the goal pose, and that join passes closer to a wall than the robot keeps (a goal behind a gap
      it cannot drive through);
    - "start_unleavable": likewise on the first leg, from the start pose to the graph;
    - "blocked_doorway": it stopped where the plan ahead passes closer to a wall than the robot
      keeps (a door or gap narrower than about 0.74 m on its way);
    - "oscillation": no progress for the last `stuck_time` seconds (the episode metric `stuck`) but
      it kept moving, back and forth;
    - "stuck": no progress and it stayed within 1 m, with no narrow gap ahead;
    - "timeout": it was still making progress when the time ran out (a route too long or slow).

    Attributes:
        start, goal: legal-pose indices.
        reached: the goal was reached within the time limit.
        time: the episode's duration, s.
        stop: (2,) where the robot stopped (its final position), m.
        cause: "" for a completed route, else one of DRIVE_CAUSES.
        where: (2,) the place the cause names (the narrowest gap, the wall touched, the
            stopping point), m.
        gap: the plan's least wall distance near `where`, m (nan where it does not apply).
    """

    start: int
    goal: int
    reached: bool
    time: float
    stop: np.ndarray
    cause: str = ""
    where: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    gap: float = math.nan

    def describe(self) -> str:
        """The route's outcome in words."""
        head = f"pose {self.start} -> pose {self.goal}"
        if self.reached:
            return f"{head}: reached in {self.time:.1f} s"
        at = f"({self.where[0]:.2f}, {self.where[1]:.2f})"
        stop = f"stopped at ({self.stop[0]:.2f}, {self.stop[1]:.2f})"
        gap = f"{self.gap:.2f} m from a wall" if math.isfinite(self.gap) else ""
        why = {
            "wall_collision": f"touched a wall at {at}",
            "goal_unreachable": f"goal unreachable: its join to the graph passes {gap} at {at}",
            "start_unleavable": f"start cannot be left: its join to the graph passes {gap} at {at}",
            "blocked_doorway": f"blocked doorway at {at}: the plan passes {gap} there",
            "oscillation": "oscillation: moving without progress",
            "stuck": "stuck: no progress, not moving",
            "timeout": f"timeout after {self.time:.0f} s while still making progress",
        }[self.cause]
        return f"{head}: {why}; {stop}"


@dataclass(frozen=True)
class DriveReport:
    """What `drive_map` found.

    Attributes:
        map_name: the map.
        num_poses: its legal poses.
        routes: every driven route, in the order driven (sorted by start, then goal).
        wall_distance: the distance the robot keeps from walls, m (what a gap is judged by).
        time_limit: the time each route had, s.
    """

    map_name: str
    num_poses: int
    routes: tuple[RouteDrive, ...]
    wall_distance: float
    time_limit: float

    @property
    def failures(self) -> tuple[RouteDrive, ...]:
        """The routes not completed."""
        return tuple(r for r in self.routes if not r.reached)

    @property
    def complete(self) -> bool:
        """True when every driven route was completed."""
        return not self.failures

    def counts(self) -> dict[str, int]:
        """Failed routes by cause (causes with none left out)."""
        out = Counter(r.cause for r in self.failures)
        return {c: out[c] for c in DRIVE_CAUSES if c in out}

    def lines(self, limit: int | None = 50) -> list[str]:
        """The report as text lines: a summary, then every failed route (at most `limit`)."""
        n = len(self.routes)
        done = n - len(self.failures)
        times = np.array([r.time for r in self.routes if r.reached])
        head = f"drive: {done} of {n} routes completed ({100 * done / n:.0f}%)" if n else "drive: no routes"
        if len(times):
            head += f"; time to goal median {np.median(times):.1f} s, max {times.max():.1f} s"
        out = [head]
        if self.failures:
            out.append("failed: " + ", ".join(f"{c} {k}" for c, k in self.counts().items()))
            shown = self.failures if limit is None else self.failures[:limit]
            out += [f"  {r.describe()}" for r in shown]
            if len(shown) < len(self.failures):
                out.append(f"  ... and {len(self.failures) - len(shown)} more")
        return out


def pose_pairs(
    m: Map, sample: int | None = None, seed: int = 0, max_route_length: float | None = None
) -> np.ndarray:
    """The pose pairs scenarios may draw for the robot (M, 2): every ordered pair of distinct legal
    poses with a feasible route (socialzoo.scenarios.feasibility), or a seeded sample of `sample` of them."""
    from socialzoo.scenarios.feasibility import MAX_ROUTE_LENGTH, feasible_pairs

    limit = MAX_ROUTE_LENGTH if max_route_length is None else max_route_length
    first, second = np.nonzero(feasible_pairs(m, limit))
    pairs = np.stack((first, second), axis=1).astype(np.int64)
    if sample is not None and sample < len(pairs):
        pick = np.sort(np.random.default_rng(seed).choice(len(pairs), size=sample, replace=False))
        pairs = pairs[pick]
    return pairs


def _scenario(m: Map, poses: np.ndarray, start: int, goal: int) -> Scenario:
    return Scenario(
        map_name=m.name,
        seed=0,
        robot_starts=poses[[start]],
        robot_goals=poses[[goal]],
        human_spawn=np.zeros((0, 2)),
        human_start_index=np.zeros(0, dtype=np.int64),
        human_goal_index=np.zeros(0, dtype=np.int64),
        human_routes=(),
        human_speed=np.zeros(0),
        family="drive_check",
    )


def drive_config(m: Map, max_steps: int = 3200) -> EnvConfig:
    """The env config of a drive: the benchmark's robot and time limit, no human slots."""
    return EnvConfig(
        map=m.path or m.name, max_steps=max_steps, scenario=ScenarioConfig(min_humans=0, max_humans=0)
    )


def drive_map(
    m: Map,
    pairs: Sequence[tuple[int, int]] | np.ndarray | None = None,
    *,
    batch_size: int = 256,
    config: EnvConfig | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> DriveReport:
    """Drive GoAlone alone over pose pairs of a map and report every route it cannot complete.

    It runs the benchmark's robot (the action-selection task with GoAlone on every row: the same
    navigator, local planner and motion model as every episode) from each legal pose to each other one
    (or a seeded sample of the ordered pairs) within the benchmark's 80 s. A route that does not reach
    its goal gets a cause (RouteDrive), judged from where the robot stopped and the plan it was
    following.

    Args:
        m: the map (valid: its legal poses join the graph).
        pairs: (M, 2) ordered (start, goal) legal-pose indices; default every feasible ordered
            pair (`pose_pairs`).
        batch_size: rows driven together.
        config: the env config (default `drive_config`: the benchmark's robot, 80 s, no humans).
        progress: called with (routes done, routes) as routes finish.

    Returns:
        The report; its routes are in the order of `pairs`.
    """
    from socialzoo.env.tasks.action_selection import ActionSelectionTask

    poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)
    todo = pose_pairs(m) if pairs is None else np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    config = config or drive_config(m)
    if len(todo) == 0:
        return DriveReport(m.name, len(poses), (), config.planner.wall_distance, config.max_steps * config.dt)
    b = min(batch_size, len(todo))
    task = ActionSelectionTask(config, b, map_data=m)
    # Positions once a second over the last stuck_time seconds (for the oscillation test), per row.
    every = max(1, round(1.0 / config.dt))
    window = max(2, math.ceil(config.metrics.stuck_time) + 1)
    trace = np.zeros((b, window, 2))
    pending = deque(range(len(todo)))
    row_job = np.full(b, -1, dtype=np.int64)
    results: dict[int, RouteDrive] = {}

    def start_rows(rows: np.ndarray) -> None:
        jobs = [pending.popleft() for _ in range(min(len(rows), len(pending)))]
        rows = rows[: len(jobs)]
        if jobs:
            task.reset_rows(rows, [_scenario(m, poses, int(todo[j, 0]), int(todo[j, 1])) for j in jobs])
            row_job[rows] = jobs
            trace[rows] = poses[todo[jobs, 0], None, :2]

    start_rows(np.arange(b))
    while (row_job >= 0).any():
        task.step(np.full((task.batch_size, 1), GO_ALONE, dtype=np.int64))
        state = task.core.state
        assert state is not None  # reset above
        count = state.step_count
        sample = np.flatnonzero(count % every == 0)
        trace[sample, (count[sample] // every) % window] = state.robot_pose[sample, 0, :2]
        # A route without progress for stuck_time is judged at once: it has failed (`stuck`).
        stuck = task.metrics.without_progress >= config.metrics.stuck_time - 1e-9
        finished = np.flatnonzero((row_job >= 0) & (task.core.done[:, 0] | stuck))
        if len(finished) == 0:
            continue
        summaries = task.episode_metrics(finished)
        for row, summary in zip(finished.tolist(), summaries, strict=True):
            job = int(row_job[row])
            results[job] = _judge(task, row, int(todo[job, 0]), int(todo[job, 1]), summary, trace[row])
        row_job[finished] = -1
        start_rows(finished)
        if progress is not None:
            progress(len(results), len(todo))
        live = np.flatnonzero(row_job >= 0)
        if not pending and 0 < len(live) <= SHRINK * len(row_job):
            # The tail: step only the routes still driving (each continues exactly as before).
            task = task.compact(live)
            row_job, trace = row_job[live], trace[live]
    return DriveReport(
        map_name=m.name,
        num_poses=len(poses),
        routes=tuple(results[j] for j in range(len(todo))),
        wall_distance=config.planner.wall_distance,
        time_limit=config.max_steps * config.dt,
    )


def _judge(task: Any, row: int, start: int, goal: int, summary: dict, trace: np.ndarray) -> RouteDrive:
    """The RouteDrive of a finished row of `task` (an ActionSelectionTask)."""
    core = task.core
    state = core.state
    stop = state.robot_pose[row, 0, :2].copy()
    time = float(summary["duration"])
    if summary["reached"]:
        return RouteDrive(start, goal, True, time, stop)
    if summary["wall_collisions"]:
        return RouteDrive(start, goal, False, time, stop, "wall_collision", stop.copy(), 0.0)
    wall_distance = task.config.planner.wall_distance
    plans = core.navigator.plans
    length = int(plans.lengths[row, 0])
    path = plans.paths[row, 0, :length]
    _, where, gap = _narrowest_ahead(core.field, path, stop)
    narrow = gap < wall_distance
    # The joins of the start and goal poses to the graph, as the robot's plans make them.
    poses = core.scenarios[row].robot_starts[0, :2], core.scenarios[row].robot_goals[0, :2]
    att = core.navigator.graph.attach(np.stack(poses), strict=False, clearance=wall_distance)
    on_join = [
        bool(att.found[k]) and closest_point_on_segment(where, poses[k], att.point[k])[1] < 0.25
        for k in (0, 1)
    ]
    if not summary["stuck"]:
        cause = "timeout"
    elif narrow and on_join[1]:
        cause = "goal_unreachable"
    elif narrow and on_join[0]:
        cause = "start_unleavable"
    elif narrow:
        cause = "blocked_doorway"
    elif np.hypot(*(trace - stop).T).max() > STILL_RADIUS:
        cause = "oscillation"
    else:
        cause = "stuck"
    if cause in ("timeout", "oscillation", "stuck"):
        where, gap = stop.copy(), math.nan
    return RouteDrive(start, goal, False, time, stop, cause, where, gap)


def _narrowest_ahead(field: object, path: np.ndarray, pos: np.ndarray) -> tuple[int, np.ndarray, float]:
    """(leg, point, wall distance) of the narrowest point of `path` (L, 2) within LOOK_AHEAD of its
    point closest to `pos`, read in the planner's distance field."""
    if len(path) < 2:
        return 0, path[0].copy(), math.inf
    a, b = path[:-1], path[1:]
    ab = b - a
    len2 = np.maximum((ab**2).sum(-1), 1e-12)
    t = np.clip(((pos - a) * ab).sum(-1) / len2, 0.0, 1.0)
    dist = np.hypot(*(a + t[:, None] * ab - pos).T)
    seg = int(np.argmin(dist))
    # Sample the path from the closest point on, 5 cm apart, up to LOOK_AHEAD.
    pts, legs = [], []
    left = LOOK_AHEAD
    frac = float(t[seg])
    for s in range(seg, len(path) - 1):
        seg_len = math.sqrt(float(len2[s]))
        span = min((1.0 - frac) * seg_len, left)
        num = max(1, math.ceil(span / 0.05))
        u = frac + np.linspace(0.0, span / max(seg_len, 1e-12), num + 1)
        pts.append(a[s] + u[:, None] * ab[s])
        legs.append(np.full(num + 1, s))
        left -= span
        frac = 0.0
        if left <= 0:
            break
    samples = np.concatenate(pts)
    leg_of = np.concatenate(legs)
    d = field.lookup(samples)  # type: ignore[attr-defined]
    k = int(np.argmin(d))
    return int(leg_of[k]), samples[k].copy(), float(d[k])


# ---------------------------------------------------------------------------- buildings with people

# The built-in buildings' reference walls: the social_gym data beside the shipped maps (maps/reference/
# in the repository, package data of socialzoo._maps in an install).
REFERENCE_WALLS = ("reference", "socialgym")
# Sample the robot's position every this many steps for pictures and "never moved" (0.25 s).
TRACE_EVERY = 10


def builtin_buildings() -> dict[str, np.ndarray]:
    """Walls (W, 4) of the built-in buildings, by name: the second floor plan in the social_gym
    GDC1 data (below y = -5 m, which the benchmark never uses) and the raw GHC3 walls (the
    reference data shipped beside the maps), then seeded synthetic plans (socialzoo.maps.floorplans:
    offices along corridors, atria with pillars, winding corridors with sharp corners, grids of rooms
    with 0.9-1.2 m doors, a 150 m corridor)."""
    import importlib.resources

    from socialzoo.maps import floorplans
    from socialzoo.maps.importers import drop_zero_length, read_table
    from socialzoo.maps.map_file import MAPS_PACKAGE

    out: dict[str, np.ndarray] = {}
    # The installed package's folder (maps are read from files on disk, not from a zip).
    reference = Path(str(importlib.resources.files(MAPS_PACKAGE).joinpath(*REFERENCE_WALLS)))
    gdc1 = read_table(reference / "gdc1_walls.txt", 4, "x1 y1 x2 y2")
    out["gdc1_floor2"] = drop_zero_length(gdc1[(gdc1[:, 1] < -5.0) & (gdc1[:, 3] < -5.0)])
    out["ghc3_raw"] = read_table(reference / "ghc3_walls.txt", 4, "x1 y1 x2 y2")
    for seed in (1, 2):
        out[f"office_corridor_{seed}"] = floorplans.office_corridor(seed, num_offices=10).walls
        out[f"atrium_{seed}"] = floorplans.atrium(seed).walls
        out[f"winding_corridor_{seed}"] = floorplans.winding_corridor(
            seed, num_legs=8, leg_length=(3.0, 10.0)
        ).walls
        out[f"room_grid_{seed}"] = floorplans.room_grid(seed, rows=3, cols=4).walls
    out["long_corridor"] = floorplans.long_corridor(150.0).walls
    return out


@dataclass(frozen=True)
class BuildingEpisodes:
    """GoAlone among people on one building (`drive_building`).

    Attributes:
        episodes: episodes run.
        outcomes: episodes by outcome (socialzoo.env.metrics.FAILURE_CAUSES: success and every
            failure cause).
        stuck: episodes whose metric `stuck` is set (whatever ended them).
        never_moved: episodes in which the robot stayed within 1 m of its start.
        pictures: the failure pictures drawn.
    """

    episodes: int
    outcomes: dict[str, int]
    stuck: int
    never_moved: int
    pictures: tuple[Path, ...] = ()

    @property
    def success_rate(self) -> float:
        """Share of successful episodes."""
        return self.outcomes["success"] / self.episodes if self.episodes else 0.0


def drive_building(
    map_path: Path, out: Path, episodes: int, *, batch_size: int = 30, pictures: bool = False
) -> BuildingEpisodes:
    """GoAlone on the first `episodes` scenarios of the test set `socialzoo benchmark --maps
    MAP_PATH` generates for the map (base seed 20220100, stored in OUT/test_sets), each episode's
    outcome by cause; with `pictures`, each failure drawn to OUT/NAME-fail-K.png (walls, the
    first plan, the robot's track, start and goal)."""
    from socialzoo.bench.runner import BatchedRunner, RunSpec, Trial, env_config_for
    from socialzoo.bench.test_sets import stored_test_set
    from socialzoo.env.metrics import FAILURE_CAUSES, failure_cause
    from socialzoo.maps.map_file import read_map

    test_set = stored_test_set(str(map_path), out, episodes)
    spec = RunSpec(
        test_sets={"eval": test_set},
        env_configs={"eval": env_config_for(test_set)},
        policies={"goalone": {}},
        batch_size=batch_size,
    )
    traces: dict[int, list[np.ndarray]] = {}
    plans: dict[int, np.ndarray] = {}

    def on_step(task, row_trial, obs, actions, result) -> None:  # type: ignore[no-untyped-def]
        core = task.core
        pos = core.state.robot_pose[:, 0, :2]
        for row, t in enumerate(row_trial):
            if t is None:
                continue
            if t.index not in plans:
                p = core.navigator.plans
                plans[t.index] = p.paths[row, 0, : p.lengths[row, 0]].copy()
            if core.state.step_count[row] % TRACE_EVERY == 0:
                traces.setdefault(t.index, []).append(pos[row].copy())

    results = BatchedRunner(spec).run([Trial("goalone", "eval", k) for k in range(episodes)], on_step=on_step)
    outcomes = dict.fromkeys(FAILURE_CAUSES, 0)
    never_moved = 0
    drawn: list[Path] = []
    m = read_map(map_path) if pictures else None
    for r in results:
        k = r.trial.index
        cause = failure_cause(r.metrics)
        outcomes[cause] += 1
        scenario = test_set.scenario(k)
        start = scenario.robot_start[:2]
        trace = np.array(traces.get(k, [start]))
        never_moved += bool(np.hypot(*(trace - start).T).max() < STILL_RADIUS)
        if m is not None and cause != "success":
            mt = r.metrics
            title = (
                f"{m.name} scenario {k}: {cause}; reached {mt['reached']}, {mt['distance_from_goal']:.1f} m "
                f"from goal, travelled {mt['distance_travelled']:.0f} m, humans coll. "
                f"{mt['human_collisions']}, wall {mt['wall_collisions']}"
            )
            drawn.append(draw_failure(m, scenario, trace, plans[k], title, out / f"{m.name}-fail-{k}.png"))
    stuck = sum(bool(r.metrics.get("stuck")) for r in results)
    return BuildingEpisodes(len(results), outcomes, stuck, never_moved, tuple(drawn))


def draw_failure(
    m: Map, scenario: Scenario, trace: np.ndarray, plan: np.ndarray, title: str, path: Path
) -> Path:
    """Walls around the episode, its first plan, the robot's track, start (green) and goal (red),
    to `path`; returns it."""
    from socialzoo.bench.figures import pyplot

    plt = pyplot()
    from matplotlib.collections import LineCollection  # after pyplot() chose the Agg backend

    fig, ax = plt.subplots(figsize=(9, 8))
    pts = np.concatenate((trace, plan, scenario.robot_start[None, :2], scenario.robot_goal[None, :2]))
    lo, hi = pts.min(axis=0) - 3.0, pts.max(axis=0) + 3.0
    walls = np.asarray(m.walls).reshape(-1, 2, 2)
    ax.add_collection(LineCollection(list(walls), colors="0.1", linewidths=0.8))
    if len(m.edges):
        ax.add_collection(LineCollection(m.nodes[m.edges], colors="tab:blue", linewidths=0.5, alpha=0.4))
    ax.plot(plan[:, 0], plan[:, 1], "--", color="tab:blue", lw=1)
    ax.plot(trace[:, 0], trace[:, 1], "-", color="tab:orange", lw=1.2)
    ax.plot(trace[-1, 0], trace[-1, 1], "x", color="k", ms=9)
    ax.plot(*scenario.robot_start[:2], "o", color="tab:green", ms=7)
    ax.plot(*scenario.robot_goal[:2], "o", color="tab:red", ms=7)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def building_table_head() -> list[str]:
    """The two header lines of the buildings table (`building_row`)."""
    from socialzoo.env.metrics import FAILURE_CAUSES

    causes = [c.replace("_", " ") for c in FAILURE_CAUSES if c != "success"]
    head = (
        "| building | own graph | import | walls | nodes | poses | routes driven on import | repairs | "
        "GoAlone success % | " + " | ".join(causes) + " | episodes stuck (metric) | never moved | s |"
    )
    return [head, "|" + "---|" * (len(causes) + 12)]


def building_row(
    name: str, own_graph: bool, status: str, m: Map | None, drive: BuildingEpisodes | None, seconds: float
) -> str:
    """One building's line of the table: its import (`status`: "ok" or why it was refused, and the
    map's provenance: the routes its drive check completed, its repairs) and GoAlone's episodes."""
    from socialzoo.env.metrics import FAILURE_CAUSES

    causes = [c for c in FAILURE_CAUSES if c != "success"]
    own = "yes" if own_graph else "no"
    if m is None or drive is None:
        return (
            f"| {name} | {own} | {status} |"
            + " |" * 5
            + " 0 |"
            + " |" * (len(causes) + 2)
            + f" {seconds:.0f} |"
        )
    provenance = m.provenance or {}
    record = provenance.get("drive", {})
    driven = f"{record['routes_completed']}/{record['routes_driven']}" if record else "-"
    outcomes = " | ".join(str(drive.outcomes[c]) for c in causes)
    return (
        f"| {name} | {own} | {status} | {m.num_walls} | {m.num_nodes} | {len(m.legal_poses)} | {driven} | "
        f"{len(provenance.get('repairs', []))} | {100 * drive.success_rate:.0f} | {outcomes} | "
        f"{drive.stuck} | {drive.never_moved} | {seconds:.0f} |"
    )
