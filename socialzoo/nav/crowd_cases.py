"""The cases of the CrowdNav task (Chen et al. 2019, vita-epfl/CrowdNav): a robot crossing an open
arena from (0, -r) to (0, r) among people placed by circle crossing or square crossing.

The rules are CrowdNav's (crowd_sim.py): in circle crossing each person starts on a circle of
radius `circle_radius` at a uniform angle, plus uniform noise of +-v_pref/2 on each coordinate, and
walks to the antipode of its start; in square crossing each person starts in a random half of a
square `square_width` wide and walks to a random point of the other half. A draw closer than
radius + other radius + discomfort distance to an earlier agent's position (or goal) is drawn
again. Case k of a split is drawn with numpy's legacy RandomState seeded as CrowdNav seeds it
(validation k: k; test k: 1000 + k; training k: 2000 + k), consuming draws in CrowdNav's order,
so our validation and test cases are CrowdNav's own (same positions, to float precision), apart
from the training stream by construction. People get one-point routes: they walk to their goal
and stay there, as CrowdNav's people do.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from socialzoo.core.validation import check_int, check_number
from socialzoo.nav.scenarios import Scenario

Layout = Literal["circle_crossing", "square_crossing"]
LAYOUTS: tuple[str, ...] = get_args(Layout)
Split = Literal["train", "val", "test"]
SPLITS: tuple[str, ...] = get_args(Split)
# CrowdNav's case seeds: validation from 0, test from 1000 (case_capacity val 1000), training from 2000.
SPLIT_SEED_OFFSET: dict[str, int] = {"val": 0, "test": 1000, "train": 2000}
# CrowdNav's fixed set sizes (env.config val_size, test_size).
SPLIT_SIZE: dict[str, int] = {"val": 100, "test": 500}
ARENA_MAP = "arena"


@dataclass(frozen=True, kw_only=True)
class CrowdCaseConfig:
    """How the CrowdNav cases are drawn (CrowdNav's env.config [sim], [humans], [robot]).

    Attributes:
        layout: "circle_crossing" or "square_crossing".
        num_humans: people per case (CrowdNav: 5; CrowdNav++'s arena: 20).
        circle_radius: radius of the circle of starts, and the robot's distance from the centre, m.
        square_width: side of the square crossing's square, m.
        human_radius: the people's radius, m.
        robot_radius: the robot's radius, m.
        human_speed: the people's preferred speed v_pref, m/s (also the scale of the start noise).
        discomfort_dist: extra spacing between drawn agents, m.
    """

    layout: Layout = "circle_crossing"
    num_humans: int = 5
    circle_radius: float = 4.0
    square_width: float = 10.0
    human_radius: float = 0.3
    robot_radius: float = 0.3
    human_speed: float = 1.0
    discomfort_dist: float = 0.2

    def __post_init__(self) -> None:
        if self.layout not in LAYOUTS:
            raise ValueError(f"CrowdCaseConfig.layout must be one of {LAYOUTS}, got {self.layout!r}")
        check_int("CrowdCaseConfig", "num_humans", self.num_humans, low=0)
        for name in ("circle_radius", "square_width", "human_radius", "robot_radius", "human_speed"):
            check_number("CrowdCaseConfig", name, getattr(self, name), low=0, low_open=True)
        check_number("CrowdCaseConfig", "discomfort_dist", self.discomfort_dist, low=0)


def case_seed(split: Split, index: int) -> int:
    """The seed of case `index` of a split (CrowdNav's np.random.seed for that case)."""
    if split not in SPLITS:
        raise ValueError(f"unknown split {split!r}; known: {SPLITS}")
    check_int("case_seed", "index", index, low=0)
    if split in SPLIT_SIZE and index >= SPLIT_SIZE[split]:
        raise ValueError(f"the {split} split holds {SPLIT_SIZE[split]} cases; index {index} is outside it")
    return SPLIT_SEED_OFFSET[split] + index


def robot_poses(num_robots: int, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(starts, goals) (R, 3) of R robots on the circle: robot 0 at (0, -r) heading +y with its
    goal at (0, r), as CrowdNav's robot; robot k at angle -pi/2 + 2 pi k / R, heading for its
    antipode (our extension for several robots)."""
    angle = -math.pi / 2 + 2 * math.pi * np.arange(num_robots) / num_robots
    start = radius * np.stack((np.cos(angle), np.sin(angle)), axis=1)
    start[0] = (0.0, -radius)  # exactly CrowdNav's, not cos(-pi/2) ~ 6e-17
    heading = np.arctan2(-start[:, 1], -start[:, 0])
    starts = np.column_stack((start, heading))
    goals = np.column_stack((0.0 - start, heading))  # 0.0 - x: no -0.0 in the goals
    return starts, goals


def crowd_case(config: CrowdCaseConfig, seed: int, num_robots: int = 1) -> Scenario:
    """The case drawn from RandomState(seed): the robots (robot_poses; one robot: CrowdNav's, at
    (0, -r) heading +y with its goal at (0, r)) and config.num_humans people with one-point
    routes to their goals, each drawn clear of the robots and of the people before it."""
    check_int("crowd_case", "num_robots", num_robots, low=1)
    u = _Uniforms(np.random.RandomState(seed))
    robot_starts, robot_goals = robot_poses(num_robots, config.circle_radius)
    positions: list[np.ndarray] = list(robot_starts[:, :2])
    goals: list[np.ndarray] = list(robot_goals[:, :2])
    radii = [config.robot_radius] * num_robots
    for _ in range(config.num_humans):
        if config.layout == "circle_crossing":
            start, goal = _circle_human(u, config, positions, goals, radii)
        else:
            start, goal = _square_human(u, config, positions, goals, radii)
        positions.append(start)
        goals.append(goal)
        radii.append(config.human_radius)
    n = config.num_humans
    spawn = np.array(positions[num_robots:]).reshape(n, 2)
    return Scenario(
        map_name=ARENA_MAP,
        seed=seed,
        robot_starts=robot_starts,
        robot_goals=robot_goals,
        human_spawn=spawn,
        human_start_index=np.full(n, -1),
        human_goal_index=np.full(n, -1),
        human_routes=tuple(np.array([g]) for g in goals[num_robots:]),
        human_speed=np.full(n, config.human_speed),
        family=config.layout,
    )


class _Uniforms:
    """The case generator's uniform draws as one stream read in order: CrowdNav's sequential
    draws, fetched from the generator in blocks (appending keeps their order)."""

    def __init__(self, rs: np.random.RandomState) -> None:
        self.rs = rs
        self.values = rs.random_sample(256)
        self.at = 0

    def peek(self, count: int) -> np.ndarray:
        """The next `count` draws, without consuming them."""
        while self.at + count > len(self.values):
            self.values = np.concatenate((self.values, self.rs.random_sample(max(count, len(self.values)))))
        return self.values[self.at : self.at + count]

    def take(self, count: int) -> np.ndarray:
        """The next `count` draws, consumed."""
        out = self.peek(count)
        self.at += count
        return out


def _first_clear(
    u: _Uniforms,
    draws: int,
    candidates: Callable[[np.ndarray], np.ndarray],
    clear: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """CrowdNav's rejection loop `while True: draw; if clear: break`, batched: the candidates of
    many tries are checked at once and only the draws up to the accepted try are consumed, so the
    cases stay CrowdNav's.

    Args:
        u: the case's draws.
        draws: uniform draws per try.
        candidates: (K, draws) uniform draws -> (K, 2) candidate points.
        clear: (K, 2) points -> (K,) bool, the point keeps its distances.
    """
    tries = 16
    while True:
        points = candidates(u.peek(draws * tries).reshape(tries, draws))
        ok = clear(points)
        if ok.any():
            first = int(np.argmax(ok))
            u.take(draws * (first + 1))
            return points[first]
        u.take(draws * tries)
        tries = min(tries * 2, 4096)


def _clear_of(
    others: list[np.ndarray], radii: list[float], own: float, gap: float
) -> Callable[[np.ndarray], np.ndarray]:
    """points (K, 2) -> (K,) no closer than own + radius + gap to any of `others`."""
    at = np.array(others).reshape(-1, 2)
    limit = own + np.array(radii) + gap

    def clear(points: np.ndarray) -> np.ndarray:
        d = np.hypot(points[:, None, 0] - at[None, :, 0], points[:, None, 1] - at[None, :, 1])
        return ~(d < limit[None, :]).any(axis=1)

    return clear


def _circle_human(
    u: _Uniforms,
    config: CrowdCaseConfig,
    positions: list[np.ndarray],
    goals: list[np.ndarray],
    radii: list[float],
) -> tuple[np.ndarray, np.ndarray]:
    """CrowdNav's generate_circle_crossing_human: a start on the circle with noise, kept clear of
    every earlier agent's position and goal; the goal is the start's antipode."""
    own, gap, r, v = config.human_radius, config.discomfort_dist, config.circle_radius, config.human_speed
    near_start = _clear_of(positions, radii, own, gap)
    near_goal = _clear_of(goals, radii, own, gap)

    def candidates(u: np.ndarray) -> np.ndarray:
        angle = u[:, 0] * np.pi * 2
        return np.stack(
            (r * np.cos(angle) + (u[:, 1] - 0.5) * v, r * np.sin(angle) + (u[:, 2] - 0.5) * v), axis=1
        )

    start = _first_clear(u, 3, candidates, lambda p: near_start(p) & near_goal(p))
    return start, -start


def _square_human(
    u: _Uniforms,
    config: CrowdCaseConfig,
    positions: list[np.ndarray],
    goals: list[np.ndarray],
    radii: list[float],
) -> tuple[np.ndarray, np.ndarray]:
    """CrowdNav's generate_square_crossing_human: a start in a random half of the square kept clear
    of earlier positions, a goal in the other half kept clear of earlier goals."""
    own, gap, w = config.human_radius, config.discomfort_dist, config.square_width
    sign = -1.0 if u.take(1)[0] > 0.5 else 1.0

    def half(side: float) -> Callable[[np.ndarray], np.ndarray]:
        return lambda u: np.stack((u[:, 0] * w * 0.5 * side, (u[:, 1] - 0.5) * w), axis=1)

    start = _first_clear(u, 2, half(sign), _clear_of(positions, radii, own, gap))
    goal = _first_clear(u, 2, half(-sign), _clear_of(goals, radii, own, gap))
    return start, goal
