"""The suite's scenarios at places (Francis et al. Fig. 7 i, j, l-o): a blind corner, a narrow hallway, entering and
leaving a room and an elevator, each one family, with what they read of their map: its door, corner, narrow stretch."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.scenarios.families import (
    Layout,
    SuiteFamily,
    _farthest_pair,
    _frame,
    _near,
    _speeds,
    nominal_timing,
    planned_route,
)
from socialzoo.scenarios.placement import ROBOT_LAG, arc_lengths, clear_of_walls, draw_spots, point_at

if TYPE_CHECKING:
    from socialzoo.maps.map_file import Map
    from socialzoo.scenarios.scenario import Scenario

# A person leaving a room as the robot enters it is timed to pass the door this much earlier, s.
LEAVE_FIRST = 1.5
# A person leaving a room walks straight out of its door to this far in front of it, m.
OUT_OF_DOOR = 1.6
# People walk through a doorway at about this fraction of their preferred speed (the walls' force).
DOORWAY_PACE = 0.6


@dataclass(frozen=True)
class Door:
    """A map's door as the families use it: a frame at its centre and the room behind it.

    Attributes:
        segment: (4,) x1, y1, x2, y2, m.
        centre: (2,) its middle, m.
        along: (2,) unit vector along the door.
        inward: (2,) unit normal pointing into the room (the side with fewer legal poses).
        inside: (along_min, along_max, depth_max) the room's extent in the door's frame: the walls
            whose ends lie behind the door, m.
    """

    segment: np.ndarray
    centre: np.ndarray
    along: np.ndarray
    inward: np.ndarray
    inside: tuple[float, float, float]

    @property
    def half_width(self) -> float:
        """Half the opening, m."""
        return 0.5 * float(np.linalg.norm(self.segment[2:] - self.segment[:2]))

    def point(self, along: float | np.ndarray, depth: float | np.ndarray) -> np.ndarray:
        """World points at (along, depth) in the door's frame (depth > 0: inside), (..., 2)."""
        a, d = np.asarray(along, dtype=np.float64), np.asarray(depth, dtype=np.float64)
        return self.centre + a[..., None] * self.along + d[..., None] * self.inward

    def frame(self, points: np.ndarray) -> np.ndarray:
        """(..., 2) (along, depth) of world points (..., 2) in the door's frame."""
        rel = np.asarray(points, dtype=np.float64) - self.centre
        return np.stack((rel @ self.along, rel @ self.inward), axis=-1)


def map_door(m: Map, who: str) -> Door:
    """The map's first door and the room behind it.

    Raises:
        ValueError: the map has no door, no legal pose on one of its sides, or no walls behind it.
    """
    if m.num_doors == 0:
        raise ValueError(f"{m.where}: family {who!r} needs a door (Map.doors); the map has none")
    segment = np.asarray(m.doors[0], dtype=np.float64)
    centre = (segment[:2] + segment[2:]) / 2.0
    along, normal = _frame(segment[:2], segment[2:])
    poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)[:, :2]
    side = (poses - centre) @ normal
    front, back = int((side > 0).sum()), int((side < 0).sum())
    if not (front and back):
        raise ValueError(f"{m.where}: family {who!r} needs legal poses on both sides of its door")
    inward = normal if front < back else -normal
    ends = np.asarray(m.walls, dtype=np.float64).reshape(-1, 2)
    rel = ends - centre
    depth, offset = rel @ inward, rel @ along
    behind = depth > 0.05
    if not behind.any():
        raise ValueError(f"{m.where}: family {who!r} finds no walls behind its door (no room)")
    inside = (float(offset[behind].min()), float(offset[behind].max()), float(depth[behind].max()))
    return Door(segment, centre, along, inward, inside)


def _sides(m: Map, door: Door) -> tuple[np.ndarray, np.ndarray]:
    """The legal poses' positions outside and inside the door's room, (k, 2) each."""
    poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)[:, :2]
    depth = door.frame(poses)[:, 1]
    return poses[depth < 0.0], poses[depth > 0.0]


def _through_door(
    m: Map, door: Door, start: np.ndarray, goal: np.ndarray, who: str
) -> tuple[np.ndarray, float]:
    """(the robot's route from start to goal, the distance along it to where it first crosses the
    door's line), m.

    Raises:
        ValueError: the route does not pass the door.
    """
    path = planned_route(m, start, goal, f"{m.where}, family {who!r}")
    side = (path - door.centre) @ door.inward
    arc = arc_lengths(path)
    for k in range(len(path) - 1):
        if side[k] * side[k + 1] <= 0.0 and side[k] != side[k + 1]:
            return path, float(arc[k] + (arc[k + 1] - arc[k]) * side[k] / (side[k] - side[k + 1]))
    raise ValueError(f"{m.where}: family {who!r}: the robot's route does not pass the door")


def _pick(rng: np.random.Generator, points: np.ndarray, keep: np.ndarray, what: str, m: Map) -> np.ndarray:
    """One of the points where keep holds (all of them where it holds nowhere)."""
    if not len(points):
        raise ValueError(f"{m.where}: no legal pose for the {what}")
    choices = np.flatnonzero(keep) if keep.any() else np.arange(len(points))
    return np.asarray(points[int(rng.choice(choices))]).copy()


def _direct(m: Map, door: Door, starts: np.ndarray, goals: np.ndarray, who: str) -> np.ndarray:
    """(k,) whether the route from each start to each goal (k, 2 each) goes through the door without
    a detour: at most 1.25 times the way through the door's centre, plus 1 m."""
    from socialzoo.scenarios.generator import plan_routes

    paths, lengths = plan_routes(m, starts, goals, f"{m.where}, family {who!r}")
    walked = np.array([arc_lengths(p[:k])[-1] for p, k in zip(paths, lengths, strict=True)])
    through = np.linalg.norm(starts - door.centre, axis=1) + np.linalg.norm(goals - door.centre, axis=1)
    return np.asarray(walked <= 1.25 * through + 1.0)


def _sharpest_turn(path: np.ndarray) -> tuple[int, float]:
    """(index, angle in rad) of the path's inner point where it turns most."""
    best, angle = -1, 0.0
    for k in range(1, len(path) - 1):
        u, v = path[k] - path[k - 1], path[k + 1] - path[k]
        nu, nv = float(np.linalg.norm(u)), float(np.linalg.norm(v))
        if nu < 1e-6 or nv < 1e-6:
            continue
        turn = math.acos(float(np.clip(u @ v / (nu * nv), -1.0, 1.0)))
        if turn > angle:
            best, angle = k, turn
    return best, angle


def _narrow_section(m: Map, path: np.ndarray, who: str) -> tuple[float, float]:
    """(start, end) distances along the path of its narrowest stretch: the longest run of points
    within 0.15 m of the path's least wall distance (its ends' first metre left out).

    Raises:
        ValueError: the path keeps more than 0.9 m from the walls everywhere (no passage narrower
            than 1.8 m), or the narrow stretch is shorter than 2 m.
    """
    arc = arc_lengths(path)
    s = np.arange(1.0, arc[-1] - 1.0, 0.1)
    points = np.array([point_at(path, float(x))[0] for x in s]).reshape(-1, 2)
    _, dist = m.wall_index.nearest(points) if m.num_walls else (None, np.full(len(s), np.inf))
    least = float(np.min(dist)) if len(s) else math.inf
    if least > 0.9:
        raise ValueError(f"{m.where}: family {who!r} needs a passage narrower than 1.8 m on its route")
    narrow = np.concatenate(([False], dist <= least + 0.15, [False]))
    edges = np.flatnonzero(np.diff(narrow.astype(np.int8)))
    starts, ends = edges[::2], edges[1::2]
    k = int(np.argmax(ends - starts))
    s0, s1 = float(s[starts[k]]), float(s[ends[k] - 1])
    if s1 - s0 < 2.0:
        raise ValueError(f"{m.where}: family {who!r}: the narrow passage is only {s1 - s0:.1f} m long")
    return s0, s1


class BlindCorner(SuiteFamily):
    """(i) The robot turns a blind corner as a person comes round it the other way.

    The robot goes between the ends of the L-shaped corridor (the map's farthest legal poses,
    either way); the corner is the sharpest turn of its route. The person walks from the other leg
    to near the robot's start, starting as far from the corner as it walks in the time the robot
    takes to reach it (GoAlone's cruise speed), so they meet at the corner.

    On the corner map (2 m corridor, solid inner corner) the walls hide the person until they are
    close: with GoAlone the robot first sees the person (core.see(), the action-selection task's
    sight lines) 2.55-2.7 m away (test seeds 100-159), the robot 1.3-1.6 m before the corner and the
    person about 2 m round it, a second after they were still 4.0-4.4 m apart
    (tests/scenarios/test_suite_places.py measures it).
    """

    name = "blind_corner"
    map_name = "corner"
    description = "a person comes round a blind corner as the robot turns it, the other way"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot end to end of the L; one person from the other leg, timed to meet at the corner."""
        a, b = _farthest_pair(m)
        if rng.random() < 0.5:
            a, b = b, a
        path = planned_route(m, a, b, f"{m.where}, family {self.name!r}")
        k, turn = _sharpest_turn(path)
        if turn < math.radians(45.0):
            raise ValueError(f"{m.where}: family {self.name!r} needs a corner on the route between its ends")
        arc = arc_lengths(path)
        speed = _speeds(rng, 1)
        cruise, lag = nominal_timing()
        ahead = speed[0] * (arc[k] / cruise + ROBOT_LAG - lag)
        ahead = float(np.clip(ahead, 1.0, arc[-1] - arc[k] - 0.5))
        spawn, u = point_at(path, arc[k] + ahead)
        start = _near(m, rng, spawn, 1, (0.0, 0.0), (-0.3, 0.3), u)
        goal = _near(m, rng, a, 1, (0.0, 0.0), (-0.3, 0.3), path[1] - path[0])
        return Layout(a, b, start, goal, speed)


class NarrowHallway(SuiteFamily):
    """(j) The robot drives through a narrow corridor as a person comes through it the other way.

    The robot goes between the map's farthest legal poses (either way); the narrow corridor is the
    narrowest stretch of its route (`_narrow_section`). The meeting point is drawn in the middle half
    of that stretch, and the person starts beyond it on the robot's route as far as it walks in the
    time the robot takes to get there; it walks to near the robot's start.
    """

    name = "narrow_hallway"
    map_name = "narrow_hallway"
    description = "a person comes the other way through a narrow corridor, meeting the robot inside"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot end to end through the passage; one person the other way, timed to meet in it."""
        a, b = _farthest_pair(m)
        if rng.random() < 0.5:
            a, b = b, a
        path = planned_route(m, a, b, f"{m.where}, family {self.name!r}")
        s0, s1 = _narrow_section(m, path, self.name)
        arc = arc_lengths(path)
        meet = (s0 + s1) / 2.0 + rng.uniform(-0.25, 0.25) * (s1 - s0)
        speed = _speeds(rng, 1)
        cruise, lag = nominal_timing()
        ahead = speed[0] * (meet / cruise + ROBOT_LAG - lag)
        spawn, _ = point_at(path, min(meet + ahead, arc[-1] - 0.3))
        start = spawn[None] if meet + ahead < s1 else _near(m, rng, spawn, 1, (0.0, 0.0), (-0.3, 0.3), b - a)
        goal = _near(m, rng, a, 1, (0.0, 0.0), (-0.3, 0.3), b - a)
        return Layout(a, b, start, goal, speed)


class EnteringRoom(SuiteFamily):
    """(l) The robot enters a room through its door as a person leaves it; 0-2 stand in the room.

    The robot goes from a legal pose outside, 3-9 m from the door (the map's first door; the room
    is the side with fewer legal poses), to a legal pose inside at least 1.5 m from it, by a route
    through the door without a detour (`_direct`: a navigation graph may lead round). The leaving
    person stands in line with the door 1.5 m or more inside, no deeper than it walks in the robot's
    time to the door, and walks out once the robot is past a gate line on the robot's route, placed
    so that it reaches the door LEAVE_FIRST before the robot at GoAlone's speed (at once if the
    robot starts too close for that; 10 s after GoAlone would pass the gate if the robot never
    does). It walks straight out (see `make`) to a legal pose outside at least 4 m from the door on
    the side away from the robot's start, and stays there (Script.stay). 0-2 more people stand in the room
    for good (stop at their start, never released), 1.2 m from the robot's goal and the leaver's way.
    """

    name = "entering_room"
    map_name = "room"
    description = "the robot enters a room as a person leaves it through the door; 0-2 stand inside"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot outside -> inside; the leaver released by the robot's approach; the standers."""
        door = map_door(m, self.name)
        outside, inside = _sides(m, door)
        out_dist = np.linalg.norm(outside - door.centre, axis=1)
        in_dist = np.linalg.norm(inside - door.centre, axis=1)
        robot_goal = _pick(rng, inside, in_dist >= 1.5, "robot's goal inside", m)
        direct = _direct(m, door, outside, np.broadcast_to(robot_goal, outside.shape), self.name)
        near = (out_dist >= 3.0) & (out_dist <= 9.0)
        robot_start = _pick(rng, outside, near & direct, "robot's start outside", m)
        path, s_door = _through_door(m, door, robot_start, robot_goal, self.name)
        cruise, lag = nominal_timing()
        speed = _speeds(rng, 1)
        lo, hi, deep = door.inside
        reach = speed[0] * (s_door / cruise + ROBOT_LAG - lag - LEAVE_FIRST)
        # The leaver stands behind the door, facing it (it walks straight out: see `make`).
        width = max(door.half_width - 0.3, 0.0)
        depth = (1.5, float(np.clip(reach, 1.6, deep - 0.6)))
        found = draw_spots(
            m, rng, 1, lambda: door.point(rng.uniform(-width, width), rng.uniform(*depth)), robot_goal, 1.2
        )
        leaver = found[0] if len(found) else door.point(0.0, 1.5)
        away = -1.0 if door.frame(robot_start)[0] > 0.0 else 1.0
        along = door.frame(outside)[:, 0] * away
        leave_goal = _pick(rng, outside, (along > 0.0) & (out_dist >= 4.0), "leaver's goal outside", m)
        # The leaver reaches the door d / v + lag after its release; the robot, past the gate,
        # covers the rest of its route to the door in that time at its cruise speed.
        to_door = float(np.linalg.norm(leaver - door.centre))
        s_gate = s_door - cruise * (to_door / speed[0] + lag + LEAVE_FIRST)
        gate = np.full((1, 4), np.nan)
        release = np.zeros(1)
        if s_gate > 0.3:
            where, u = point_at(path, s_gate)
            gate[0] = [*where, *u]
            release[0] = s_gate / cruise + ROBOT_LAG + 10.0
        num_standing = int(rng.integers(0, 2, endpoint=True))
        lane = np.linspace(leaver, door.centre, 6)
        standing = draw_spots(
            m,
            rng,
            num_standing,
            lambda: door.point(rng.uniform(lo + 0.5, hi - 0.5), rng.uniform(1.5, deep - 0.5)),
            np.vstack((robot_goal, lane)),
            1.2,
        )
        starts = np.vstack((leaver, standing))
        n = len(starts)
        return Layout(
            robot_start,
            robot_goal,
            starts,
            np.vstack((leave_goal, standing)),
            np.concatenate((speed, _speeds(rng, n - 1))),
            human_stop=starts.copy(),
            script={
                "release": np.concatenate((release, np.full(n - 1, np.inf))),
                "gate": np.vstack((gate, np.full((n - 1, 4), np.nan))),
                "stay": np.ones(n, dtype=bool),  # the leaver stays out in the corridor
            },
        )

    def make(self, seed: int, num_robots: int = 1, m: Map | None = None) -> Scenario:
        """The layout's scenario, the leaver's route replaced by a straight walk out of the door to
        a point in front of it, then to its goal.

        People cut their route's corners by their waypoint radius (1 m): a route through a graph node
        close to the door (the room map's is 0.28 m outside it) turns before the person is through
        and presses it against the wall beside the door, and a diagonal line through a 1.2 m door
        does the same.
        """
        from socialzoo.maps.map_file import load_map
        from socialzoo.maps.segments import segments_free

        m = load_map(self.map_name) if m is None else m
        scenario = super().make(seed, num_robots, m)
        door = map_door(m, self.name)
        start, goal = scenario.human_spawn[0], scenario.human_routes[0][-1]
        outside, _ = _sides(m, door)
        front = min(OUT_OF_DOOR, 0.9 * float(-door.frame(outside)[:, 1].min()))
        via = door.point(door.frame(start)[0], -front)
        if not segments_free(m.wall_index, np.array([start, via]), np.array([via, goal])).all():
            return scenario
        routes = (np.array([start, via, goal]), *scenario.human_routes[1:])
        return dataclasses.replace(scenario, human_routes=routes)


class ExitingRoom(SuiteFamily):
    """(m) The robot leaves a room through its door into a corridor where 1-3 people walk past.

    The robot goes from a legal pose inside the room (the side of the map's first door with fewer
    legal poses) to one outside at least 3 m from the door, by a route through the door without a
    detour (`_direct`). Each person walks along the corridor past the door (either way, at a depth
    within the outside legal poses'), starting as far along it as it walks in the time the robot
    takes to the door: the first is timed to pass the door with the robot, the others up to 4 s
    earlier or later. They walk to the corridor's end (as far as its legal poses go) and back.
    """

    name = "exiting_room"
    map_name = "room"
    description = "the robot leaves a room through its door as 1-3 people walk past it outside"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot inside -> outside; 1-3 corridor walkers timed around the robot's exit."""
        door = map_door(m, self.name)
        outside, inside = _sides(m, door)
        robot_start = _pick(rng, inside, np.ones(len(inside), dtype=bool), "robot's start inside", m)
        out_dist = np.linalg.norm(outside - door.centre, axis=1)
        direct = _direct(m, door, np.broadcast_to(robot_start, outside.shape), outside, self.name)
        robot_goal = _pick(rng, outside, (out_dist >= 3.0) & direct, "robot's goal outside", m)
        _, s_door = _through_door(m, door, robot_start, robot_goal, self.name)
        cruise, lag = nominal_timing()
        t_door = s_door / cruise + ROBOT_LAG
        corridor = door.frame(outside)
        left, right = float(corridor[:, 0].min()), float(corridor[:, 0].max())
        shallow, deep = float(corridor[:, 1].max()), float(corridor[:, 1].min())
        n = int(rng.integers(1, 3, endpoint=True))
        speed = _speeds(rng, n)
        way = np.where(rng.random(n) < 0.5, 1.0, -1.0)
        when = t_door + np.concatenate(([0.0], rng.uniform(-4.0, 4.0, n - 1)))
        depth = rng.uniform(deep, shallow, n)
        # A walker going way = +1 starts at along = -distance and ends at the corridor's right end.
        distance = np.clip(speed * (when - lag), 0.5, np.where(way > 0, -left, right))
        starts = door.point(-way * distance, depth)
        goals = door.point(np.where(way > 0, right, left), depth)
        bad = ~clear_of_walls(m, starts)
        starts[bad] = door.point(-way[bad] * np.minimum(distance[bad], 1.0), 0.5 * (deep + shallow))
        return Layout(robot_start, robot_goal, starts, goals, speed)


def _car(m: Map, door: Door, who: str) -> tuple[np.ndarray, np.ndarray]:
    """The car's spots behind the door, 0.45 m inside its walls: (its back row (3, 2): the left
    corner, the middle, the right corner (along the door); its centre (2,)).

    Raises:
        ValueError: the car is smaller than 1.6 x 1.6 m or a spot is too close to a wall.
    """
    lo, hi, deep = door.inside
    if hi - lo < 1.6 or deep < 1.6:
        raise ValueError(f"{m.where}: family {who!r}: the room behind the door is too small for a car")
    back = door.point(np.array([lo + 0.45, (lo + hi) / 2.0, hi - 0.45]), np.full(3, deep - 0.45))
    centre = door.point((lo + hi) / 2.0, deep / 2.0)
    if not clear_of_walls(m, np.vstack((back, centre[None])), 0.35).all():
        raise ValueError(f"{m.where}: family {who!r}: the car behind the door has no room for its spots")
    return back, centre


def _door_times(rng: np.random.Generator, door: Door) -> tuple[float, np.ndarray]:
    """(t_open, the script's doors (1, 6)): the door opens at 3-6 s and stays open 15-25 s."""
    t_open = float(rng.uniform(3.0, 6.0))
    t_close = t_open + float(rng.uniform(15.0, 25.0))
    return t_open, np.array([[*door.segment, t_open, t_close]])


class EnteringElevator(SuiteFamily):
    """(n) The robot waits in the lobby for an elevator: the doors open, the people in the car come
    out, people in the lobby go in, and the robot must get in while the doors are open.

    The door (the map's first; the car is the side with fewer legal poses) is closed until t_open
    (3-6 s) and open for 15-25 s. The robot starts beside it in the lobby (1.2-2 m to one side,
    1-1.6 m out) and goes to the car's centre. 1-2 people wait at the back of the car (in line with
    the door's edges) and walk out to the lobby's sides at t_open (the second 1-2 s later); 0-2 wait
    in the lobby 1.6-3 m to the door's sides and walk into the car's back corners 3-4 s after t_open,
    or later: so as to reach the door a second after the last one leaving is 1 m out of it (at
    DOORWAY_PACE of their speeds). Everyone stays at the end of their route (Script.stay): those
    leaving in the lobby, those entering in the car.
    """

    name = "entering_elevator"
    map_name = "elevator"
    description = "the robot enters an elevator once its doors open and the people in it are out"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot lobby -> car; leavers held in the car until t_open, enterers held until after."""
        door = map_door(m, self.name)
        back, centre = _car(m, door, self.name)
        # Those leaving start at the back corners drawn in line with the door: a person walking out
        # at a slant sticks on the door's edge.
        span = door.half_width - 0.15
        exits = door.point(np.clip(door.frame(back)[:, 0], -span, span), door.frame(back)[:, 1])
        outside, _ = _sides(m, door)
        lobby = door.frame(outside)[:, 0]
        t_open, doors = _door_times(rng, door)
        # The robot waits beside the door, clear of the way in and out along the door's axis.
        side = 1.0 if rng.random() < 0.5 else -1.0
        robot_start = draw_spots(
            m,
            rng,
            1,
            lambda: door.point(side * rng.uniform(1.2, 2.0), -rng.uniform(1.0, 1.6)),
            centre[None],
            1.0,
        )
        if not len(robot_start):
            raise ValueError(f"{m.where}: family {self.name!r}: no room beside the door")
        num_out = int(rng.integers(1, 2, endpoint=True))
        num_in = int(rng.integers(0, 2, endpoint=True))
        out_side = rng.permutation([-1.0, 1.0])[:num_out]
        leaving = exits[np.where(out_side > 0, 2, 0)]
        reach = np.where(out_side > 0, float(lobby.max()), -float(lobby.min())) - 0.5
        leave_goal = door.point(
            out_side * rng.uniform(2.5, np.maximum(reach, 2.6)), -rng.uniform(1.0, 2.5, num_out)
        )
        # The second one leaving goes 1-2 s after the first: two abreast jam the door.
        release_out = t_open + np.concatenate(([0.0], rng.uniform(1.0, 2.0, num_out - 1)))
        speed = _speeds(rng, num_out + num_in)
        # When the last one leaving is 1 m out of the door: people slow down in a doorway (DOORWAY_PACE
        # of their speed).
        _, lag = nominal_timing()
        to_out = np.linalg.norm(leaving - door.centre, axis=1) + 1.0
        out_at = np.max(release_out + lag + to_out / (DOORWAY_PACE * speed[:num_out]))
        waiting = draw_spots(
            m,
            rng,
            num_in,
            lambda: door.point(rng.choice([-1.0, 1.0]) * rng.uniform(1.6, 3.0), -rng.uniform(0.8, 1.6)),
            robot_start,
            1.0,
        )
        num_in = len(waiting)
        # Into the back corners, the one more to the left (along the door) to the left one.
        rank = np.argsort(np.argsort(door.frame(waiting)[:, 0]))
        corner = 2 * rank if num_in == 2 else np.where(door.frame(waiting)[:, 0] > 0, 2, 0)
        speed = speed[: num_out + num_in]
        in_travel = np.linalg.norm(waiting - door.centre, axis=1) / speed[num_out:] + lag
        release_in = np.maximum(t_open + rng.uniform(3.0, 4.0, num_in), out_at + 1.0 - in_travel)
        starts = np.vstack((leaving, waiting))
        return Layout(
            robot_start[0],
            centre,
            starts,
            np.vstack((leave_goal, back[corner])),
            speed,
            human_stop=starts.copy(),
            # Those leaving stay in the lobby, those entering in the car.
            script={
                "release": np.concatenate((release_out, release_in)),
                "doors": doors,
                "stay": np.ones(len(speed), dtype=bool),
            },
        )


class ExitingElevator(SuiteFamily):
    """(o) The robot rides in an elevator's car: when the doors open it must get out into the
    lobby, where people wait to get in.

    The door (the map's first; the car is the side with fewer legal poses) is closed until t_open
    (3-6 s) and open for 15-25 s; a robot that drives at it before t_open collides with it. The robot
    starts at the car's centre and goes to a legal pose in the lobby at least 3 m from the door. 1-3
    people wait 1.2-2.2 m in front of the door, 0.7-2.2 m to its sides, and walk into the back of the
    car 2-3 s after t_open (whether or not the robot is out), and stay in it (Script.stay).
    """

    name = "exiting_elevator"
    map_name = "elevator"
    description = "the robot leaves an elevator once its doors open, as people wait to get in"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot car -> lobby; 1-3 people held in the lobby until 2-3 s after t_open."""
        door = map_door(m, self.name)
        back, centre = _car(m, door, self.name)
        outside, _ = _sides(m, door)
        out_dist = np.linalg.norm(outside - door.centre, axis=1)
        robot_goal = _pick(rng, outside, out_dist >= 3.0, "robot's goal in the lobby", m)
        t_open, doors = _door_times(rng, door)
        n = int(rng.integers(1, 3, endpoint=True))

        def spot() -> np.ndarray:
            side = 1.0 if rng.random() < 0.5 else -1.0
            return door.point(side * rng.uniform(0.7, 2.2), -rng.uniform(1.2, 2.2))

        waiting = draw_spots(m, rng, n, spot, np.vstack((robot_goal, door.point(0.0, -1.0))), 0.8)
        n = len(waiting)
        goals = back[rng.permutation(3)[:n]]
        return Layout(
            centre,
            robot_goal,
            waiting,
            goals,
            _speeds(rng, n),
            human_stop=waiting.copy(),
            script={
                "release": t_open + rng.uniform(2.0, 3.0, n),
                "doors": doors,
                "stay": np.ones(n, dtype=bool),
            },
        )
