"""The cases of the CrowdNav task (Chen et al. 2019, vita-epfl/CrowdNav): a robot crossing an open arena from
(0, -r) to (0, r) among people placed by circle crossing or square crossing."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.core.validation import check_choice, check_fields, check_int
from socialzoo.scenarios.catalogue import ScenarioFamily, SeedSplit
from socialzoo.scenarios.families import antipode, circle_point
from socialzoo.scenarios.scenario import Scenario

if TYPE_CHECKING:
    from socialzoo.maps.map_file import Map

Layout = Literal["circle_crossing", "square_crossing"]
LAYOUTS: tuple[str, ...] = get_args(Layout)
Split = Literal["train", "val", "test"]
SPLITS: tuple[str, ...] = get_args(Split)
# CrowdNav's case seeds: validation from 0, test from 1000 (case_capacity val 1000), training from 2000.
SPLIT_SEED_OFFSET: dict[str, int] = {"val": 0, "test": 1000, "train": 2000}
# CrowdNav's fixed set sizes (env.config val_size, test_size).
SPLIT_SIZE: dict[str, int] = {"val": 100, "test": 500}
ARENA_MAP = "arena"
# Most uniform draws a case may take (128 MiB) before its config is refused as too full: CrowdNav
# draws a person again until it fits, forever when the people placed leave it no room, and a
# 20-person case in CrowdNav's 4 m circle takes a median 5,300.
MAX_CASE_DRAWS = 1 << 24


@dataclass(frozen=True, kw_only=True)
class CrowdCaseConfig:
    """How the CrowdNav cases are drawn (CrowdNav's env.config [sim], [humans], [robot]).

    Attributes:
        layout: "circle_crossing" or "square_crossing".
        num_humans: people per case (CrowdNav: 5; CrowdNav++'s arena: 20).
        circle_radius: radius of the circle of starts, and the robot's distance from the centre, m.
        square_width: side of the square crossing's square, m.
        human_radius: the people's radius, m.
        robot_radius: the robot's radius, m (in the CrowdNav task its robot's: CrowdNavConfig
            keeps the two equal, as CrowdNav reads both from [robot] radius).
        human_speed: the people's preferred speed v_pref, m/s (also the scale of the start noise).
        discomfort_dist: extra spacing between drawn agents, m (in the CrowdNav task its reward's
            discomfort distance, as CrowdNav's [reward] discomfort_dist is both).
        robot_layout: "crossing" (CrowdNav: the robot from (0, -r) to (0, r)) or "random"
            (CrowdNav++: start and goal uniform in [-r, r]^2, at least min_robot_route apart,
            drawn before the people from the same stream).
        min_robot_route: the shortest start-goal distance of a "random" robot, m (CrowdNav++: 6).
    """

    layout: Layout = "circle_crossing"
    num_humans: int = 5
    circle_radius: float = 4.0
    square_width: float = 10.0
    human_radius: float = 0.3
    robot_radius: float = 0.3
    human_speed: float = 1.0
    discomfort_dist: float = 0.2
    robot_layout: Literal["crossing", "random"] = "crossing"
    min_robot_route: float = 6.0

    def __post_init__(self) -> None:
        check_choice("CrowdCaseConfig", "layout", self.layout, LAYOUTS)
        check_fields(self, nonnegative=("num_humans", "discomfort_dist", "min_robot_route"))
        check_choice("CrowdCaseConfig", "robot_layout", self.robot_layout, ("crossing", "random"))
        if self.robot_layout == "random" and self.min_robot_route >= 2 * math.sqrt(2) * self.circle_radius:
            raise ValueError(
                f"CrowdCaseConfig.min_robot_route ({self.min_robot_route}) leaves no start-goal pair in the "
                f"[-{self.circle_radius}, {self.circle_radius}]^2 square"
            )


@functools.lru_cache(maxsize=64)
def robot_poses(num_robots: int, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(starts, goals) (R, 3) of R robots on the circle: robot 0 at (0, -r) heading +y with its
    goal at (0, r), as CrowdNav's robot; robot k at angle -pi/2 + 2 pi k / R, heading for its
    antipode (our extension for several robots)."""
    angle = -math.pi / 2 + 2 * math.pi * np.arange(num_robots) / num_robots
    start = np.stack(circle_point(0.0, 0.0, radius, angle), axis=1)
    start[0] = (0.0, -radius)  # exactly CrowdNav's, not cos(-pi/2) ~ 6e-17
    heading = np.arctan2(-start[:, 1], -start[:, 0])
    starts = np.column_stack((start, heading))
    goals = np.column_stack((*antipode(0.0, 0.0, start[:, 0], start[:, 1]), heading))  # 2 * 0.0 - x: no -0.0
    starts.flags.writeable = False  # cached: shared by every case
    goals.flags.writeable = False
    return starts, goals


@dataclass(frozen=True)
class CrowdCase:
    """A case as plain arrays (what a reset writes into the state; case_scenario wraps it in a
    Scenario).

    Attributes:
        seed: the case's seed.
        robot_starts: (R, 3) start poses.
        robot_goals: (R, 3) goal poses.
        human_starts: (n, 2) the people's starts, m.
        human_goals: (n, 2) their goals, m.
    """

    seed: int
    robot_starts: np.ndarray
    robot_goals: np.ndarray
    human_starts: np.ndarray
    human_goals: np.ndarray


def crowd_case_arrays(
    config: CrowdCaseConfig, seed: int, num_robots: int = 1, rs: np.random.RandomState | None = None
) -> CrowdCase:
    """The case drawn from RandomState(seed): the robots (robot_poses; one robot: CrowdNav's, at
    (0, -r) heading +y with its goal at (0, r)) and config.num_humans people with one-point
    routes to their goals, each drawn clear of the robots and of the people before it.

    The rules are CrowdNav's (crowd_sim.py): in circle crossing each person starts on a circle of
    radius `circle_radius` at a uniform angle, plus uniform noise of +-v_pref/2 on each coordinate, and
    walks to the antipode of its start; in square crossing each person starts in a random half of a
    square `square_width` wide and walks to a random point of the other half. A draw closer than
    radius + other radius + discomfort distance to an earlier agent's position (or goal) is drawn
    again. Draws are consumed in CrowdNav's order. People walk to their goal and stay there, as
    CrowdNav's people do.

    Args:
        config: how cases are drawn.
        seed: the case's seed.
        num_robots: R.
        rs: a RandomState to reseed and reuse (a new one costs ~0.6 ms, a reseed ~0.01 ms).
    """
    check_int("crowd_case", "num_robots", num_robots, low=1)
    if rs is None:
        rs = np.random.RandomState(seed)
    else:
        rs.seed(seed)
    # Enough draws for most cases at once (a 5-person case uses about 30, a 20-person one a median 5,300).
    n = config.num_humans
    draws = rs.random_sample(256 * (n + 1) + 64 * num_robots)
    used = 0
    if config.robot_layout == "random":
        gap = 2 * config.robot_radius + config.discomfort_dist
        robot_starts, robot_goals, used = _random_robots(
            draws, num_robots, config.circle_radius, config.min_robot_route, gap
        )
    else:
        robot_starts, robot_goals = robot_poses(num_robots, config.circle_radius)
    positions = np.empty((num_robots + n, 2))
    goals = np.empty((num_robots + n, 2))
    radii = np.full(num_robots + n, config.human_radius)
    positions[:num_robots] = robot_starts[:, :2]
    goals[:num_robots] = robot_goals[:, :2]
    radii[:num_robots] = config.robot_radius
    square = config.layout == "square_crossing"
    person, at = num_robots, used
    while True:
        person, at = _draw_people(
            draws, at, square, person, num_robots + n, config.circle_radius, config.square_width,
            config.human_speed, config.human_radius, config.discomfort_dist, positions, goals, radii,
        )  # fmt: skip
        if person == num_robots + n:
            break
        if len(draws) >= MAX_CASE_DRAWS:
            raise ValueError(
                f"crowd case {seed}: person {person - num_robots} of {n} found no place clear of the "
                f"{person} agents before it in {len(draws):,} draws (CrowdNav's rule would draw forever): "
                f"the {config.layout} layout is too full for {n} people; use fewer people or a larger "
                "circle_radius or square_width (CrowdNav++'s 20 people: CrowdNavConfig.variant('20'))"
            )
        # The draws ran out before every person found a place: the same stream, longer, from the
        # person whose draws ran out (the people before keep their places).
        draws = np.concatenate((draws, rs.random_sample(len(draws))))
    return CrowdCase(
        seed, robot_starts, robot_goals, positions[num_robots:].copy(), goals[num_robots:].copy()
    )


def _random_robots(
    draws: np.ndarray, num_robots: int, half: float, min_route: float, gap: float
) -> tuple[np.ndarray, np.ndarray, int]:
    """CrowdNav++'s robots: start and goal uniform in [-half, half]^2 until at least min_route apart
    (4 draws a try), heading pi / 2; returns (starts, goals, draws used). A robot after the first
    is also drawn again while its start (goal) is closer than `gap` (two robot radii and the
    discomfort distance, the people's spacing rule) to an earlier robot's start (goal)."""
    starts, goals, at = np.empty((num_robots, 3)), np.empty((num_robots, 3)), 0
    for k in range(num_robots):
        while True:
            if at + 4 > len(draws):
                raise RuntimeError("crowd_case: the robots' draws ran out")  # ~never: each try succeeds often
            px, py, gx, gy = -half + 2 * half * draws[at : at + 4]
            at += 4
            if math.hypot(px - gx, py - gy) >= min_route and all(
                math.hypot(px - starts[j, 0], py - starts[j, 1]) >= gap
                and math.hypot(gx - goals[j, 0], gy - goals[j, 1]) >= gap
                for j in range(k)
            ):
                break
        starts[k], goals[k] = (px, py, math.pi / 2), (gx, gy, math.pi / 2)
    return starts, goals, at


def case_scenario(case: CrowdCase, config: CrowdCaseConfig) -> Scenario:
    """A case as a Scenario: one-point routes to the people's goals, at config.human_speed."""
    n = case.human_starts.shape[0]
    return Scenario(
        map_name=ARENA_MAP,
        seed=case.seed,
        robot_starts=case.robot_starts,
        robot_goals=case.robot_goals,
        human_spawn=case.human_starts,
        human_start_index=np.full(n, -1),
        human_goal_index=np.full(n, -1),
        human_routes=tuple(g[None, :] for g in case.human_goals),
        human_speed=np.full(n, config.human_speed),
        family=_BY_LAYOUT[config.layout].name,
    )


class CrowdNavFamily(ScenarioFamily):
    """CrowdNav's cases as a scenario family: drawn by CrowdNav's rules from its case seeds, in the
    open arena, for a CrowdCaseConfig of the family's layout (default: CrowdNav's own).

    Case k of a split is drawn with numpy's legacy RandomState seeded as CrowdNav seeds it
    (validation k: k; test k: 1000 + k; training k: 2000 + k), so our validation and test cases are
    CrowdNav's own (same positions, to float precision), apart from the training stream by
    construction.

    Args:
        cases: how cases are drawn; its layout must be the family's.
    """

    map_name = ARENA_MAP
    layout: Layout = "circle_crossing"
    splits = {split: SeedSplit(SPLIT_SEED_OFFSET[split], SPLIT_SIZE.get(split)) for split in SPLITS}

    def __init__(self, cases: CrowdCaseConfig | None = None) -> None:
        self.cases = CrowdCaseConfig(layout=self.layout) if cases is None else cases
        if self.cases.layout != self.layout:
            raise ValueError(
                f"{type(self).__name__} draws {self.layout}, got a {self.cases.layout} CrowdCaseConfig"
            )

    def make(self, seed: int, num_robots: int = 1, m: Map | None = None) -> Scenario:
        """The case of `seed` (crowd_case_arrays) in the arena; a map is refused (CrowdNav's cases are
        drawn for the open arena: the CrowdNav task's ids, e.g. socialzoo/CrowdNav-v1, play them)."""
        if m is not None:
            raise ValueError(
                f"scenario family {self.name!r} runs in CrowdNav's open arena, not on map {m.name!r}"
            )
        return case_scenario(self.arrays(seed, num_robots), self.cases)

    def arrays(self, seed: int, num_robots: int = 1, rs: np.random.RandomState | None = None) -> CrowdCase:
        """The case of `seed` as plain arrays (what a training reset writes; crowd_case_arrays)."""
        return crowd_case_arrays(self.cases, seed, num_robots, rs)


class CrowdNavCircleCrossing(CrowdNavFamily):
    """CrowdNav's circle crossing."""

    name = "crowdnav_circle_crossing"
    description = "CrowdNav's circle crossing: people near a circle walk to the antipode, the robot across it"
    layout = "circle_crossing"


class CrowdNavSquareCrossing(CrowdNavFamily):
    """CrowdNav's square crossing."""

    name = "crowdnav_square_crossing"
    description = (
        "CrowdNav's square crossing: people cross a square from one half to a random point of the other"
    )
    layout = "square_crossing"


def crowd_family(cases: CrowdCaseConfig) -> CrowdNavFamily:
    """The CrowdNav family drawing the cases of `cases` (its layout picks the family)."""
    return _BY_LAYOUT[cases.layout](cases)


_BY_LAYOUT: dict[str, type[CrowdNavFamily]] = {
    "circle_crossing": CrowdNavCircleCrossing,
    "square_crossing": CrowdNavSquareCrossing,
}


# Circle crossing's geometry (socialzoo.scenarios.families), compiled for the rejection loop.
_circle_point = kernel(circle_point)
_antipode = kernel(antipode)


@kernel
def _clear(x, y, points, radii, count, own, gap):  # type: ignore[no-untyped-def]
    """(x, y) no closer than own + radius + gap to any of the first `count` points."""
    for j in range(count):
        if math.hypot(x - points[j, 0], y - points[j, 1]) < own + radii[j] + gap:
            return False
    return True


@kernel
def _draw_people(  # type: ignore[no-untyped-def]
    u, at, square, first, end, circle_radius, width, speed, own, gap, positions, goals, radii
):
    """CrowdNav's rejection loops for people first .. end - 1 (agents before `first` are placed),
    reading the uniform draws `u` from index `at` in CrowdNav's order; fills positions and goals.
    Returns (end, draws used) when everyone is placed, else (i, where person i's draws began)
    when `u` ran out during person i: a call with more draws goes on from there."""
    size = len(u)
    for i in range(first, end):
        begin = at
        if square:
            if at >= size:
                return i, begin
            sign = -1.0 if u[at] > 0.5 else 1.0
            at += 1
            # The start on one half of the square, then the goal on the other.
            for k in range(2):
                side, out = (sign, positions) if k == 0 else (-sign, goals)
                while True:
                    if at + 2 > size:
                        return i, begin
                    x = u[at] * width * 0.5 * side
                    y = (u[at + 1] - 0.5) * width
                    at += 2
                    if _clear(x, y, out, radii, i, own, gap):
                        break
                out[i, 0], out[i, 1] = x, y
        else:
            while True:
                if at + 3 > size:
                    return i, begin
                x, y = _circle_point(0.0, 0.0, circle_radius, u[at] * np.pi * 2)
                # CrowdNav's jitter moves the start off the circle; the goal is its antipode.
                x += (u[at + 1] - 0.5) * speed
                y += (u[at + 2] - 0.5) * speed
                at += 3
                if _clear(x, y, positions, radii, i, own, gap) and _clear(x, y, goals, radii, i, own, gap):
                    break
            positions[i, 0], positions[i, 1] = x, y
            goals[i, 0], goals[i, 1] = _antipode(0.0, 0.0, x, y)
    return end, at
