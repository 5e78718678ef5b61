"""Scenario families beyond the benchmark, each a few lines of layout on a small map: hallway
head-on, overtaking, crossing at an intersection, doorway, circle crossing and parallel traffic
(the scenario names of the social-navigation evaluation guidelines).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from socialzoo.nav.family_catalogue import FAMILY_CATALOGUE
from socialzoo.nav.maps import Map
from socialzoo.nav.scenarios import Scenario, plan_routes, spawn_points, split_routes


@dataclass(frozen=True)
class Layout:
    """A family's choice of robot and human starts, goals and speeds (world frame, m, m/s).

    Attributes:
        robot_start, robot_goal: (2,) positions; headings point from start to goal.
        human_start, human_goal: (n, 2).
        human_speed: (n,).
    """

    robot_start: np.ndarray
    robot_goal: np.ndarray
    human_start: np.ndarray
    human_goal: np.ndarray
    human_speed: np.ndarray


@dataclass(frozen=True)
class Family:
    """A scenario family: a small layout rule, and the small map it is designed for.

    Families place people relative to the map's legal poses (its main axis is its farthest pair of
    poses), so they also run on other maps of a similar shape.
    """

    name: str
    map_name: str
    description: str
    layout: Callable[[Map, np.random.Generator], Layout]


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

    base = np.broadcast_to(anchor, (n, 2)).copy()
    return spawn_points(m.wall_index, base, base, draw, 0.3, 20)


def _speeds(rng: np.random.Generator, n: int, mean: float = 1.0, std: float = 0.1) -> np.ndarray:
    return np.clip(rng.normal(mean, std, size=n), 0.5, 1.3)


def _hallway_head_on(m: Map, rng: np.random.Generator) -> Layout:
    a, b = _farthest_pair(m)
    u, _ = _frame(a, b)
    n = int(rng.integers(1, 3, endpoint=True))
    return Layout(
        a,
        b,
        _near(m, rng, b, n, (-2.0, 0.0), (-0.6, 0.6), u),
        _near(m, rng, a, n, (0.0, 1.0), (-0.6, 0.6), u),
        _speeds(rng, n),
    )


def _overtaking(m: Map, rng: np.random.Generator) -> Layout:
    a, b = _farthest_pair(m)
    u, _ = _frame(a, b)
    return Layout(
        a,
        b,
        _near(m, rng, a, 1, (2.0, 3.0), (-0.3, 0.3), u),
        _near(m, rng, b, 1, (-1.0, 0.0), (-0.3, 0.3), u),
        rng.uniform(0.4, 0.6, size=1),
    )


def _crossing(m: Map, rng: np.random.Generator) -> Layout:
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


def _doorway(m: Map, rng: np.random.Generator) -> Layout:
    a, b = _farthest_pair(m)
    u, _ = _frame(a, b)
    n = int(rng.integers(1, 3, endpoint=True))
    return Layout(
        a,
        b,
        _near(m, rng, b, n, (-1.5, 0.0), (-0.8, 0.8), u),
        _near(m, rng, a, n, (0.0, 1.0), (-0.8, 0.8), u),
        _speeds(rng, n),
    )


def _circle_crossing(m: Map, rng: np.random.Generator) -> Layout:
    if not m.num_walls and m.region is None:
        raise ValueError(f"{m.where}: circle_crossing needs walls or a region to size its circle")
    # The walls' bounding box, cut down to the region if there is one (a region may have margins).
    lo, hi = np.full(2, -np.inf), np.full(2, np.inf)
    if m.num_walls:
        ends = np.asarray(m.walls, dtype=np.float64).reshape(-1, 2)
        lo, hi = ends.min(0), ends.max(0)
    if m.region is not None:
        lo = np.maximum(lo, np.asarray(m.region[:2], dtype=np.float64))
        hi = np.minimum(hi, np.asarray(m.region[2:], dtype=np.float64))
    centre = (lo + hi) / 2.0
    # One metre inside the smaller half-extent keeps everyone clear of the enclosing walls.
    radius = max(0.5 * float(np.min(hi - lo)) - 1.0, 0.5)
    n = int(rng.integers(4, 8, endpoint=True))
    angle = rng.uniform(0.0, 2.0 * np.pi) + 2.0 * np.pi * (
        np.arange(n + 1) + rng.uniform(-0.2, 0.2, n + 1)
    ) / (n + 1)
    ring = centre + radius * np.stack((np.cos(angle), np.sin(angle)), axis=-1)
    return Layout(ring[0], 2.0 * centre - ring[0], ring[1:], 2.0 * centre - ring[1:], _speeds(rng, n))


def _parallel_traffic(m: Map, rng: np.random.Generator) -> Layout:
    a, b = _farthest_pair(m)
    u, _ = _frame(a, b)
    length = float(np.linalg.norm(b - a))
    n = int(rng.integers(4, 8, endpoint=True))
    starts = _near(m, rng, a, n, (1.0, 0.6 * length), (-1.0, 1.0), u)
    goals = _near(m, rng, b, n, (-1.0, 0.0), (-1.0, 1.0), u)
    return Layout(a, b, starts, goals, _speeds(rng, n, 1.0, 0.2))


# Each family's layout rule; its map and description are in the catalogue.
_LAYOUTS: dict[str, Callable[[Map, np.random.Generator], Layout]] = {
    "hallway_head_on": _hallway_head_on,
    "overtaking": _overtaking,
    "crossing": _crossing,
    "doorway": _doorway,
    "circle_crossing": _circle_crossing,
    "parallel_traffic": _parallel_traffic,
}
FAMILIES: dict[str, Family] = {
    name: Family(name, map_name, description, _LAYOUTS[name])
    for name, (map_name, description) in FAMILY_CATALOGUE.items()
}


def make_family_scenario(name: str, m: Map, seed: int) -> Scenario:
    """A scenario of family `name` (a key of FAMILIES) on map m, drawn from default_rng(seed).

    Routes are planned like the benchmark's (a straight line where wall-free); humans spawn on
    their start points, and their pose indices are -1.

    Raises:
        KeyError: unknown family (the message lists the known ones).
        ValueError: the map has fewer than 2 legal poses.
        NoPathError: someone's goal cannot be reached.
    """
    if name not in FAMILIES:
        raise KeyError(f"unknown scenario family {name!r}; known: {sorted(FAMILIES)}")
    rng = np.random.default_rng(seed)
    lay = FAMILIES[name].layout(m, rng)
    n = len(lay.human_start)
    starts = np.concatenate((lay.robot_start[None], lay.human_start))
    goals = np.concatenate((lay.robot_goal[None], lay.human_goal))
    paths, lengths = plan_routes(m, starts, goals, f"{m.where}, family {name!r} seed {seed}")
    # The robot faces along the first leg of its route.
    first_leg = paths[0, min(1, int(lengths[0]) - 1)] - lay.robot_start
    heading = math.atan2(float(first_leg[1]), float(first_leg[0]))
    return Scenario(
        map_name=m.name,
        seed=seed,
        family=name,
        robot_starts=np.array([[*lay.robot_start, heading]]),
        robot_goals=np.array([[*lay.robot_goal, heading]]),
        human_spawn=lay.human_start,
        human_start_index=np.full(n, -1),
        human_goal_index=np.full(n, -1),
        human_routes=split_routes(paths[1:], lengths[1:]),
        human_speed=lay.human_speed,
    )
