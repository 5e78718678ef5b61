"""Episode logs: one episode, sample by sample, in a documented JSON Schema, scored (`socialzoo metrics LOG.json`)
by the function that scores socialzoo's own trajectories (socialzoo.bench.guideline_metrics)."""

from __future__ import annotations

import json
import math
import os
import reprlib
from collections.abc import Sequence
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.guideline_metrics import GuidelineParams, Trajectories, guideline_metrics
from socialzoo.core.files import write_text_atomic

FORMAT = "socialzoo-episode-log"
VERSION = 1
SCHEMA_FILE = "episode_log.schema.json"
# How far a step of `time` may stray from the mean step dt (the metrics' one step), as a share of dt:
# wide enough for the stamps a simulator writes (float32 times, as a JAX or torch simulator keeps
# them, stray by 4e-6 s after a minute; stamps rounded to the millisecond), narrow enough to refuse a
# dropped sample (a step of 2 dt) or a variable step.
_SPACING_TOLERANCE = 0.01


class EpisodeLogError(ValueError):
    """An episode log that cannot be read or breaks the schema: names the file and the field.

    Attributes:
        source: the file (or "<log>" for a log in memory).
        field: the field's path in the log, e.g. "robot.positions[3]" ("(file)" for the whole file).
        problem: what is wrong with it.
    """

    def __init__(self, source: str, field: str, problem: str) -> None:
        super().__init__(f"{source}: {field}: {problem}")
        self.source, self.field, self.problem = source, field, problem


@cache
def schema() -> dict[str, Any]:
    """The episode log's JSON Schema (draft 2020-12), shipped as package data."""
    return dict(json.loads(schema_path().read_text(encoding="utf-8")))


def schema_path() -> Path:
    """Where the schema file lies (for tools that want the file itself)."""
    return Path(str(resources.files("socialzoo.bench") / "schemas" / SCHEMA_FILE))


def _path(parts: Sequence[Any]) -> str:
    """jsonschema's path as "robot.positions[3][0]" ("(top level)" when empty)."""
    text = ""
    for part in parts:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "(top level)"


def _finite(values: Any, where: str, source: str) -> np.ndarray:
    arr = np.asarray(values, dtype=np.float64)
    if not np.isfinite(arr).all():  # Python's json reads NaN and Infinity; the schema cannot refuse them
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise EpisodeLogError(source, where + "".join(f"[{i}]" for i in bad), "must be a finite number")
    return arr


def _points(values: list[Any], n: int, where: str, source: str) -> tuple[np.ndarray, np.ndarray]:
    """(positions (n, 2) with NaN where null, present (n,)) of a per-sample point list."""
    if len(values) != n:
        raise EpisodeLogError(source, where, f"has {len(values)} entries, time has {n}")
    present = np.array([v is not None for v in values], dtype=bool)
    out = np.full((n, 2), np.nan)
    if present.any():
        filled = np.asarray([v for v in values if v is not None], dtype=np.float64)
        if not np.isfinite(filled).all():
            row, col = np.argwhere(~np.isfinite(filled))[0]
            raise EpisodeLogError(
                source, f"{where}[{np.flatnonzero(present)[row]}][{col}]", "must be a finite number"
            )
        out[present] = filled
    return out, present


def _number(v: Any) -> bool:
    return type(v) is int or type(v) is float  # JSON numbers as json.loads reads them (a bool is not one)


def _point(v: Any) -> bool:
    return type(v) is list and len(v) == 2 and _number(v[0]) and _number(v[1])


# The per-sample arrays of the schema (and the walls) in the log, in each of its objects, by kind.
_ARRAYS: dict[str, dict[str, str]] = {
    "": {"time": "numbers", "walls": "segments"},
    "robot": {
        "positions": "points",
        "velocities": "points",
        "headings": "numbers",
        "goal_distance": "numbers",
    },
    "people": {"positions": "maybe_points", "velocities": "maybe_points"},
    "other_robots": {"positions": "maybe_points"},
    "collisions": {"wall": "flags", "human": "flags", "robot": "flags"},
}
# A test of one entry of each kind that accepts exactly what the schema's entry accepts (of the
# types json.loads gives).
_ENTRY_TESTS: dict[str, Any] = {
    "numbers": _number,
    "points": _point,
    "maybe_points": lambda v: v is None or _point(v),
    "flags": lambda v: type(v) is bool,
    "segments": lambda v: type(v) is list and len(v) == 4 and all(map(_number, v)),
}


def _cut(body: Any, where: str) -> Any:
    if type(body) is not dict:
        return body
    out = dict(body)
    for name, kind in _ARRAYS[where].items():
        values = body.get(name)
        if type(values) is list and all(map(_ENTRY_TESTS[kind], values)):
            out[name] = values[:1]
    return out


def _for_schema(data: Any) -> Any:
    """A copy of `data` for jsonschema in which each per-sample array whose entries all pass their
    quick test is cut to its first entry: jsonschema walks every entry through `$ref` and `oneOf`,
    which took minutes on a log of 10,000 samples and 200 people. An array that fails keeps all its
    entries, so the errors (and jsonschema's choice among them) are those of the whole log."""
    if type(data) is not dict:
        return data
    out = _cut(data, "")
    for where in ("robot", "collisions"):
        if where in data:
            out[where] = _cut(data[where], where)
    for where in ("people", "other_robots"):
        if type(data.get(where)) is list:
            out[where] = [_cut(body, where) for body in data[where]]
    return out


def _problem(error: Any) -> str:
    """jsonschema's message with the value it quotes shortened (a whole log quoted is megabytes)."""
    quoted = repr(error.instance)
    if len(quoted) > 80 and error.message.startswith(quoted):
        return reprlib.repr(error.instance) + error.message[len(quoted) :]
    return str(error.message)


def validate_log(data: Any, source: str = "<log>") -> None:
    """Check a log against the schema and its own consistency: every per-sample array as long as
    `time`, `time` increasing and evenly spaced, every number finite.

    Raises:
        EpisodeLogError: the first problem, naming `source` and the field.
    """
    import jsonschema

    if type(data) is list:
        raise EpisodeLogError(
            source,
            "(top level)",
            f"a list of {len(data)} entries is not of type 'object': an episode log is one episode, "
            "one JSON object per file",
        )
    validator = jsonschema.Draft202012Validator(schema())
    error = jsonschema.exceptions.best_match(validator.iter_errors(_for_schema(data)))
    if error is not None:
        raise EpisodeLogError(source, _path(error.absolute_path), _problem(error))
    time = _finite(data["time"], "time", source)
    n = len(time)
    if n > 1:
        steps = np.diff(time)
        dt = float(steps.mean())
        if not (steps > 0).all():
            raise EpisodeLogError(source, "time", "must increase from sample to sample")
        stray = np.abs(steps - dt)
        if stray.max() > _SPACING_TOLERANCE * dt:
            k = int(np.argmax(stray))
            raise EpisodeLogError(
                source,
                "time",
                f"must be evenly spaced (one step dt): the step from time[{k}] to time[{k + 1}] is "
                f"{steps[k]:.6g} s, the mean step {dt:.6g} s (a step may differ from it by "
                f"{_SPACING_TOLERANCE:.0%})",
            )
    if "time_limit" in data:
        _finite(data["time_limit"], "time_limit", source)
    robot = data["robot"]
    for key in ("radius", "goal_radius", "shortest_path_length"):
        if key in robot:
            _finite(robot[key], f"robot.{key}", source)
    _finite(robot["goal"], "robot.goal", source)
    for key in ("positions", "velocities"):
        if key in robot:
            _points(robot[key], n, f"robot.{key}", source)
    for key in ("headings", "goal_distance"):
        if key in robot:
            if len(robot[key]) != n:
                raise EpisodeLogError(source, f"robot.{key}", f"has {len(robot[key])} entries, time has {n}")
            _finite(robot[key], f"robot.{key}", source)
    for group in ("people", "other_robots"):
        for i, body in enumerate(data.get(group, [])):
            _finite(body["radius"], f"{group}[{i}].radius", source)
            for key in ("positions", "velocities"):
                if key in body:
                    _points(body[key], n, f"{group}[{i}].{key}", source)
            for key in ("goal", "goal_radius"):
                if key in body:
                    _finite(body[key], f"{group}[{i}].{key}", source)
    if data.get("walls"):
        _finite(data["walls"], "walls", source)
    for key, flags in data.get("collisions", {}).items():
        if len(flags) != n:
            raise EpisodeLogError(source, f"collisions.{key}", f"has {len(flags)} entries, time has {n}")


def read_episode_log(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The log in file `path`, validated (validate_log).

    Raises:
        EpisodeLogError: the file cannot be read, is not UTF-8 text or is not JSON (a number or a
            nesting past Python's limits included), or the log is invalid.
    """
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as err:
        raise EpisodeLogError(
            source, "(file)", f"is not UTF-8 text: {err.reason} at byte {err.start}"
        ) from None
    except OSError as err:
        raise EpisodeLogError(source, "(file)", f"cannot be read: {err.strerror or err}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise EpisodeLogError(source, "(file)", f"is not JSON: {err}") from None
    except (ValueError, RecursionError) as err:  # json.loads's other refusals: [[[... deep, 5000 digits
        raise EpisodeLogError(source, "(file)", f"is not JSON: {type(err).__name__}: {err}") from None
    validate_log(data, source)
    return dict(data)


def write_episode_log(path: str | os.PathLike[str], log: dict[str, Any]) -> Path:
    """Validate `log` and write it to `path` (a temporary file renamed into place, so a failed
    write leaves no partial file); returns the path.

    Raises:
        EpisodeLogError: the log is invalid (nothing is written).
    """
    validate_log(log, str(Path(path)))
    return write_text_atomic(path, json.dumps(log, allow_nan=False, separators=(",", ":")))


def _point_list(arr: np.ndarray, present: np.ndarray | None = None) -> list[Any]:
    rows = np.asarray(arr, dtype=np.float64).reshape(-1, 2).tolist()
    if present is None:
        return rows
    return [
        row if ok else None for row, ok in zip(rows, np.asarray(present, dtype=bool).tolist(), strict=True)
    ]


def make_episode_log(
    *,
    dt: float,
    robot_pos: Any,
    goal: Any,
    robot_radius: float,
    goal_radius: float,
    robot_vel: Any = None,
    robot_heading: Any = None,
    people_pos: Any = None,
    people_vel: Any = None,
    people_mask: Any = None,
    people_radius: Any = 0.2,
    walls: Any = None,
    others_pos: Any = None,
    others_mask: Any = None,
    others_radius: Any = 0.3,
    others_goal: Any = None,
    shortest_path_length: float | None = None,
    goal_distance: Any = None,
    time_limit: float | None = None,
    wall_contact: Any = None,
    human_contact: Any = None,
    robot_contact: Any = None,
    label: str | None = None,
    source: str | None = None,
) -> dict[str, Any]:
    """An episode log (a dict in the schema) of one episode's arrays: robot_pos (N, 2),
    people_pos (N, H, 2) with people_mask (N, H), walls (W, 4), others_pos (N, K, 2), flags (N,);
    the rest as in socialzoo.bench.guideline_metrics.Trajectories without the batch axis. Sample k
    is at time k dt. Absent people's positions are written as null; another robot whose others_goal
    (K, 2) is NaN, outside the cooperative set, is written without a goal.

    Raises:
        EpisodeLogError: the result breaks the schema (shapes that do not agree, non-finite numbers).
    """
    pos = np.asarray(robot_pos, dtype=np.float64).reshape(-1, 2)
    n = len(pos)
    from socialzoo import __version__

    robot: dict[str, Any] = {
        "radius": float(robot_radius),
        "goal": [float(v) for v in np.asarray(goal, dtype=np.float64).reshape(-1)[:2]],
        "goal_radius": float(goal_radius),
        "positions": _point_list(pos),
    }
    if robot_vel is not None:
        robot["velocities"] = _point_list(robot_vel)
    if robot_heading is not None:
        robot["headings"] = np.asarray(robot_heading, dtype=np.float64).reshape(-1).tolist()
    if shortest_path_length is not None:
        robot["shortest_path_length"] = float(shortest_path_length)
    if goal_distance is not None:
        robot["goal_distance"] = np.asarray(goal_distance, dtype=np.float64).reshape(-1).tolist()
    log: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "source": source or f"socialzoo {__version__}",
        "time": (float(dt) * np.arange(n)).tolist(),
        "robot": robot,
    }
    if label is not None:
        log["label"] = str(label)
    if time_limit is not None:
        log["time_limit"] = float(time_limit)
    for group, bodies, vels, mask, radius in (
        ("people", people_pos, people_vel, people_mask, people_radius),
        ("other_robots", others_pos, None, others_mask, others_radius),
    ):
        if bodies is None:
            continue
        arr = np.asarray(bodies, dtype=np.float64)
        count = arr.shape[1] if arr.ndim == 3 else 0
        here = (
            np.ones((n, count), dtype=bool)
            if mask is None
            else np.asarray(mask, dtype=bool).reshape(n, count)
        )
        radii = np.broadcast_to(np.asarray(radius, dtype=np.float64), (count,))
        entries = []
        for j in range(count):  # one entry per body in the file's layout (not a metric loop)
            entry: dict[str, Any] = {
                "id": j,
                "radius": float(radii[j]),
                "positions": _point_list(arr[:, j], here[:, j]),
            }
            if vels is not None:
                entry["velocities"] = _point_list(np.asarray(vels, dtype=np.float64)[:, j], here[:, j])
            if group == "other_robots" and others_goal is not None:
                goal_j = np.asarray(others_goal, dtype=np.float64)[j, :2]
                if np.isfinite(goal_j).all():  # a NaN goal: outside the cooperative set, no goal in the log
                    entry["goal"] = goal_j.tolist()
            entries.append(entry)
        log[group] = entries
    if walls is not None:
        log["walls"] = np.asarray(walls, dtype=np.float64).reshape(-1, 4).tolist()
    flags = {
        k: np.asarray(v, dtype=bool).reshape(-1).tolist()
        for k, v in (("wall", wall_contact), ("human", human_contact), ("robot", robot_contact))
        if v is not None
    }
    if flags:
        log["collisions"] = flags
    validate_log(log)
    return log


def trace_episode_log(
    trace: Any,
    scene: Any,
    *,
    robot_radius: float | None = None,
    shortest_path_length: float | None = None,
    time_limit: float | None = None,
    source: str | None = None,
) -> dict[str, Any]:
    """The episode log of a recorded replay (socialzoo.render.replay_data.EpisodeTrace, robot 0)
    on its scene (ReplayScene: walls, human radius, goal radius, footprint).

    The robot's world velocity is v (cos heading, sin heading) of the trace's (v, omega); the
    trace's per-step contact flags (the simulator's own collision rules: a human centre within
    0.4 m, the footprint touching a wall) become the log's collision flags at samples 1..T.

    Args:
        trace: the EpisodeTrace.
        scene: its ReplayScene.
        robot_radius: the robot's disc for the gaps (default: the scene's robot_radius for a
            round robot, else the circle round the footprint, hypot(length, width) / 2).
        shortest_path_length: SPL's l, m (default: none in the log: the straight line).
        time_limit: the episode's time limit, s (for the timeout).
        source: the log's source line.
    """
    pose = np.asarray(trace.robot_pose, dtype=np.float64)
    speed = np.asarray(trace.robot_vel, dtype=np.float64)[:, 0]
    vel = speed[:, None] * np.stack([np.cos(pose[:, 2]), np.sin(pose[:, 2])], axis=1)
    if robot_radius is not None:
        radius = robot_radius
    elif scene.robot_radius is not None:  # a round robot (CrowdNav's), not the circle round its square
        radius = scene.robot_radius
    else:
        radius = math.hypot(scene.robot_length, scene.robot_width) / 2
    human = np.concatenate([[False], np.asarray(trace.human_collisions) > 0])
    wall = np.concatenate([[False], np.asarray(trace.wall_collision, dtype=bool)])
    return make_episode_log(
        dt=trace.dt,
        robot_pos=pose[:, :2],
        robot_vel=vel,
        robot_heading=pose[:, 2],
        goal=np.asarray(trace.goal)[:2],
        robot_radius=radius,
        goal_radius=scene.goal_radius,
        people_pos=trace.human_pos,
        people_vel=trace.human_vel,
        people_mask=trace.human_present,
        people_radius=scene.human_radius,
        walls=scene.walls,
        shortest_path_length=shortest_path_length,
        time_limit=time_limit,
        wall_contact=wall,
        human_contact=human,
        label=trace.label,
        source=source,
    )


def log_trajectories(log: dict[str, Any], source: str = "<log>") -> Trajectories:
    """The arrays of guideline_metrics (a batch of one) of a validated log (a person's velocity is
    the log's where given, else from the positions)."""
    time = np.asarray(log["time"], dtype=np.float64)
    n = len(time)
    dt = float(np.diff(time).mean()) if n > 1 else 1.0
    robot = log["robot"]
    fields: dict[str, Any] = {
        "dt": dt,
        "robot_pos": _points(robot["positions"], n, "robot.positions", source)[0][None],
        "goal": np.asarray(robot["goal"], dtype=np.float64)[None],
        "robot_radius": float(robot["radius"]),
        "goal_radius": float(robot["goal_radius"]),
        "walls": np.asarray(log.get("walls", []), dtype=np.float64).reshape(-1, 4),
    }
    if "velocities" in robot:
        fields["robot_vel"] = _points(robot["velocities"], n, "robot.velocities", source)[0][None]
    if "shortest_path_length" in robot:
        fields["shortest_path"] = np.array([float(robot["shortest_path_length"])])
    if "goal_distance" in robot:
        fields["goal_distance"] = np.asarray(robot["goal_distance"], dtype=np.float64)[None]
    if "time_limit" in log:
        fields["time_limit"] = np.array([float(log["time_limit"])])
    for group, prefix in (("people", "people"), ("other_robots", "others")):
        bodies = log.get(group, [])
        if not bodies:
            continue
        read = [_points(b["positions"], n, f"{group}[{i}].positions", source) for i, b in enumerate(bodies)]
        fields[f"{prefix}_pos"] = np.stack([p for p, _ in read], axis=1)[None]
        fields[f"{prefix}_mask"] = np.stack([m for _, m in read], axis=1)[None]
        fields[f"{prefix}_radius"] = np.array([float(b["radius"]) for b in bodies])
        if group == "people" and any("velocities" in b for b in bodies):
            vels = [
                _points(b["velocities"], n, f"people[{i}].velocities", source)[0]
                if "velocities" in b
                else np.full((n, 2), np.nan)  # not given: from the positions
                for i, b in enumerate(bodies)
            ]
            fields["people_vel"] = np.stack(vels, axis=1)[None]
        if group == "other_robots" and any("goal" in b for b in bodies):
            # Robots without a goal (NaN) are outside the cooperative set.
            fields["others_goal"] = np.array(
                [b.get("goal", [np.nan, np.nan]) for b in bodies], dtype=np.float64
            )[None]
            fields["others_goal_radius"] = np.array(
                [float(b.get("goal_radius", robot["goal_radius"])) for b in bodies]
            )[None]
    flags = log.get("collisions", {})
    for key, name in (("wall", "wall_contact"), ("human", "human_contact"), ("robot", "robot_contact")):
        if key in flags:
            fields[name] = np.asarray(flags[key], dtype=bool)[None]
    return Trajectories(**fields)


def log_metrics(
    log: dict[str, Any], params: GuidelineParams | None = None, source: str = "<log>"
) -> dict[str, Any]:
    """The Table I metrics of one validated log: {name: bool, int or float} in registry order."""
    found = guideline_metrics(log_trajectories(log, source), params)
    return {name: values[0].item() for name, values in found.items()}
