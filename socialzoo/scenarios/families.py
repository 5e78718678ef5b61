"""Scenario families on small maps, each one class with a few lines of layout: hallway head-on, overtaking, crossing
at an intersection, doorway, circle crossing and parallel traffic (the guidelines' scenario names)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

# FAMILIES: the registry, also read from here (socialzoo.env.config checks EnvConfig.family in it).
from socialzoo.scenarios.catalogue import FAMILIES as FAMILIES
from socialzoo.scenarios.catalogue import ScenarioFamily
from socialzoo.scenarios.suite import SUITE_SPLITS

if TYPE_CHECKING:
    from socialzoo.maps.map_file import Map
    from socialzoo.scenarios.scenario import Scenario


# Layouts a family draws from one seed before it gives up on a map (LayoutFamily.make).
LAYOUT_TRIES = 30


@dataclass(frozen=True)
class Layout:
    """A family's choice of robot and human starts, goals and speeds (world frame, m, m/s).

    Attributes:
        robot_start, robot_goal: (2,) positions; headings point from start to goal.
        human_start, human_goal: (n, 2).
        human_speed: (n,).
        human_stop: (n, 2) the point where each person waits (its route goes start -> stop -> goal),
            NaN rows for people who do not stop; None: nobody stops.
        script: the other fields of the scenario's script (socialzoo.scenarios.script.Script:
            release, gate, gesture, follow, gap, escort, escort_kind, band, doors) for one robot;
            None with no stops: no script.
        human_group: (n,) walking or standing group of each person (the index of its first
            member), -1 for none; None: none.
    """

    robot_start: np.ndarray
    robot_goal: np.ndarray
    human_start: np.ndarray
    human_goal: np.ndarray
    human_speed: np.ndarray
    human_stop: np.ndarray | None = None
    script: dict[str, Any] | None = None
    human_group: np.ndarray | None = None


class LayoutFamily(ScenarioFamily):
    """A family on a map, written as its layout rule: `layout(m, rng)` picks the starts, goals
    and speeds from rng (numpy's default_rng(seed)); `make` plans everyone's route.

    Layouts place people relative to the map's legal poses (its main axis is its farthest pair of
    poses), so they also run on other maps of a similar shape. They place one robot: the env's
    scenario stream adds the others (socialzoo.env.scenario_source.with_robots).
    """

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The layout drawn from rng on map m."""
        raise NotImplementedError(f"{type(self).__name__}.layout")

    def start_heading(self, route: np.ndarray, start: np.ndarray, goal: np.ndarray) -> float:
        """The robot's start heading, rad: along the first leg of its planned route (however short:
        the older families' rule, kept so that their seeded episodes stay as they were)."""
        first_leg = route[min(1, len(route) - 1)] - start
        return math.atan2(float(first_leg[1]), float(first_leg[0]))

    def make(self, seed: int, num_robots: int = 1, m: Map | None = None) -> Scenario:
        """The scenario of `seed` on map m (default: the family's map), drawn from default_rng(seed).

        Routes are planned like the benchmark's (a straight line where wall-free); humans spawn on
        their start points, and their pose indices are -1. One robot, whatever num_robots. A layout
        that puts someone where no route reaches (on another map than the family's: in a wall,
        outside the building, in a closed room) is drawn again from the same generator, up to
        LAYOUT_TRIES layouts, so a layout that plans is the one it always was.

        Raises:
            ValueError: the map has fewer than 2 legal poses.
            NoPathError: none of LAYOUT_TRIES layouts can be planned: the layout does not fit the map.
        """
        from socialzoo.maps.map_file import load_map
        from socialzoo.nav.graph import NoPathError
        from socialzoo.scenarios.generator import plan_routes, split_routes
        from socialzoo.scenarios.scenario import Scenario
        from socialzoo.scenarios.script import Script

        m = load_map(self.map_name) if m is None else m
        rng = np.random.default_rng(seed)
        context = f"{m.where}, family {self.name!r} seed {seed}"
        for attempt in range(LAYOUT_TRIES):
            lay = self.layout(m, rng)
            n = len(lay.human_start)
            starts = np.concatenate((lay.robot_start[None], lay.human_start))
            goals = np.concatenate((lay.robot_goal[None], lay.human_goal))
            stops = (
                np.full((n, 2), np.nan)
                if lay.human_stop is None
                else np.asarray(lay.human_stop, dtype=np.float64)
            )
            stopping = ~np.isnan(stops[:, 0])
            # People who stop walk start -> stop, then stop -> goal: their goals are their stops first.
            goals[1:][stopping] = stops[stopping]
            try:
                paths, lengths = plan_routes(m, starts, goals, context)
                if stopping.any():
                    rest, rest_len = plan_routes(m, stops[stopping], lay.human_goal[stopping], context)
                break
            except NoPathError as err:
                if attempt == LAYOUT_TRIES - 1:
                    raise NoPathError(
                        f"{context}: the family's layout does not fit this map ({LAYOUT_TRIES} layouts drawn, "
                        f"each with someone where no route reaches); the last: {str(err).removeprefix(context + ': ')}"
                    ) from err
        routes = list(split_routes(paths[1:], lengths[1:]))
        stop_index = np.full(n, -1)
        if stopping.any():
            for k, i in enumerate(np.flatnonzero(stopping)):
                stop_index[i] = len(routes[i]) - 1
                routes[i] = np.concatenate((routes[i], rest[k, 1 : rest_len[k]]))
        script = None
        if lay.script is not None or stopping.any():
            script = Script.plain(n, 1, stop=stop_index, **(lay.script or {}))
        # The robot faces along the first leg of its route.
        heading = self.start_heading(paths[0, : int(lengths[0])], lay.robot_start, lay.robot_goal)
        return Scenario(
            map_name=m.name,
            seed=seed,
            family=self.name,
            robot_starts=np.array([[*lay.robot_start, heading]]),
            robot_goals=np.array([[*lay.robot_goal, heading]]),
            human_spawn=lay.human_start,
            human_start_index=np.full(n, -1),
            human_goal_index=np.full(n, -1),
            human_routes=tuple(routes),
            human_speed=lay.human_speed,
            human_group=lay.human_group,  # type: ignore[arg-type]
            script=script,
        )


# A first route leg shorter than this does not set a suite robot's start heading, m.
MIN_LEG = 0.2


class SuiteFamily(LayoutFamily):
    """A scenario of the guidelines' suite (socialzoo.scenarios.suite): a layout family with the
    suite's seed splits (validation 0-99, test 100-599, training from 1000)."""

    splits = SUITE_SPLITS

    def start_heading(self, route: np.ndarray, start: np.ndarray, goal: np.ndarray) -> float:
        """Along the route's first point at least MIN_LEG away (a leg of a few millimetres onto the
        navigation graph says nothing of the way), else towards the goal."""
        legs = route[1:] - start
        long_enough = np.flatnonzero(np.hypot(legs[:, 0], legs[:, 1]) >= MIN_LEG)
        way = legs[long_enough[0]] if len(long_enough) else goal - start
        return math.atan2(float(way[1]), float(way[0]))


def interior(m: Map, margin: float, who: str) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) the walls' bounding box, cut down to the map's region if there is one (a region may
    have margins), `margin` inside it, m.

    Raises:
        ValueError: the map has no walls and no region, or the box is gone at that margin.
    """
    if not m.num_walls and m.region is None:
        raise ValueError(f"{m.where}: family {who!r} needs walls or a region to bound its open area")
    lo, hi = np.full(2, -np.inf), np.full(2, np.inf)
    if m.num_walls:
        ends = np.asarray(m.walls, dtype=np.float64).reshape(-1, 2)
        lo, hi = ends.min(0), ends.max(0)
    if m.region is not None:
        lo = np.maximum(lo, np.asarray(m.region[:2], dtype=np.float64))
        hi = np.minimum(hi, np.asarray(m.region[2:], dtype=np.float64))
    lo, hi = lo + margin, hi - margin
    if np.any(hi <= lo):
        raise ValueError(f"{m.where}: family {who!r} needs an open area wider than {2 * margin:g} m")
    return lo, hi


def planned_route(m: Map, start: np.ndarray, goal: np.ndarray, context: str) -> np.ndarray:
    """(k, 2) the route from start to goal, planned as people's routes are; errors begin with `context`."""
    from socialzoo.scenarios.generator import plan_routes

    paths, lengths = plan_routes(m, start[None], goal[None], context)
    return np.asarray(paths[0, : int(lengths[0])])


def nominal_timing() -> tuple[float, float]:
    """(the robot's nominal speed: GoAlone's cruise, m/s; a person's start-up lag from rest: the
    social force's relaxation time, s), the defaults the suite's timed encounters are laid out with."""
    from socialzoo.core.config import HumanConfig
    from socialzoo.nav.subpolicies import SubPolicyConfig

    return SubPolicyConfig().go_alone_speed, HumanConfig().relaxation_time


def circle_point(cx: Any, cy: Any, radius: Any, angle: Any) -> tuple[Any, Any]:
    """The point at `angle` (rad) on the circle of `radius` (m) about (cx, cy): scalars or arrays.

    Circle crossing's geometry, written once: the CircleCrossing family calls it on arrays (numpy's
    cos and sin), CrowdNav's cases compile it into their rejection kernel (socialzoo.scenarios.crowd_cases).
    """
    return cx + radius * np.cos(angle), cy + radius * np.sin(angle)


def antipode(cx: Any, cy: Any, x: Any, y: Any) -> tuple[Any, Any]:
    """The point opposite (x, y) across the centre (cx, cy), where a circle-crossing walker heads."""
    return 2.0 * cx - x, 2.0 * cy - y


def _farthest_pair(m: Map) -> tuple[np.ndarray, np.ndarray]:
    """The two legal poses farthest apart, (2,) positions each, lower index first."""
    p = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)[:, :2]
    if len(p) < 2:
        raise ValueError(f"{m.where}: scenario families need at least 2 legal poses, the map has {len(p)}")
    d = ((p[:, None] - p[None]) ** 2).sum(-1)
    i, j = np.unravel_index(int(np.argmax(d)), d.shape)
    return p[min(i, j)], p[max(i, j)]


def _cross_pair(m: Map, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pair of legal poses whose line crosses a-b most squarely, weighted by its length."""
    p = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)[:, :2]
    u = (b - a) / max(float(np.linalg.norm(b - a)), 1e-9)
    diff = p[None] - p[:, None]
    score = np.abs(diff[..., 0] * u[1] - diff[..., 1] * u[0])  # |cross|: perpendicular extent
    i, j = np.unravel_index(int(np.argmax(score)), score.shape)
    return p[min(i, j)], p[max(i, j)]


def _frame(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vector along a->b and its left normal."""
    u = (b - a) / max(float(np.linalg.norm(b - a)), 1e-9)
    return u, np.array([-u[1], u[0]])


def _near(
    m: Map,
    rng: np.random.Generator,
    anchor: np.ndarray,
    n: int,
    along: tuple[float, float],
    lateral: tuple[float, float],
    u: np.ndarray,
) -> np.ndarray:
    """n wall-safe points around `anchor`: offsets uniform in `along` x `lateral` in the frame of u."""
    left = np.array([-u[1], u[0]])

    def draw(k: int) -> np.ndarray:
        s = rng.uniform(*along, size=(k, 1))
        t = rng.uniform(*lateral, size=(k, 1))
        return s * u + t * left

    from socialzoo.scenarios.generator import spawn_points

    base = np.broadcast_to(anchor, (n, 2)).copy()
    return spawn_points(m.wall_index, base, base, draw, 0.3, 20)


def _speeds(rng: np.random.Generator, n: int, mean: float = 1.0, std: float = 0.1) -> np.ndarray:
    return np.clip(rng.normal(mean, std, size=n), 0.5, 1.3)


class Oncoming(LayoutFamily):
    """1-3 people start near the robot's goal and walk to near its start (HallwayHeadOn, Doorway).

    Attributes:
        spawn_along: where people start along the main axis, offsets from the robot's goal, m.
        lateral: their lateral offsets, at the start and at the goal, m.
    """

    spawn_along: tuple[float, float]
    lateral: tuple[float, float]

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot along the main axis; people start near its goal and walk to its start."""
        a, b = _farthest_pair(m)
        u, _ = _frame(a, b)
        n = int(rng.integers(1, 3, endpoint=True))
        return Layout(
            a,
            b,
            _near(m, rng, b, n, self.spawn_along, self.lateral, u),
            _near(m, rng, a, n, (0.0, 1.0), self.lateral, u),
            _speeds(rng, n),
        )


class HallwayHeadOn(Oncoming):
    """1-3 people walk down the hallway towards the robot."""

    name = "hallway_head_on"
    map_name = "hallway"
    description = "1-3 humans walk down the hallway towards the robot"
    spawn_along = (-2.0, 0.0)
    lateral = (-0.6, 0.6)


class Overtaking(LayoutFamily):
    """A slow person walks ahead of the robot, the same way."""

    name = "overtaking"
    map_name = "hallway"
    description = "a slow human (0.4-0.6 m/s) walks ahead of the robot, same way"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """One person 2-3 m ahead of the robot at 0.4-0.6 m/s, to the robot's goal."""
        a, b = _farthest_pair(m)
        u, _ = _frame(a, b)
        return Layout(
            a,
            b,
            _near(m, rng, a, 1, (2.0, 3.0), (-0.3, 0.3), u),
            _near(m, rng, b, 1, (-1.0, 0.0), (-0.3, 0.3), u),
            rng.uniform(0.4, 0.6, size=1),
        )


class Crossing(LayoutFamily):
    """People cross the robot's way along the other corridor of an intersection."""

    name = "crossing"
    map_name = "intersection"
    description = "2-4 humans cross the robot's way along the other corridor"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot along the main axis; 2-4 people along the crossing axis, either way."""
        a, b = _farthest_pair(m)
        c, d = _cross_pair(m, a, b)
        v, _ = _frame(c, d)
        n = int(rng.integers(2, 4, endpoint=True))
        forward = rng.random(n) < 0.5
        starts = np.where(
            forward[:, None],
            _near(m, rng, c, n, (0.0, 1.5), (-0.5, 0.5), v),
            _near(m, rng, d, n, (-1.5, 0.0), (-0.5, 0.5), v),
        )
        goals = np.where(forward[:, None], d, c)
        return Layout(a, b, starts, goals, _speeds(rng, n))


class Doorway(Oncoming):
    """People come through the door the robot must pass."""

    name = "doorway"
    map_name = "doorway"
    description = "1-3 humans come through the door the robot must pass"
    spawn_along = (-1.5, 0.0)
    lateral = (-0.8, 0.8)


class CircleCrossing(LayoutFamily):
    """The robot and 4-8 people on a circle walk to the antipode of their start."""

    name = "circle_crossing"
    map_name = "open_room"
    description = "robot and 4-8 humans on a circle walk to the antipode"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """n + 1 evenly spaced slots on the largest circle a metre inside the walls (or region),
        turned by a uniform angle, each jittered by up to 0.2 of a slot; the robot takes the first."""
        lo, hi = interior(m, 0.0, self.name)
        centre = (lo + hi) / 2.0
        # One metre inside the smaller half-extent keeps everyone clear of the enclosing walls.
        radius = max(0.5 * float(np.min(hi - lo)) - 1.0, 0.5)
        n = int(rng.integers(4, 8, endpoint=True))
        angle = rng.uniform(0.0, 2.0 * np.pi) + 2.0 * np.pi * (
            np.arange(n + 1) + rng.uniform(-0.2, 0.2, n + 1)
        ) / (n + 1)
        x, y = circle_point(centre[0], centre[1], radius, angle)
        gx, gy = antipode(centre[0], centre[1], x, y)
        start, goal = np.stack((x, y), axis=-1), np.stack((gx, gy), axis=-1)
        return Layout(start[0], goal[0], start[1:], goal[1:], _speeds(rng, n))


class ParallelTraffic(LayoutFamily):
    """People walk the robot's way at mixed speeds."""

    name = "parallel_traffic"
    map_name = "hallway"
    description = "4-8 humans walk the robot's way at mixed speeds"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """4-8 people spread along the first 60% of the main axis, to its far end."""
        a, b = _farthest_pair(m)
        u, _ = _frame(a, b)
        length = float(np.linalg.norm(b - a))
        n = int(rng.integers(4, 8, endpoint=True))
        starts = _near(m, rng, a, n, (1.0, 0.6 * length), (-1.0, 1.0), u)
        goals = _near(m, rng, b, n, (-1.0, 0.0), (-1.0, 1.0), u)
        return Layout(a, b, starts, goals, _speeds(rng, n, 1.0, 0.2))
