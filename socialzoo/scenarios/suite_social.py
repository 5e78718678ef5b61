"""The suite's scenarios with people (Francis et al. Fig. 7 p-u, w, y) in an open area: joining and leaving a group,
following, leading and accompanying a person, crowds and crossing flows, people crowding round the robot."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.scenarios.families import Layout, SuiteFamily, _speeds, circle_point, interior, nominal_timing
from socialzoo.scenarios.placement import ROBOT_LAG, draw_spots
from socialzoo.scenarios.script import ACCOMPANY, FOLLOW, LEAD

if TYPE_CHECKING:
    from socialzoo.maps.map_file import Map

# The walking speeds of a person the robot follows or accompanies, m/s: a pace the suite's slowest
# robot (the CrowdNav task's, 1 m/s) can keep and still close a gap.
ESCORTED_SPEED = (0.6, 0.9)
# Standing groups: members on a circle of this radius, m (facing its centre, as a conversation
# stands; the world's people have no heading of their own, so only the circle is laid out).
GROUP_RADIUS = (0.8, 1.0)


def _segment(
    m: Map, rng: np.random.Generator, length: tuple[float, float], behind: float, margin: float, who: str
) -> tuple[np.ndarray, np.ndarray, float]:
    """(start, unit direction, length): a straight walk of a length drawn from `length` (shortened
    to what fits, at least its minimum) that, with `behind` m before its start, lies `margin` inside
    the open area, in a uniform direction.

    Raises:
        ValueError: the area has no room for the shortest walk.
    """
    lo, hi = interior(m, margin, who)
    size = hi - lo
    for _ in range(100):
        angle = rng.uniform(0.0, 2.0 * math.pi)
        u = np.array([math.cos(angle), math.sin(angle)])
        with np.errstate(divide="ignore"):
            chord = float(np.min(size / np.abs(u)))
        longest = min(length[1], chord - behind)
        if longest < length[0]:
            continue
        span = rng.uniform(length[0], longest)
        # The walk's extent from `behind` m before its start to its end, and where its start may go.
        first = np.minimum(-behind * u, span * u)
        last = np.maximum(-behind * u, span * u)
        start = rng.uniform(lo - first, hi - last)
        return start, u, float(span)
    raise ValueError(f"{m.where}: family {who!r}: no room for a {length[0]:g} m walk in the open area")


def _circle(m: Map, rng: np.random.Generator, radius: float, who: str) -> np.ndarray:
    """(2,) the centre of a standing group's circle of `radius`, anywhere 2 m clear of the walls
    (those round the area and, in up to 50 draws, any inside it)."""
    lo, hi = interior(m, radius + 2.0, who)
    for _ in range(50):
        centre = rng.uniform(lo, hi)
        if not m.num_walls or float(m.wall_index.nearest(centre[None])[1][0]) >= radius + 2.0:
            break
    return centre


def _spots(centre: np.ndarray, radius: float, count: int, first: float) -> np.ndarray:
    """(count, 2) evenly spaced spots on the circle, the first at angle `first` (rad)."""
    angle = first + 2.0 * math.pi * np.arange(count) / count
    return np.stack(circle_point(centre[0], centre[1], radius, angle), axis=-1)


def _away(rng: np.random.Generator, poses: np.ndarray, point: np.ndarray, distance: float) -> np.ndarray:
    """One of the poses at least `distance` from point (the farthest if none is)."""
    far = np.linalg.norm(poses - point, axis=1)
    if not (far >= distance).any():
        return poses[int(np.argmax(far))].copy()
    return poses[int(rng.choice(np.flatnonzero(far >= distance)))].copy()


class JoiningGroup(SuiteFamily):
    """(p) 2-4 people stand talking on a circle with a free spot; the robot must join them there,
    while 0-3 passers-by walk across the area.

    The circle (radius 0.8-1.0 m) lies anywhere in the area 2 m clear of the walls, with n + 1
    evenly spaced spots; the free one faces the robot's start (a legal pose at least 5 m away, or
    the farthest) give or take 60 degrees and is the robot's goal. The members stand at the other
    spots for ever (they stop at their start and are never released) and form one group
    (human_group), so the group-intrusion metric counts the robot crossing between them. Each
    passer-by walks between two legal poses whose line keeps 1 m clear of the circle.
    """

    name = "joining_group"
    map_name = "plaza"
    description = "the robot joins a standing group of 2-4 at its free spot as 0-3 people pass by"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """A standing circle with a free spot for the robot; passers-by clear of the circle."""
        n = int(rng.integers(2, 4, endpoint=True))
        radius = rng.uniform(*GROUP_RADIUS)
        poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)[:, :2]
        centre = _circle(m, rng, radius, self.name)
        robot_start = _away(rng, poses, centre, 5.0)
        facing = math.atan2(*(robot_start - centre)[::-1]) + rng.uniform(-math.pi / 3, math.pi / 3)
        spots = _spots(centre, radius, n + 1, facing)
        members = spots[1:]
        num_passing = int(rng.integers(0, 3, endpoint=True))
        starts, goals = [], []
        for _ in range(num_passing):
            for _ in range(30):
                i, j = rng.choice(len(poses), 2, replace=False)
                a, b = poses[i], poses[j]
                t = np.clip((centre - a) @ (b - a) / max(float((b - a) @ (b - a)), 1e-9), 0.0, 1.0)
                if (
                    np.linalg.norm(a + t * (b - a) - centre) >= radius + 1.0
                    and np.linalg.norm(a - robot_start) > 1.0
                ):
                    starts.append(a)
                    goals.append(b)
                    break
        passing = np.array(starts).reshape(-1, 2)
        k = len(passing)
        return Layout(
            robot_start,
            spots[0],
            np.vstack((members, passing)),
            np.vstack((members, np.array(goals).reshape(-1, 2))),
            _speeds(rng, n + k),
            human_stop=np.vstack((members, np.full((k, 2), np.nan))),
            human_group=np.concatenate((np.zeros(n, dtype=np.int64), np.full(k, -1))),
        )


class LeavingGroup(SuiteFamily):
    """(q) The robot stands in a circle of 2-4 people and leaves it for a goal away from the group.

    The robot starts at one of n + 1 evenly spaced spots of a circle 2 m clear of the walls, its
    radius 0.8-1.0 m but at most what keeps neighbouring spots 1.4 m apart (so the robot starts
    within 1.5 m of its neighbours); the members stand at the other spots for ever, one group. The
    robot's goal is a legal pose at least 5 m from the centre on the robot's side of the circle (the
    half-plane its spot faces), or the farthest such pose where none is 5 m away (a circle near the
    area's edge: 9 of 367 seeds tried, the nearest 3.5 m), so it leaves outwards.
    """

    name = "leaving_group"
    map_name = "plaza"
    description = "the robot leaves the standing group of 2-4 it is part of, for a goal away from it"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot at a spot of a standing circle; its goal a legal pose away from the circle."""
        n = int(rng.integers(2, 4, endpoint=True))
        radius = min(rng.uniform(*GROUP_RADIUS), 0.7 / math.sin(math.pi / (n + 1)))
        centre = _circle(m, rng, radius, self.name)
        spots = _spots(centre, radius, n + 1, rng.uniform(0.0, 2.0 * math.pi))
        poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)[:, :2]
        outward = (poses - centre) @ (spots[0] - centre) > 0.0
        goal = _away(rng, poses[outward] if outward.any() else poses, centre, 5.0)
        members = spots[1:]
        return Layout(
            spots[0],
            goal,
            members,
            members.copy(),
            _speeds(rng, n),
            human_stop=members.copy(),
            human_group=np.zeros(n, dtype=np.int64),
        )


class FollowingPerson(SuiteFamily):
    """(r) The robot follows a person who walks 12-20 m across the area and stops.

    The person walks a straight line (any direction that fits 1 m inside the walls) at 0.6-0.9 m/s
    (ESCORTED_SPEED) and stops at its end for ever; the robot starts 1.5-2.5 m behind it and its
    goal is 1.0-1.5 m short of the person's stop on the same line. The robot escorts the person
    (FOLLOW, socialzoo.scenarios.script.Script): all the way, the person stays 0.5-3.0 m away and
    ahead of the robot.
    """

    name = "following_person"
    map_name = "plaza"
    description = "the robot follows a person walking 12-20 m across the area, arriving with it"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """One person's straight walk with a stop at its end; the robot behind, stopping short."""
        behind = rng.uniform(1.5, 2.5)
        start, u, length = _segment(m, rng, (12.0, 20.0), behind, 1.0, self.name)
        goal = start + length * u
        return Layout(
            start - behind * u,
            goal - rng.uniform(1.0, 1.5) * u,
            start[None],
            goal[None],
            rng.uniform(*ESCORTED_SPEED, size=1),
            human_stop=goal[None],
            script={"escort": [0], "escort_kind": [FOLLOW], "band": [[0.5, 3.0]]},
        )


class LeadingPerson(SuiteFamily):
    """(s) The robot guides a person across the area: the person follows it.

    The robot drives a straight 10-16 m line (any direction that fits 1 m inside the walls); the
    person starts 1-2 m behind it and follows it (Script.follow) at a 1.2 m gap, at 1.6-1.8 m/s so
    it keeps up with GoAlone. The robot escorts the person (LEAD, socialzoo.scenarios.script.Script):
    all the way, the person stays 0.5-3.0 m away and behind the robot.
    """

    name = "leading_person"
    map_name = "plaza"
    description = "the robot leads a person who follows it 10-16 m across the area"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot's straight drive; one person behind it who follows it."""
        behind = rng.uniform(1.0, 2.0)
        start, u, length = _segment(m, rng, (10.0, 16.0), behind, 1.0, self.name)
        person = (start - behind * u)[None]
        return Layout(
            start,
            start + length * u,
            person,
            person.copy(),
            rng.uniform(1.6, 1.8, size=1),
            script={
                "follow": [0],
                "gap": [1.2],
                "escort": [0],
                "escort_kind": [LEAD],
                "band": [[0.5, 3.0]],
            },
        )


class AccompanyingPeer(SuiteFamily):
    """(t) The robot walks beside a person across the area, and they stop together.

    The robot's route is a straight 12-20 m line (any direction that fits 2 m inside the walls);
    the person walks the parallel line 1 m to its left or right at 0.6-0.9 m/s (ESCORTED_SPEED) and
    stops at its end for ever (its route ends at its stop). The robot escorts the person (ACCOMPANY,
    socialzoo.scenarios.script.Script): all the way, the person stays 0.5-2.0 m away and beside the
    robot.
    """

    name = "accompanying_peer"
    map_name = "plaza"
    description = "the robot walks 12-20 m beside a person, 1 m apart, and they stop together"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot's straight route; the person on the parallel line 1 m to one side."""
        start, u, length = _segment(m, rng, (12.0, 20.0), 0.0, 2.0, self.name)
        side = np.array([-u[1], u[0]]) * (1.0 if rng.random() < 0.5 else -1.0)
        goal = start + length * u
        return Layout(
            start,
            goal,
            (start + side)[None],
            (goal + side)[None],
            rng.uniform(*ESCORTED_SPEED, size=1),
            human_stop=(goal + side)[None],
            script={"escort": [0], "escort_kind": [ACCOMPANY], "band": [[0.5, 2.0]]},
        )


class CrowdNavigation(SuiteFamily):
    """(u) The robot crosses the area through 10-20 people walking between random points.

    The robot goes between two legal poses across the area (at least 0.75 of its farthest pair's
    distance apart). Each person walks from a point uniform in the area 1 m inside the walls (1 m
    from the robot's start and goal and from each other) to a point uniform within 2 m of the
    robot's way (its middle 80%, at least 4 m from the person's start), and back, so that the crowd
    keeps crossing the robot's way.
    """

    name = "crowd_navigation"
    map_name = "plaza"
    description = "the robot crosses an area busy with 10-20 people walking between random points"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """Robot across; the crowd's starts uniform in the area, its goals about the robot's way."""
        # The robot's way: any pair of legal poses at least 0.75 of the farthest pair's distance apart.
        p = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)[:, :2]
        if len(p) < 2:
            raise ValueError(f"{m.where}: family {self.name!r} needs at least 2 legal poses")
        d = np.linalg.norm(p[:, None] - p[None], axis=-1)
        ends = np.nonzero(d >= 0.75 * d.max())
        k = int(rng.integers(len(ends[0])))
        a, b = p[ends[0][k]], p[ends[1][k]]
        left = np.array([a[1] - b[1], b[0] - a[0]]) / max(float(np.linalg.norm(b - a)), 1e-9)
        box = interior(m, 1.0, self.name)
        n = int(rng.integers(10, 20, endpoint=True))
        starts = draw_spots(m, rng, n, lambda: rng.uniform(*box), np.vstack((a, b)), 1.0)

        def on_way() -> np.ndarray:
            return a + rng.uniform(0.1, 0.9) * (b - a) + rng.uniform(-2.0, 2.0) * left

        goals = np.empty_like(starts)
        for i, start in enumerate(starts):
            goal = draw_spots(m, rng, 1, on_way, start[None], 4.0, box)
            goals[i] = goal[0] if len(goal) else (a + b) / 2.0
        return Layout(a, b, starts, goals, _speeds(rng, len(starts)))


class PerpendicularFlow(SuiteFamily):
    """(w) The robot crosses the area through a stream of 4-8 people walking across its way.

    The robot drives along the area's longer axis through its middle (1 m from the walls at both
    ends, within 1 m of the axis). The stream is a 4 m wide band across the robot's line, centred
    55-70% of the way along it: each person walks across the band, either way, from one side of the
    area to the other (1 m inside the walls) and back, starting as far from the robot's line as it
    walks until 3 s before to 2 s after the robot gets there (GoAlone's speed; no farther than the
    side of the area), so that people cross ahead of the robot.
    """

    name = "perpendicular_flow"
    map_name = "plaza"
    description = "4-8 people stream across the robot's way in a 4 m band"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot along the long axis; the stream across it, timed round its arrival."""
        lo, hi = interior(m, 1.0, self.name)
        axis = int(np.argmax(hi - lo))
        u = np.eye(2)[axis]
        v = np.eye(2)[1 - axis]
        side = ((lo + hi) / 2.0 + rng.uniform(-1.0, 1.0)) @ v
        robot_start, robot_goal = lo @ u * u + side * v, hi @ u * u + side * v
        n = int(rng.integers(4, 8, endpoint=True))
        speed = _speeds(rng, n)
        # Each person's distance along the robot's line, and the room on either side of the line.
        along = (hi - lo) @ u * rng.uniform(0.55, 0.7) + rng.uniform(-2.0, 2.0, n)
        way = np.where(rng.random(n) < 0.5, 1.0, -1.0)
        cruise, lag = nominal_timing()
        when = along / cruise + ROBOT_LAG + rng.uniform(-3.0, 2.0, n)
        before, after = (
            np.where(way > 0, side - lo @ v, hi @ v - side),
            np.where(way > 0, hi @ v - side, side - lo @ v),
        )
        lateral = np.clip(speed * (when - lag), 1.0, before)
        base = robot_start + along[:, None] * u
        starts = base - (way * lateral)[:, None] * v
        goals = base + (way * after)[:, None] * v
        return Layout(robot_start, robot_goal, starts, goals, speed)


class RobotCrowding(SuiteFamily):
    """(y) People gather round the robot as it tries to cross the area: 4-8 follow it.

    The robot drives a straight 8-12 m line (any direction that fits 3 m inside the walls); 4-8
    people start 2-5 m from its start, from evenly spread directions (0.8 m from each other), and
    follow it (Script.follow) at a brisk 1.1-1.3 m/s, each keeping 0.9-1.2 m from it (the world's
    followers stand about 0.4 m farther off, more where others are in the way).
    """

    name = "robot_crowding"
    map_name = "plaza"
    description = "4-8 people converge on the robot and keep 0.9-1.2 m from it"

    def layout(self, m: Map, rng: np.random.Generator) -> Layout:
        """The robot's straight drive; onlookers round its start who follow it."""
        # 3 m inside the walls: room for an onlooker 2 m from the robot's start in every direction.
        start, u, length = _segment(m, rng, (8.0, 12.0), 0.0, 3.0, self.name)
        box = interior(m, 1.0, self.name)
        # One person from each of n evenly spread directions (turned and jittered): people coming
        # from the same side queue behind each other instead of gathering round.
        wanted = int(rng.integers(4, 8, endpoint=True))
        turn = rng.uniform(0.0, 2.0 * math.pi)
        spots = np.zeros((0, 2))
        for k in range(wanted):

            def around(k: int = k) -> np.ndarray:
                angle = turn + 2.0 * math.pi * (k + rng.uniform(-0.3, 0.3)) / wanted
                return start + rng.uniform(2.0, 5.0) * np.array([math.cos(angle), math.sin(angle)])

            spots = np.vstack((spots, draw_spots(m, rng, 1, around, np.vstack((start, spots)), 0.8, box)))
        n = len(spots)
        return Layout(
            start,
            start + length * u,
            spots,
            spots.copy(),
            rng.uniform(1.1, 1.3, n),
            script={"follow": np.zeros(n, dtype=np.int64), "gap": rng.uniform(0.9, 1.2, n)},
        )
