"""The benchmark's scenario generator (SPEC section 5) and its settings, ScenarioConfig; also the spawn jitter and
route planning that the scenario families share with it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from socialzoo.core.validation import check_fields
from socialzoo.core.walls import WallIndex
from socialzoo.maps.map_file import Map
from socialzoo.maps.segments import segments_free
from socialzoo.nav.graph import NoPathError, graph_of
from socialzoo.scenarios.feasibility import (
    MAX_ROUTE_LENGTH,
    feasible_pairs,
    max_humans_for,
    redraw_human_pairs,
    redraw_robot_pair,
)
from socialzoo.scenarios.scenario import Scenario


@dataclass(frozen=True, kw_only=True)
class ScenarioConfig:
    """How the benchmark draws scenarios (SPEC sections 4 and 5).

    Attributes:
        min_humans, max_humans: head count range, inclusive (h_min, h_max).
        repeats: episodes run on each scenario before a new one is drawn (N_r).
        spawn_jitter: half-width of the uniform spawn offset around a human's start pose, m.
        speed_mean, speed_std: preferred walking speed distribution N(mean, std), m/s.
        min_speed, max_speed: the sampled speed is clipped to this range, m/s.
        spawn_clearance: a jittered spawn closer than this to a wall is re-drawn, m.
        spawn_tries: jitter draws per human before it spawns on its start pose itself.
        max_route_length: the feasibility rule: a robot or human start/goal pair whose planned
            route is longer than this is drawn again, m (socialzoo.scenarios.feasibility: by default
            75% of the 80 s time limit at GoAlone's 1.5 m/s cruise speed, 90 m).
    """

    min_humans: int = 5
    max_humans: int = 25
    repeats: int = 1
    spawn_jitter: float = 0.5
    speed_mean: float = 1.0
    speed_std: float = 0.1
    min_speed: float = 0.5
    max_speed: float = 1.3
    spawn_clearance: float = 0.2
    spawn_tries: int = 10
    max_route_length: float = MAX_ROUTE_LENGTH

    def __post_init__(self) -> None:
        check_fields(
            self, nonnegative=("min_humans", "max_humans", "spawn_jitter", "speed_std", "spawn_clearance")
        )
        if self.min_humans > self.max_humans:
            raise ValueError(
                f"ScenarioConfig.min_humans ({self.min_humans}) exceeds max_humans ({self.max_humans})"
            )
        if self.min_speed > self.max_speed:
            raise ValueError(
                f"ScenarioConfig.min_speed ({self.min_speed}) exceeds max_speed ({self.max_speed})"
            )


def _bad_spawns(
    walls: WallIndex, spawn: np.ndarray, anchor: np.ndarray, target: np.ndarray, clearance: float
) -> np.ndarray:
    """(n,) spawns too close to a wall, or cut off by a wall from their anchor or first target."""
    _, dist = walls.nearest(spawn)
    return (dist < clearance) | ~segments_free(walls, spawn, anchor) | ~segments_free(walls, spawn, target)


def spawn_points(
    walls: WallIndex,
    anchor: np.ndarray,
    target: np.ndarray,
    draw: Callable[[int], np.ndarray],
    clearance: float,
    tries: int,
) -> np.ndarray:
    """Offset anchors by random draws, re-drawing the offsets of spawns that land badly.

    A spawn is bad when it is closer than `clearance` to a wall or when a wall cuts the straight
    line from it to its anchor or to its first target; after `tries` draws a still-bad spawn
    falls back to its anchor. Re-draws consume the generator in row order, so the result depends
    only on the generator's state.

    Args:
        walls: the map's wall index.
        anchor: (n, 2) start positions, m.
        target: (n, 2) the first point each human walks to from its spawn, m.
        draw: k -> (k, 2) random offsets, m.
        clearance: m.
        tries: number of draws, >= 1.

    Returns:
        (n, 2) spawn positions, m.
    """
    spawn = anchor + draw(len(anchor))
    bad = _bad_spawns(walls, spawn, anchor, target, clearance)
    for _ in range(tries - 1):
        rows = np.flatnonzero(bad)
        if len(rows) == 0:
            break
        spawn[rows] = anchor[rows] + draw(len(rows))
        bad[rows] = _bad_spawns(walls, spawn[rows], anchor[rows], target[rows], clearance)
    spawn[bad] = anchor[bad]
    return spawn


def split_routes(paths: np.ndarray, lengths: np.ndarray) -> tuple[np.ndarray, ...]:
    """Each row's route, its first `lengths[i]` points of `paths[i]`."""
    return tuple(paths[i, : lengths[i]] for i in range(len(paths)))


def plan_routes(m: Map, starts: np.ndarray, goals: np.ndarray, context: str) -> tuple[np.ndarray, np.ndarray]:
    """plan_batch with errors that say which scenario asked."""
    try:
        return graph_of(m).plan_batch(starts, goals)
    except NoPathError as err:
        raise NoPathError(f"{context}: {err}") from err


def generate_scenario(m: Map, seed: int, cfg: ScenarioConfig | None = None) -> Scenario:
    """Draw one benchmark scenario (SPEC section 5) from a seed.

    Draws, in this order, from np.random.default_rng(seed): robot start and goal (two distinct
    legal poses, both drawn again while their route is infeasible); the head count n, uniform in
    [min_humans, max_humans] (max_humans lowered to the benchmark's crowd density on a map with
    a walkable_area, see socialzoo.scenarios.feasibility); n human starts, each any legal pose but the
    robot's start; n human goals, each any legal pose but that human's start (infeasible human pairs are drawn again,
    row by row); n preferred speeds N(speed_mean, speed_std) clipped to [min_speed, max_speed]; spawn jitter,
    uniform in +-spawn_jitter per axis, re-drawn for bad spawns (see `spawn_points`). Humans may
    share start and goal poses with each other, and a human's goal may be the robot's start or
    goal: the benchmark needs up to 25 humans on maps with few poses (GDC1 has 26). Every route
    is planned with NavGraph.plan_batch (A*-equal shortest paths, start and goal joined to the
    nearest reachable edge, a straight line where wall-free). Feasible: a route at most
    cfg.max_route_length long (socialzoo.scenarios.feasibility); a pair still infeasible after 256
    draws is replaced by a uniform pick among the feasible pairs.

    Args:
        m: the map.
        seed: any non-negative int.
        cfg: generator settings; defaults to ScenarioConfig().

    Returns:
        The scenario.

    Raises:
        ValueError: the map has fewer than 2 legal poses, or no feasible pair of them.
    """
    cfg = cfg or ScenarioConfig()
    poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)
    num_poses = len(poses)
    if num_poses < 2:
        raise ValueError(
            f"{m.where}: scenario generation needs at least 2 legal poses, the map has {num_poses}"
        )
    feasible = feasible_pairs(m, cfg.max_route_length)
    if not feasible.any():
        raise ValueError(
            f"{m.where}: no two legal poses are joined by a route of at most {cfg.max_route_length:g} m "
            "(ScenarioConfig.max_route_length, the feasibility rule); check the map with "
            "`socialzoo map check`"
        )
    rng = np.random.default_rng(seed)
    robot_start = int(rng.integers(num_poses))
    robot_goal = int(rng.integers(num_poses - 1))
    robot_goal += robot_goal >= robot_start
    robot_start, robot_goal = redraw_robot_pair(rng, feasible, robot_start, robot_goal)
    n = int(rng.integers(cfg.min_humans, max_humans_for(m, cfg.min_humans, cfg.max_humans), endpoint=True))
    start = rng.integers(num_poses - 1, size=n)
    start += start >= robot_start
    goal = rng.integers(num_poses - 1, size=n)
    goal += goal >= start
    redraw_human_pairs(rng, feasible, robot_start, start, goal, m.where)
    speed = np.clip(rng.normal(cfg.speed_mean, cfg.speed_std, size=n), cfg.min_speed, cfg.max_speed)
    context = f"{m.where}, scenario seed {seed}"
    starts = np.concatenate((poses[[robot_start], :2], poses[start, :2]))
    goals = np.concatenate((poses[[robot_goal], :2], poses[goal, :2]))
    paths, lengths = plan_routes(m, starts, goals, context)
    routes = split_routes(paths[1:], lengths[1:])
    first_target = paths[1:, 1] if n else np.zeros((0, 2))
    jitter = cfg.spawn_jitter
    spawn = spawn_points(
        m.wall_index,
        poses[start, :2],
        first_target,
        lambda k: rng.uniform(-jitter, jitter, size=(k, 2)),
        cfg.spawn_clearance,
        cfg.spawn_tries,
    )
    return Scenario(
        map_name=m.name,
        seed=seed,
        robot_starts=poses[[robot_start]],
        robot_goals=poses[[robot_goal]],
        human_spawn=spawn,
        human_start_index=start,
        human_goal_index=goal,
        human_routes=routes,
        human_speed=speed,
    )
