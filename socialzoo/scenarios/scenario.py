"""A scenario: who starts and ends where on a map and how its people walk, a read-only value that saves to JSON
exactly (drawn by socialzoo.scenarios.generator for the benchmark, by socialzoo.scenarios.families on small maps)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.core.files import read_json, write_text_atomic
from socialzoo.scenarios.recorded_people import RecordedPeople
from socialzoo.scenarios.script import Script

SCENARIO_FORMAT = "socialzoo-scenario/1"


class ScenarioError(ValueError):
    """A scenario file or scenario JSON that cannot be read: the message names the file and field."""


def _frozen_array(value: Any, dtype: type, shape: tuple[int | None, ...], what: str) -> np.ndarray:
    """A read-only copy of `value` as `dtype`, checked against `shape` (None = any length)."""
    try:
        arr: np.ndarray = np.array(value, dtype=dtype)
    except OverflowError:  # a JSON int of more digits than the dtype holds
        raise ValueError(
            f"Scenario.{what} holds a number beyond the range of {np.dtype(dtype).name}"
        ) from None
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
        seed: the seed it was generated from, an int in [0, 2**64).
        robot_starts: (R, 3) start poses (x, y, theta) of the R robots; the benchmark has R = 1.
        robot_goals: (R, 3) goal poses.
        human_spawn: (n, 2) spawn positions (the start pose position plus jitter).
        human_start_index: (n,) legal-pose index of each human's start, -1 if not a legal pose.
        human_goal_index: (n,) legal-pose index of each human's goal, -1 if not a legal pose.
        human_routes: n arrays (L_i, 2), route waypoints from the human's start to its goal.
        human_speed: (n,) preferred walking speed, m/s, >= 0.
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
    # Derived in __post_init__: the routes end to end, their lengths and the longest (see there).
    _route_points: np.ndarray = field(init=False, repr=False)
    _route_lens: np.ndarray = field(init=False, repr=False)
    _route_width: int = field(init=False, repr=False)

    def first_outside(self, low: np.ndarray, high: np.ndarray) -> str | None:
        """The first of the robots' starts and goals, the people's spawns and route points that
        lies outside the box [low, high] (2,), named with its position; None if all lie inside."""
        parts = (
            ("robot start", self.robot_starts[:, :2]),
            ("robot goal", self.robot_goals[:, :2]),
            ("person spawn", self.human_spawn),
            ("route point", self._route_points),
        )
        for what, points in parts:
            out = np.flatnonzero(((points < low) | (points > high)).any(axis=1))
            if len(out):
                x, y = points[out[0]]
                return f"{what} {out[0]} at ({x:.2f}, {y:.2f})"
        return None

    def __post_init__(self) -> None:
        for name in ("map_name", "family"):
            if not isinstance(getattr(self, name), str):
                raise ValueError(f"Scenario.{name} must be a string, got {getattr(self, name)!r}")
        seed = self.seed
        if (
            isinstance(seed, (bool, np.bool_))
            or not isinstance(seed, (int, np.integer))
            or not 0 <= seed < 2**64
        ):
            raise ValueError(f"Scenario.seed must be an int in [0, 2**64), got {seed!r}")
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
        for name, low in (("human_start_index", -1), ("human_goal_index", -1), ("human_speed", 0)):
            below = np.flatnonzero(getattr(self, name) < low)
            if len(below):
                k = int(below[0])
                raise ValueError(
                    f"Scenario.{name}[{k}] must be >= {low}, got {getattr(self, name)[k].item()!r}"
                )
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
        # The routes end to end, their lengths and the longest, once: a reset stacks a few scenarios'
        # blocks instead of every person's route (a kept scenario, as recorded scenes' are, is reset often).
        object.__setattr__(self, "_route_lens", np.array([len(r) for r in routes], dtype=np.intp))
        object.__setattr__(self, "_route_width", max([1] + [len(r) for r in routes]))
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
        # Every array field (robot_starts ... human_group; the derived ones follow from them).
        same_arrays = all(
            _same(getattr(self, f.name), getattr(other, f.name))
            for f in fields(self)
            if f.init and isinstance(getattr(self, f.name), np.ndarray)
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
                type or shape or out of range (a negative speed, a seed outside [0, 2**64)); the
                message starts with `where` and names the key or field.
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
        except (TypeError, ValueError, OverflowError) as err:  # a bad value, named by __post_init__
            raise ScenarioError(f"{where}: {err}") from None

    def save(self, path: str | Path) -> Path:
        """Write the scenario as JSON, whole or not at all (core.files.write_text_atomic); returns the path."""
        return write_text_atomic(path, json.dumps(self.to_json(), separators=(",", ":")) + "\n")

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
