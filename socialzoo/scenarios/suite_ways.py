"""The suite's scenarios on ways (socialzoo.scenarios.suite, Fig. 7 a-h, k, v, x): traffic along a corridor, at an
intersection, through a door and across a room, each one family laid out on its map."""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.scenarios.families import (
    CircleCrossing,
    Layout,
    Overtaking,
    ParallelTraffic,
    SuiteFamily,
    _farthest_pair,
    _near,
    _speeds,
    nominal_timing,
    planned_route,
)
from socialzoo.scenarios.script import PROCEED, SLOW_DISTANCE, STOP_RADIUS, WAIT

if TYPE_CHECKING:
    from socialzoo.maps.map_file import Map
    from socialzoo.scenarios.scenario import Scenario

# A way narrower than this counts as a corridor, m; shorter stretches do not count.
CORRIDOR_WIDTH = 3.0
CORRIDOR_LENGTH = 4.0
# Where the hallway families' robot starts and stops: this far before and past the corridor, m.
ROOM_MARGIN = 2.0
# Nobody is placed nearer a wall than this, m (a person's radius and some).
CLEARANCE = 0.3
# A signalling person stops this far before the edge of the robot's way (design.md, g and h), m.
STOP_BEFORE = 1.2
# A gate is this far past the crossing way's far edge: the robot's centre is past its footprint, m.
GATE_PAST = 0.5


def _walls(m: Map) -> np.ndarray:
    return np.asarray(m.walls, dtype=np.float64).reshape(-1, 4)


def _ray(m: Map, origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Distance from each origin (..., 2) along its unit direction to the first wall, m (inf: none)."""
    from socialzoo.core.geometry import ray_segment_hit

    w = _walls(m)
    if len(w) == 0:
        return np.full(np.shape(origin)[:-1], np.inf)
    hit = ray_segment_hit(
        np.asarray(origin)[..., None, :], np.asarray(direction)[..., None, :], w[:, :2], w[:, 2:]
    )
    return np.asarray(hit.min(-1))


def _nearest_on(route: np.ndarray, point: np.ndarray) -> tuple[float, float]:
    """(the distance from `point` to the polyline `route` (k, 2), the arc length along the route to
    its point nearest `point`), m."""
    a, b = route[:-1], route[1:]
    ab = b - a
    t = np.clip(((point - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12), 0.0, 1.0)
    gap = np.hypot(*(a + t[:, None] * ab - point).T)
    seg = int(np.argmin(gap))
    before = float(np.hypot(*ab[:seg].T).sum())
    return float(gap[seg]), before + float(t[seg] * np.hypot(*ab[seg]))


def _left(u: np.ndarray) -> np.ndarray:
    return np.array([-u[1], u[0]])


def _unit(v: np.ndarray) -> np.ndarray:
    return v / max(float(np.linalg.norm(v)), 1e-9)


def _check_clear(m: Map, points: np.ndarray, what: str, family: str) -> None:
    """Raise a ValueError naming the map when a placed point lies within CLEARANCE of a wall."""
    from socialzoo.core.geometry import wall_distances

    near = wall_distances(np.asarray(points).reshape(-1, 2), _walls(m)) < CLEARANCE
    if near.any():
        raise ValueError(f"{m.where}: {family} has no room for {what} (the map's way is too short or narrow)")


@dataclass(frozen=True)
class Corridor:
    """The narrow stretch of a map's main way, the route between its two farthest legal poses.

    Attributes:
        start, end: (2,) the ends of the corridor's centre line, world frame, m; `start` is nearer
            the first of the farthest poses (`_farthest_pair`).
        half_width: half the corridor's width (its median along the stretch), m.
        back: room behind `start` along the corridor's axis up to a wall, m.
        ahead: room beyond `end` along the axis up to a wall, m.
    """

    start: np.ndarray
    end: np.ndarray
    half_width: float
    back: float
    ahead: float

    @property
    def u(self) -> np.ndarray:
        """(2,) the unit vector along the corridor, start to end."""
        return _unit(self.end - self.start)

    @property
    def length(self) -> float:
        """The corridor's length, m."""
        return float(np.linalg.norm(self.end - self.start))

    def at(self, s: np.ndarray | float, t: np.ndarray | float = 0.0) -> np.ndarray:
        """Points `s` along the axis from `start` and `t` to its left, m: (..., 2) for (...,) s and t."""
        s, t = np.asarray(s, dtype=np.float64)[..., None], np.asarray(t, dtype=np.float64)[..., None]
        return self.start + s * self.u + t * _left(self.u)


def corridor(m: Map) -> Corridor:
    """The corridor of map m: the longest stretch of the route between its farthest legal poses
    where the way (measured across the route) is narrower than CORRIDOR_WIDTH.

    Raises:
        ValueError: the route has no such stretch CORRIDOR_LENGTH long (naming the map).
    """
    a, b = _farthest_pair(m)
    route = planned_route(m, a, b, f"{m.where}, the corridor")
    pts, dirs = [], []
    for p, q in itertools.pairwise(route):
        n = max(int(np.ceil(np.linalg.norm(q - p) / 0.05)), 1)
        pts.append(p + np.linspace(0.0, 1.0, n, endpoint=False)[:, None] * (q - p))
        dirs.append(np.broadcast_to(_unit(q - p), (n, 2)))
    p, d = np.concatenate(pts), np.concatenate(dirs)
    left = np.stack((-d[:, 1], d[:, 0]), axis=-1)
    to_left, to_right = _ray(m, p, left), _ray(m, p, -left)
    width = to_left + to_right
    arc = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))))
    narrow = np.concatenate(([False], width <= CORRIDOR_WIDTH, [False]))
    edges = np.flatnonzero(np.diff(narrow.astype(np.int8)))
    runs = edges.reshape(-1, 2) - [0, 1]  # first and last index of each narrow run
    long = [(i, j) for i, j in runs if arc[j] - arc[i] >= CORRIDOR_LENGTH]
    if not long:
        raise ValueError(
            f"{m.where}: no corridor (a way narrower than {CORRIDOR_WIDTH} m for {CORRIDOR_LENGTH} m) "
            "between the map's farthest legal poses"
        )
    i, j = max(long, key=lambda r: arc[r[1]] - arc[r[0]])
    centre = p + left * ((to_left - to_right) / 2.0)[:, None]
    start, end = centre[i], centre[j]
    u = _unit(end - start)
    return Corridor(
        start=start,
        end=end,
        half_width=float(np.median(width[i : j + 1])) / 2.0,
        back=float(_ray(m, start, -u)),
        ahead=float(_ray(m, end, u)),
    )


def _hallway_robot(c: Corridor, m: Map, family: str, room: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """The hallway families' robot: from ROOM_MARGIN before the corridor to ROOM_MARGIN past it, with
    `room` m more at both ends."""
    if min(c.back, c.ahead) < ROOM_MARGIN + room:
        raise ValueError(
            f"{m.where}: {family} needs {ROOM_MARGIN + room} m of room at both ends of its corridor"
        )
    return c.at(-ROOM_MARGIN), c.at(c.length + ROOM_MARGIN)


def _sides(rng: np.random.Generator, n: int, low: float, high: float) -> np.ndarray:
    """(n,) lateral offsets on alternate sides (+, -, +, ...), magnitudes uniform in [low, high], m."""
    return np.where(np.arange(n) % 2 == 0, 1.0, -1.0) * rng.uniform(low, high, size=n)


def _spread(rng: np.random.Generator, n: int, low: float, high: float) -> np.ndarray:
    """(n,) positions in [low, high], one in the middle half of each of n equal slots (no two
    nearer than half a slot), m."""
    slot = (high - low) / max(n, 1)
    return low + slot * (np.arange(n) + rng.uniform(0.25, 0.75, size=n))


class FrontalApproach(SuiteFamily):
    """(a) One person walks head-on towards the robot along the corridor."""

    name = "frontal_approach"
    map_name = "hallway"
    description = "a person starts 8-12 m ahead in the corridor and walks head-on towards the robot"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot through the corridor; the person 8-12 m ahead of it at 0.9-1.3 m/s, on a
        straight line along the corridor to the far side of the room behind the robot's start,
        where it stays."""
        c = corridor(m)
        start, goal = _hallway_robot(c, m, self.name)
        ahead, t = rng.uniform(8.0, 12.0), rng.uniform(-0.4, 0.4)
        person = c.at(-ROOM_MARGIN + ahead, t)[None]
        end = c.at(-c.back + 1.0, t)[None]
        _check_clear(m, np.concatenate((person, end)), "the oncoming person", self.name)
        return Layout(start, goal, person, end, rng.uniform(0.9, 1.3, size=1), human_stop=end)


class PedestrianObstruction(SuiteFamily):
    """(b) One person stands in the corridor ahead of the robot, in its way, then walks on."""

    name = "pedestrian_obstruction"
    map_name = "hallway"
    description = "a person stands in the corridor ahead in the robot's way for 10-20 s, then walks on"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot through the corridor; the person stands on the robot's line 5-9 m ahead of it
        until 10-20 s, then walks on the robot's way, straight to the far side of the room beyond
        the corridor, 0.5-1 m to one side of the robot's line."""
        c = corridor(m)
        start, goal = _hallway_robot(c, m, self.name)
        s_stop = -ROOM_MARGIN + rng.uniform(5.0, 9.0)
        # It stands on its point from the start (its route begins at its stop).
        stop = c.at(s_stop, rng.uniform(-0.2, 0.2))[None]
        end = c.at(c.length + c.ahead - 1.0, rng.choice((-1.0, 1.0)) * rng.uniform(0.5, 1.0, size=1))
        _check_clear(m, np.concatenate((stop, end)), "the standing person", self.name)
        return Layout(
            start,
            goal,
            stop,
            end,
            _speeds(rng, 1),
            human_stop=stop,
            script={"release": rng.uniform(10.0, 20.0, size=1)},
        )


class PedestrianOvertaking(SuiteFamily):
    """(c) A fast walker starts behind the robot and overtakes it along the corridor."""

    name = "pedestrian_overtaking"
    map_name = "hallway"
    description = "a fast person (2.0-2.4 m/s) starts 3-5 m behind the robot and overtakes it"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot from before the corridor into the far room, to a point off the corridor's
        axis 2.5 m short of the far wall; the person 3-5 m behind it at 2.0-2.4 m/s, on a straight
        line along the corridor to the far wall, on the other side, where it stays.

        The speeds are above design.md's 1.8-2.2 m/s: in the 2 m corridor the walls and the robot
        slow a walker by 0.1-0.2 m/s, and one at under 1.95 m/s does not draw past GoAlone's 1.5 m/s
        within the hallway's 22 m.
        """
        c = corridor(m)
        start, _ = _hallway_robot(c, m, self.name)
        side = rng.choice((-1.0, 1.0))
        goal = c.at(c.length + c.ahead - 2.5, side * min(2.5, c.half_width + 1.5))
        behind = rng.uniform(3.0, 5.0)
        t = -side * rng.uniform(0.3, 0.5)
        person = c.at(-ROOM_MARGIN - behind, t)
        end = c.at(c.length + c.ahead - 1.0, t)
        _check_clear(m, np.stack((goal, person, end)), "the overtaking person", self.name)
        return Layout(
            start, goal, person[None], end[None], rng.uniform(2.0, 2.4, size=1), human_stop=end[None]
        )

    def make(self, seed: int, num_robots: int = 1, m: Map | None = None) -> Scenario:
        """LayoutFamily.make, the robot facing along the corridor (make faces it along its route's
        first leg, here the step of a few millimetres onto the navigation graph)."""
        from socialzoo.maps.map_file import load_map

        m = load_map(self.map_name) if m is None else m
        scenario = super().make(seed, num_robots, m)
        u = corridor(m).u
        heading = math.atan2(float(u[1]), float(u[0]))
        starts, goals = scenario.robot_starts.copy(), scenario.robot_goals.copy()
        starts[:, 2] = goals[:, 2] = heading
        return dataclasses.replace(scenario, robot_starts=starts, robot_goals=goals)


class RobotOvertaking(Overtaking, SuiteFamily):
    """(d) A slow person walks ahead of the robot, the same way: the `overtaking` family's layout."""

    name = "robot_overtaking"
    map_name = "hallway"
    description = "a slow person (0.4-0.6 m/s) walks 2-3 m ahead of the robot, the same way"


class DownPath(SuiteFamily):
    """(e) A few people walk the corridor both ways: some towards the robot, some its way."""

    name = "down_path"
    map_name = "hallway"
    description = "2-4 people walk the corridor, at least one towards the robot and one its way"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot through the corridor; 2-4 people in it, the first oncoming, the second the
        robot's way, the rest either. Each way keeps a lane on one side of the robot's line (two
        abreast would fill the corridor): people walk a straight line along it out of the corridor
        to the room's far side beyond the robot's start or goal, where they stay. Oncoming ones
        start in the corridor's far half, the others 2.3-4.8 m ahead of the robot (more with
        three), spread along their lane."""
        c = corridor(m)
        start, goal = _hallway_robot(c, m, self.name, room=3.0)
        n = int(rng.integers(2, 4, endpoint=True))
        oncoming = np.concatenate(([True, False], rng.random(n - 2) < 0.5))
        lane = rng.choice((-1.0, 1.0))  # the side of the robot's line its way's walkers keep
        s, s_end = np.empty(n), np.empty(n)
        for towards in (True, False):
            group = oncoming == towards
            k = int(group.sum())
            j = np.arange(k)
            if towards:
                s[group] = _spread(rng, k, 0.5 * c.length, c.length - 0.5)
                s_end[group] = -c.back + 1.0 + 0.8 * j + rng.uniform(0.0, 0.3, size=k)
            else:
                # Near enough for the robot to catch up with them.
                s[group] = _spread(rng, k, 0.3, 0.3 + max(2.5, 1.2 * k))
                s_end[group] = c.length + c.ahead - 1.0 - 0.8 * j - rng.uniform(0.0, 0.3, size=k)
        t = np.where(oncoming, -lane, lane) * rng.uniform(0.3, 0.5, size=n)
        people, ends = c.at(s, t), c.at(s_end, t)
        _check_clear(m, np.concatenate((people, ends)), "its walkers", self.name)
        return Layout(start, goal, people, ends, _speeds(rng, n), human_stop=ends)


@dataclass(frozen=True)
class Crossroads:
    """Where the map's main way (the robot's, between its farthest legal poses) crosses the way
    most square to it (the people's, `_cross_pair`).

    Attributes:
        centre: (2,) where the two ways' axes cross, world frame, m.
        robot_start, robot_goal: (2,) the robot's way's ends (its farthest legal poses), m.
        ends: (2, 2) the crossing way's ends, m.
        half_width: half the robot's way's width, m.
        cross_half_width: half the crossing way's width, m.
    """

    centre: np.ndarray
    robot_start: np.ndarray
    robot_goal: np.ndarray
    ends: np.ndarray
    half_width: float
    cross_half_width: float

    @property
    def u(self) -> np.ndarray:
        """(2,) the unit vector along the robot's way, start to goal."""
        return _unit(self.robot_goal - self.robot_start)


def crossroads(m: Map) -> Crossroads:
    """The crossing of map m's main way with the way most square to it.

    Raises:
        ValueError: the two ways' axes do not cross between their ends (naming the map).
    """
    from socialzoo.maps.segments import segments_free
    from socialzoo.scenarios.families import _cross_pair

    a, b = _farthest_pair(m)
    c, d = _cross_pair(m, a, b)
    # a + p (b - a) = c + q (d - c): the axes' crossing, inside both ways.
    lhs = np.stack((b - a, c - d), axis=1)
    if abs(float(np.linalg.det(lhs))) < 1e-9:
        raise ValueError(f"{m.where}: no crossing ways (its two longest ways are parallel)")
    p, q = np.linalg.solve(lhs, c - a)
    centre = a + p * (b - a)
    ends = np.stack((a, b, c, d))
    open_arms = segments_free(m.wall_index, np.broadcast_to(centre, ends.shape), ends)
    if not (0.15 < p < 0.85 and 0.15 < q < 0.85 and open_arms.all()):
        raise ValueError(
            f"{m.where}: no crossing ways (the lines between its farthest poses and between the poses "
            "most square to them do not cross in the open)"
        )

    def half_width(end: np.ndarray) -> float:
        mid = (centre + end) / 2.0
        side = _left(_unit(end - centre))
        return float(_ray(m, mid, side) + _ray(m, mid, -side)) / 2.0

    return Crossroads(
        centre=centre,
        robot_start=a,
        robot_goal=b,
        ends=np.stack((c, d)),
        half_width=half_width(a),
        cross_half_width=half_width(c),
    )


def _crosser(
    x: Crossroads, rng: np.random.Generator, before: float, lateral: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """One person on the crossing way, from a random end: (walking direction (2,), the point
    `before` m ahead of the centre on its way with `lateral` to its left, its goal at the other
    end with the same offset, the room its end gives it before that point, m)."""
    side = int(rng.integers(0, 2))
    origin, far = x.ends[side], x.ends[1 - side]
    e = _unit(x.centre - origin)
    offset = lateral * _left(e)
    room = float(np.linalg.norm(x.centre - origin)) - before
    return e, x.centre - before * e + offset, far + offset, room


class IntersectionNoGesture(SuiteFamily):
    """(f) People cross the robot's way at an intersection, timed to reach the centre with it."""

    name = "intersection_no_gesture"
    map_name = "intersection"
    description = "1-2 people cross the robot's way at an intersection, timed to meet it at the centre"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot along the main way; 1-2 people along the crossing way from either end, each
        starting where it reaches the centre when the robot does (give or take 0.5 s), to the
        other end, where it stays."""
        x = crossroads(m)
        cruise, lag = nominal_timing()
        meet = float(np.linalg.norm(x.centre - x.robot_start)) / cruise
        n = int(rng.integers(1, 2, endpoint=True))
        speed = _speeds(rng, n)
        lateral = _sides(rng, n, 0.3, 0.55)
        starts, ends = np.empty((n, 2)), np.empty((n, 2))
        for k in range(n):
            wanted = speed[k] * (meet - lag + rng.uniform(-0.5, 0.5))
            e, at_centre, ends[k], room = _crosser(x, rng, 0.0, lateral[k])
            starts[k] = at_centre - float(np.clip(wanted, x.half_width + 1.0, room - 0.5)) * e
        _check_clear(m, np.concatenate((starts, ends)), "its crossing people", self.name)
        return Layout(x.robot_start, x.robot_goal, starts, ends, speed, human_stop=ends)


def _signaller(
    family: SuiteFamily, m: Map, rng: np.random.Generator, robot_left: tuple[float, float]
) -> tuple[Crossroads, Layout, float]:
    """The gesture families' layout (g, h): one person along the crossing way stops STOP_BEFORE m
    before the robot's way, arriving when the robot is `robot_left` (uniform range) m from the
    centre, then crosses to the other end. Returns (the crossroads, the layout without its script,
    the time the person stands at its stop, nominally, s)."""
    x = crossroads(m)
    cruise, lag = nominal_timing()
    to_centre = float(np.linalg.norm(x.centre - x.robot_start))
    arrive = max(to_centre - rng.uniform(*robot_left), 0.0) / cruise
    speed = _speeds(rng, 1)
    v = float(speed[0])
    before = x.half_width + STOP_BEFORE
    e, stop, end, room = _crosser(x, rng, before, rng.uniform(-0.2, 0.2))
    # A waiting person slows over the last SLOW_DISTANCE to its stop (its speed in proportion to the
    # distance left) and stands within STOP_RADIUS of it: that stretch takes log(SLOW / STOP) / v.
    settle = math.log(SLOW_DISTANCE / STOP_RADIUS) / v
    walk = float(np.clip(SLOW_DISTANCE + v * (arrive - lag - settle), SLOW_DISTANCE, room - 0.5))
    start = stop - walk * e
    _check_clear(m, np.stack((start, stop, end)), "the signalling person", family.name)
    layout = Layout(x.robot_start, x.robot_goal, start[None], end[None], speed, human_stop=stop[None])
    return x, layout, lag + (walk - SLOW_DISTANCE) / v + settle


class IntersectionWait(SuiteFamily):
    """(g) A person stops before the crossing, signals the robot to wait, then crosses first."""

    name = "intersection_wait"
    map_name = "intersection"
    description = "a person stops 1.2 m before the crossing, signals 'wait' for 2-4 s, then crosses first"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot along the main way; the person along the crossing way stops 1.2 m before the
        robot's way as the robot comes within 4-6 m of the centre, signals WAIT, and walks on 2-4 s
        after reaching its stop (the script's `wait`)."""
        _, lay, _ = _signaller(self, m, rng, (4.0, 6.0))
        wait = rng.uniform(2.0, 4.0, size=1)
        return dataclasses.replace(lay, script={"wait": wait, "gesture": np.array([WAIT])})


class IntersectionProceed(SuiteFamily):
    """(h) A person stops before the crossing, signals the robot to go first, and crosses after it."""

    name = "intersection_proceed"
    map_name = "intersection"
    description = "a person stops before the crossing, signals 'proceed', and crosses once the robot is past"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot along the main way; the person along the crossing way stops 1.2 m before the
        robot's way as the robot comes within 5-7 m of the centre, signals PROCEED, and walks on
        once the robot is past the crossing (the gate: GATE_PAST m beyond the crossing way's far
        edge, facing the robot's way) or at 30 s."""
        x, lay, _ = _signaller(self, m, rng, (5.0, 7.0))
        line = x.centre + (x.cross_half_width + GATE_PAST) * x.u
        gate = np.array([[*line, *x.u]])
        return dataclasses.replace(
            lay, script={"release": np.array([30.0]), "gate": gate, "gesture": np.array([PROCEED])}
        )


class NarrowDoorway(SuiteFamily):
    """(k) One person comes through the door the other way, timed to reach it with the robot."""

    name = "narrow_doorway"
    map_name = "doorway"
    description = "a person comes through the door the other way, timed to reach it when the robot does"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot between the map's farthest poses, through the door nearest its route (the
        `doorway` family's way); one person on the far side of the door, where it reaches the door
        when the robot does (give or take 0.5 s), to near the robot's start, where it stays."""
        if m.num_doors == 0:
            raise ValueError(f"{m.where}: {self.name} needs a door (the map lists none)")
        a, b = _farthest_pair(m)
        route = planned_route(m, a, b, f"{m.where}, family {self.name!r}")
        doors = np.asarray(m.doors, dtype=np.float64)
        mids = (doors[:, :2] + doors[:, 2:]) / 2.0
        k = int(np.argmin([_nearest_on(route, q)[0] for q in mids]))
        q, along_door = mids[k], _unit(doors[k, 2:] - doors[k, :2])
        normal = _left(along_door)
        normal = normal if float((b - q) @ normal) > 0 else -normal
        cruise, lag = nominal_timing()
        meet = _nearest_on(route, q)[1] / cruise
        speed = _speeds(rng, 1)
        room = float(_ray(m, q, normal))
        wanted = speed[0] * (meet - lag + rng.uniform(-0.5, 0.5))
        half_door = float(np.linalg.norm(doors[k, 2:] - doors[k, :2])) / 2.0
        person = q + float(np.clip(wanted, 1.5, room - 0.6)) * normal
        person = person + rng.uniform(-0.5, 0.5) * half_door * along_door
        u = _unit(b - a)
        end = _near(m, rng, a, 1, (0.5, 1.5), (-0.8, 0.8), u)
        _check_clear(m, np.concatenate((person[None], end)), "the person at the door", self.name)
        return Layout(a, b, person[None], end, speed, human_stop=end)


class ParallelFlow(ParallelTraffic, SuiteFamily):
    """(v) People walk the robot's way at mixed speeds: the `parallel_traffic` family's layout."""

    name = "parallel_flow"
    map_name = "hallway"
    description = "4-8 people walk the robot's way along the corridor at mixed speeds"


class CircularCrossing(CircleCrossing, SuiteFamily):
    """(x) The robot and people on a circle walk to its opposite points: `circle_crossing`'s layout."""

    name = "circular_crossing"
    map_name = "open_room"
    description = "the robot and 4-8 people on a circle each walk to the opposite point"
