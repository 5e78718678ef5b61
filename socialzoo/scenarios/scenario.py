"""Seeded scenarios: the benchmark's generator (SPEC section 5), its fixed test sets, and the conversion of
scenarios into a batched WorldState (scenario families for the small maps: socialzoo.scenarios.families)."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from socialzoo.core.files import read_json
from socialzoo.core.jit import kernel
from socialzoo.core.seed_hash import seed_states
from socialzoo.core.state import WorldState
from socialzoo.core.validation import check_int, check_number
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
from socialzoo.scenarios.recorded_people import RecordedPeople
from socialzoo.scenarios.script import Script

SCENARIO_FORMAT = "socialzoo-scenario/1"
# Mixed with a scenario's seed to derive its counter-based noise key (see core.noise).
_NOISE_STREAM = 0x6E6F697365  # "noise"


class ScenarioError(ValueError):
    """A scenario file or scenario JSON that cannot be read: the message names the file and field."""


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
        for name, low in (("min_humans", 0), ("max_humans", 0), ("repeats", 1), ("spawn_tries", 1)):
            check_int("ScenarioConfig", name, getattr(self, name), low=low)
        if self.min_humans > self.max_humans:
            raise ValueError(
                f"ScenarioConfig.min_humans ({self.min_humans}) exceeds max_humans ({self.max_humans})"
            )
        for name in ("spawn_jitter", "speed_std", "spawn_clearance"):
            check_number("ScenarioConfig", name, getattr(self, name), low=0.0)
        for name in ("speed_mean", "min_speed", "max_speed"):
            check_number("ScenarioConfig", name, getattr(self, name), low=0.0, low_open=True)
        if self.min_speed > self.max_speed:
            raise ValueError(
                f"ScenarioConfig.min_speed ({self.min_speed}) exceeds max_speed ({self.max_speed})"
            )
        check_number("ScenarioConfig", "max_route_length", self.max_route_length, low=0.0, low_open=True)


def _frozen_array(value: Any, dtype: type, shape: tuple[int | None, ...], what: str) -> np.ndarray:
    """A read-only copy of `value` as `dtype`, checked against `shape` (None = any length)."""
    arr: np.ndarray = np.array(value, dtype=dtype)
    if arr.size == 0 and len(shape) > 1:
        arr = arr.reshape((0, *(s or 0 for s in shape[1:])))
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape, strict=True)):
        want = "(" + ", ".join("*" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"Scenario.{what} must have shape {want}, got {arr.shape}")
    if dtype is np.float64 and not np.all(np.isfinite(arr)):
        raise ValueError(f"Scenario.{what} must be finite")
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, kw_only=True, eq=False)
class Scenario:
    """Everything needed to reset a world: robots' starts and goals, humans' spawns, routes, speeds.

    All positions are in the world frame, metres; headings in radians. Arrays are read-only.
    Equality compares every array exactly (bit for bit). A scenario is a pure function of (map, seed,
    config) and saves to JSON exactly, so a saved scenario replays bit for bit.

    Attributes:
        map_name: name of the map the scenario belongs to.
        seed: the seed it was generated from.
        robot_starts: (R, 3) start poses (x, y, theta) of the R robots; the benchmark has R = 1.
        robot_goals: (R, 3) goal poses.
        human_spawn: (n, 2) spawn positions (the start pose position plus jitter).
        human_start_index: (n,) legal-pose index of each human's start, -1 if not a legal pose.
        human_goal_index: (n,) legal-pose index of each human's goal, -1 if not a legal pose.
        human_routes: n arrays (L_i, 2), route waypoints from the human's start to its goal.
        human_speed: (n,) preferred walking speed, m/s.
        family: "benchmark" for the SPEC generator, else the scenario family's name.
        human_group: (n,) the walking group of each human (the index of its first member), -1
            for none (socialzoo.humans.group_formation); default none. Saved only when someone walks in a group.
        script: who waits, signals or follows a robot, whom each robot escorts, and doors
            (socialzoo.scenarios.script); None: people walk their routes, robots reach their goals.
        recorded: the people's recorded tracks and the person the robot replaced
            (socialzoo.scenarios.recorded); None: nobody is recorded.
    """

    map_name: str
    seed: int
    robot_starts: np.ndarray
    robot_goals: np.ndarray
    human_spawn: np.ndarray
    human_start_index: np.ndarray
    human_goal_index: np.ndarray
    human_routes: tuple[np.ndarray, ...]
    human_speed: np.ndarray
    family: str = "benchmark"
    human_group: np.ndarray = None  # type: ignore[assignment]
    script: Script | None = None
    recorded: RecordedPeople | None = None
    # Derived in __post_init__: the routes end to end and their lengths (see there).
    _route_points: np.ndarray = field(init=False, repr=False)
    _route_lens: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        starts = _frozen_array(self.robot_starts, np.float64, (None, 3), "robot_starts")
        if len(starts) == 0:
            raise ValueError("Scenario.robot_starts must hold at least one robot")
        object.__setattr__(self, "robot_starts", starts)
        object.__setattr__(
            self, "robot_goals", _frozen_array(self.robot_goals, np.float64, (len(starts), 3), "robot_goals")
        )
        spawn = _frozen_array(self.human_spawn, np.float64, (None, 2), "human_spawn")
        n = len(spawn)
        object.__setattr__(self, "human_spawn", spawn)
        for name in ("human_start_index", "human_goal_index", "human_speed"):
            dtype = np.float64 if name == "human_speed" else np.int64
            object.__setattr__(self, name, _frozen_array(getattr(self, name), dtype, (n,), name))
        if len(self.human_routes) != n:
            raise ValueError(f"Scenario.human_routes holds {len(self.human_routes)} routes for {n} humans")
        routes = tuple(
            _frozen_array(r, np.float64, (None, 2), f"human_routes[{i}]")
            for i, r in enumerate(self.human_routes)
        )
        for i, r in enumerate(routes):
            if len(r) == 0:
                raise ValueError(f"Scenario.human_routes[{i}] is empty")
        object.__setattr__(self, "human_routes", routes)
        # The routes end to end and their lengths, once: a reset stacks a few scenarios' blocks
        # instead of every person's route (a kept scenario, as recorded scenes' are, is reset often).
        object.__setattr__(self, "_route_lens", np.array([len(r) for r in routes], dtype=np.intp))
        object.__setattr__(self, "_route_points", np.concatenate(routes) if routes else np.zeros((0, 2)))
        object.__setattr__(self, "seed", int(self.seed))
        group = np.full(n, -1) if self.human_group is None else self.human_group
        group = _frozen_array(group, np.int64, (n,), "human_group")
        if np.any((group < -1) | (group >= n)) or np.any((group >= 0) & (group > np.arange(n))):
            raise ValueError("Scenario.human_group must hold -1 or the index of a group's first member")
        object.__setattr__(self, "human_group", group)
        if self.script is not None and (self.script.num_humans, self.script.num_robots) != (n, len(starts)):
            raise ValueError(
                f"Scenario.script is for {self.script.num_humans} people and {self.script.num_robots} robots, "
                f"the scenario has {n} and {len(starts)}"
            )

        if self.recorded is not None and self.recorded.num_people != n:
            raise ValueError(
                f"Scenario.recorded holds {self.recorded.num_people} tracks, the scenario has {n} people"
            )

    @property
    def robot_start(self) -> np.ndarray:
        """(3,) the first robot's start pose."""
        return self.robot_starts[0]

    @property
    def robot_goal(self) -> np.ndarray:
        """(3,) the first robot's goal pose."""
        return self.robot_goals[0]

    @property
    def num_robots(self) -> int:
        """R, the robots of the scenario."""
        return len(self.robot_starts)

    @property
    def num_humans(self) -> int:
        """The humans of the scenario."""
        return len(self.human_spawn)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scenario):
            return NotImplemented
        same_arrays = all(
            _same(getattr(self, name), getattr(other, name))
            for name in (
                "robot_starts",
                "robot_goals",
                "human_spawn",
                "human_start_index",
                "human_goal_index",
                "human_speed",
                "human_group",
            )
        )
        return (
            same_arrays
            and (self.map_name, self.seed, self.family) == (other.map_name, other.seed, other.family)
            and self.script == other.script  # None equals only None: Script's __eq__ declines other types
            and self.recorded == other.recorded
            and len(self.human_routes) == len(other.human_routes)
            and all(_same(a, b) for a, b in zip(self.human_routes, other.human_routes, strict=True))
        )

    __hash__ = None  # type: ignore[assignment]

    def with_seed(self, seed: int) -> Scenario:
        """This scenario under another seed: a shallow copy (the arrays, read-only, are shared) that is
        not checked again, as copy.copy makes it, at about a third of its cost (0.74 against 2.5 us
        here; a family that keeps its scenarios renames one on every reset: socialzoo.scenarios.recorded)."""
        renamed = object.__new__(Scenario)
        renamed.__dict__.update(self.__dict__)
        renamed.__dict__["seed"] = int(seed)
        return renamed

    def to_json(self) -> dict[str, Any]:
        """The scenario as a JSON-ready dict; floats keep their exact value (shortest repr)."""
        return {
            "format": SCENARIO_FORMAT,
            "map_name": self.map_name,
            "seed": self.seed,
            "family": self.family,
            "robot_starts": self.robot_starts.tolist(),
            "robot_goals": self.robot_goals.tolist(),
            "human_spawn": self.human_spawn.tolist(),
            "human_start_index": self.human_start_index.tolist(),
            "human_goal_index": self.human_goal_index.tolist(),
            "human_routes": [r.tolist() for r in self.human_routes],
            "human_speed": self.human_speed.tolist(),
            **({"human_group": self.human_group.tolist()} if np.any(self.human_group >= 0) else {}),
            **({"script": self.script.to_json()} if self.script is not None else {}),
            **({"recorded": self.recorded.to_json()} if self.recorded is not None else {}),
        }

    @classmethod
    def from_json(cls, data: dict[str, Any], where: str = "scenario JSON") -> Scenario:
        """Inverse of `to_json`.

        Args:
            data: the parsed JSON object.
            where: how error messages name the source, usually the file path.

        Raises:
            ScenarioError: not a JSON object, a wrong format, a missing key, or a value of the wrong
                type or shape (the message starts with `where` and names the key or field).
        """
        if not isinstance(data, dict):
            raise ScenarioError(f"{where}: expected a JSON object, got {type(data).__name__}")
        if data.get("format") != SCENARIO_FORMAT:
            raise ScenarioError(
                f"{where}: scenario format must be {SCENARIO_FORMAT!r}, got {data.get('format')!r}"
            )
        try:
            return cls(
                map_name=data["map_name"],
                seed=data["seed"],
                family=data["family"],
                robot_starts=data["robot_starts"],
                robot_goals=data["robot_goals"],
                human_spawn=data["human_spawn"],
                human_start_index=data["human_start_index"],
                human_goal_index=data["human_goal_index"],
                human_routes=tuple(
                    np.array(r, dtype=np.float64).reshape(-1, 2) for r in data["human_routes"]
                ),
                human_speed=data["human_speed"],
                human_group=data.get("human_group"),  # type: ignore[arg-type]
                script=None if data.get("script") is None else Script.from_json(data["script"]),
                recorded=None if data.get("recorded") is None else RecordedPeople.from_json(data["recorded"]),
            )
        except KeyError as err:
            raise ScenarioError(f"{where}: scenario JSON lacks key {err.args[0]!r}") from None
        except (TypeError, ValueError) as err:  # a value of the wrong type or shape, named by __post_init__
            raise ScenarioError(f"{where}: {err}") from None

    def save(self, path: str | Path) -> Path:
        """Write the scenario as JSON; returns the path."""
        path = Path(path)
        path.write_text(json.dumps(self.to_json(), separators=(",", ":")) + "\n")
        return path

    @classmethod
    def load(cls, path: str | Path) -> Scenario:
        """Read a scenario written by `save`.

        Raises:
            FileNotFoundError: no such file.
            ScenarioError: not a scenario file (random bytes, a truncated file or a file of another
                kind included); the message names the file.
        """
        return cls.from_json(read_json(path, "scenario file", ScenarioError), str(path))


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Exact equality of two arrays: shape, dtype and every value."""
    return a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a, b))


# ---------------------------------------------------------------------------- the benchmark generator
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


# ---------------------------------------------------------------------------- fixed test sets
@dataclass(frozen=True)
class TestSet:
    """A fixed list of seeded benchmark scenarios on one map.

    Scenario k has seed `seed(k)`, a 64-bit value derived from (base_seed, k) by numpy's
    SeedSequence, so it is the same on every machine, whether generated alone or in a list, and
    independent of every other scenario.

    Attributes:
        map_name: the map, as `load_map` names it (a shipped name or a map file's path).
        base_seed: the set's seed.
        count: number of scenarios.
        cfg: generator settings.
        name: the set's registry name, if any.
    """

    __test__: ClassVar[bool] = False  # not a pytest test class

    map_name: str
    base_seed: int
    count: int
    cfg: ScenarioConfig = field(default_factory=ScenarioConfig)
    name: str = ""

    def __post_init__(self) -> None:
        check_int("TestSet", "count", self.count, low=0)
        check_int("TestSet", "base_seed", self.base_seed, low=0)

    def __len__(self) -> int:
        return self.count

    def seed(self, k: int) -> int:
        """Seed of scenario k, 0 <= k < count."""
        if not 0 <= k < self.count:
            raise IndexError(
                f"test set {self.name or self.map_name!r}: scenario {k} is outside 0..{self.count - 1}"
            )
        return int(np.random.SeedSequence([self.base_seed, k]).generate_state(1, dtype=np.uint64)[0])

    def _map(self, m: Map | None) -> Map:
        if m is None:
            from socialzoo.maps import map_file as maps

            return maps.load_map(self.map_name)
        if self.map_name not in (m.name, m.path):
            raise ValueError(
                f"test set {self.name or self.map_name!r} is on map {self.map_name!r}, got map {m.name!r}"
            )
        return m

    def scenario(self, k: int, m: Map | None = None) -> Scenario:
        """Scenario k; loads the map by name unless `m` is given."""
        return generate_scenario(self._map(m), self.seed(k), self.cfg)

    def scenarios(self, indices: Sequence[int] | None = None, m: Map | None = None) -> list[Scenario]:
        """Scenarios at `indices` (default: all), each exactly as `scenario(k)` makes it."""
        m = self._map(m)
        ks = range(self.count) if indices is None else indices
        return [generate_scenario(m, self.seed(k), self.cfg) for k in ks]


TEST_SETS: dict[str, TestSet] = {
    "gdc1-test": TestSet("gdc1", 20220001, 2000, name="gdc1-test"),
    "ghc3-test": TestSet("ghc3", 20220002, 2000, name="ghc3-test"),
    "gdc1-quick": TestSet("gdc1", 20220003, 100, name="gdc1-quick"),
    "ghc3-quick": TestSet("ghc3", 20220004, 100, name="ghc3-quick"),
}


# Base seed of every map's validation scenarios: apart from every test set's, for choices
# (training lengths, settings, checkpoints) that must not look at a test set.
VALIDATION_BASE_SEED = 20_229_001
VALIDATION_SIZE = 1000


def validation_set(map_name: str) -> TestSet:
    """Our own validation scenarios on a map ("<map>-val", 1000 scenarios): never a test set."""
    return TestSet(map_name, VALIDATION_BASE_SEED, VALIDATION_SIZE, name=f"{map_name}-val")


def get_test_set(name: str) -> TestSet:
    """A named test set: "gdc1-test", "ghc3-test" (2000 each), "gdc1-quick", "ghc3-quick" (100 each).

    The quick sets have their own base seeds: they are not the first 100 of the full sets, so
    choosing checkpoints on a quick set does not look at the final test scenarios.
    """
    try:
        return TEST_SETS[name]
    except KeyError:
        raise KeyError(f"unknown test set {name!r}; known: {sorted(TEST_SETS)}") from None


# ---------------------------------------------------------------------------- scenarios -> state
def scenarios_to_state(
    scenarios: Sequence[Scenario], num_robots: int = 1, max_humans: int | None = None, route_width: int = 1
) -> WorldState:
    """The batched world state at the start of each scenario (one row per scenario).

    Robots stand on their start poses with zero velocity. Humans stand on their spawns with zero
    velocity, walking towards the second waypoint of their route (index 1; index 0 for a one-point
    route) in direction +1. Humans beyond a scenario's count are absent (mask False, route of one
    point at the origin); routes are padded by repeating their last waypoint.

    Args:
        scenarios: B scenarios.
        num_robots: robots per row R; each scenario must hold at least R robot starts.
        max_humans: human slots H; default the largest head count.
        route_width: route points per slot at least (the longest route's count if more): a batch's
            state takes the rows without padding them again.

    Returns:
        The state, B = len(scenarios).

    Raises:
        ValueError: no scenarios, a scenario with fewer than R robots or more than H humans.
    """
    if len(scenarios) == 0:
        raise ValueError("scenarios_to_state needs at least one scenario")
    if not isinstance(num_robots, int) or num_robots < 1:
        raise ValueError(f"num_robots must be an int >= 1, got {num_robots!r}")
    most = max(s.num_humans for s in scenarios)
    h = most if max_humans is None else max_humans
    b = len(scenarios)
    # Every element is written by write_scenarios.
    state = WorldState(
        robot_pose=np.empty((b, num_robots, 3)),
        robot_vel=np.empty((b, num_robots, 2)),
        robot_goal=np.empty((b, num_robots, 3)),
        human_pos=np.empty((b, h, 2)),
        human_vel=np.empty((b, h, 2)),
        human_pref_speed=np.empty((b, h)),
        human_mask=np.empty((b, h), dtype=bool),
        human_route=np.empty((b, h, route_width, 2)),
        human_route_len=np.empty((b, h), dtype=np.int64),
        human_waypoint=np.empty((b, h), dtype=np.int64),
        human_direction=np.empty((b, h), dtype=np.int64),
        step_count=np.empty(b, dtype=np.int64),
        noise_key=np.empty(b, dtype=np.uint64),
        human_group=np.empty((b, h), dtype=np.int64),
    )
    write_scenarios(state, np.arange(b), scenarios)
    return state


def write_scenarios(state: WorldState, rows: np.ndarray, scenarios: Sequence[Scenario]) -> None:
    """Overwrite `rows` of `state` with the start of each scenario, as `scenarios_to_state` makes
    it (its docstring says what a row holds); the route axis of every row first widens to the
    longest route where that is longer (WorldState.widen_routes). A batch's reset writes its rows
    in place: building a state of the rows and copying it in cost most of a recorded scene's reset.
    The rows' human_model is left as it was (the people's models are the caller's).

    Args:
        state: B rows of R robots and H person slots.
        rows: (len(scenarios),) distinct row indices in 0..B-1.
        scenarios: one per row, each with at least R robots and at most H people.

    Raises:
        ValueError: a scenario with fewer than R robots or more than H humans.
        IndexError: a row outside 0..B-1.
    """
    num_robots, h = state.num_robots, state.max_humans
    for i, s in enumerate(scenarios):
        if s.num_robots < num_robots:
            raise ValueError(
                f"scenario {i} (seed {s.seed}) has {s.num_robots} robots, {num_robots} requested"
            )
    counts = np.array([s.num_humans for s in scenarios], dtype=np.intp)
    if len(counts) and counts.max() > h:
        bad = int(np.argmax(counts))
        raise ValueError(f"scenario {bad} has {counts[bad]} humans, more than max_humans={h}")
    if len(scenarios) == 0:
        return
    lens = [s._route_lens for s in scenarios]
    state.widen_routes(max([1] + [int(x.max()) for x in lens if len(x)]))
    _write_rows(
        np.asarray(rows, dtype=np.intp), counts, np.concatenate(lens),
        np.concatenate([s._route_points for s in scenarios]),
        np.concatenate([s.human_spawn for s in scenarios]),
        np.concatenate([s.human_speed for s in scenarios]),
        np.concatenate([s.human_group for s in scenarios]),
        np.stack([s.robot_starts[:num_robots] for s in scenarios]),
        np.stack([s.robot_goals[:num_robots] for s in scenarios]),
        seed_states([s.seed for s in scenarios], _NOISE_STREAM),
        state.robot_pose, state.robot_vel, state.robot_goal, state.human_pos, state.human_vel,
        state.human_pref_speed, state.human_mask, state.human_route, state.human_route_len,
        state.human_waypoint, state.human_direction, state.step_count, state.noise_key, state.human_group,
    )  # fmt: skip


@kernel
def _write_rows(
    rows, counts, route_lens, route_points, spawn, speed, group, robot_starts, robot_goals, noise_keys,
    robot_pose, robot_vel, robot_goal, human_pos, human_vel, human_pref_speed, human_mask, human_route,
    human_route_len, human_waypoint, human_direction, step_count, noise_key, human_group,
):  # fmt: skip
    """write_scenarios' writes, every field of every row in one compiled loop (a few dozen numpy
    calls per reset otherwise). The people's arrays are the scenarios' end to end (counts[j] people
    in row j; route_points: their routes end to end); only copies, no arithmetic."""
    h, width = human_mask.shape[1], human_route.shape[2]
    person, point = 0, 0
    for j in range(rows.shape[0]):
        b = rows[j]
        if b < 0 or b >= robot_pose.shape[0]:
            raise IndexError("write_scenarios: a row outside the batch")
        for r in range(robot_pose.shape[1]):
            for c in range(3):
                robot_pose[b, r, c] = robot_starts[j, r, c]
                robot_goal[b, r, c] = robot_goals[j, r, c]
            for c in range(2):
                robot_vel[b, r, c] = 0.0
        step_count[b] = 0
        noise_key[b] = noise_keys[j]
        for i in range(h):
            present = i < counts[j]
            n = route_lens[person] if present else 1
            human_mask[b, i] = present
            human_route_len[b, i] = n
            human_waypoint[b, i] = 1 if n > 1 else 0
            human_direction[b, i] = 1
            human_pref_speed[b, i] = speed[person] if present else 0.0
            human_group[b, i] = group[person] if present else -1
            for c in range(2):
                human_pos[b, i, c] = spawn[person, c] if present else 0.0
                human_vel[b, i, c] = 0.0
                # Padded by repeating the last point; an absent slot's one point is the origin.
                for k in range(width):
                    human_route[b, i, k, c] = route_points[point + min(k, n - 1), c] if present else 0.0
            if present:
                person += 1
                point += n
