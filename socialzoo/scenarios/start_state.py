"""Scenarios into the batched WorldState: each row as it stands at the start of its scenario, a new state or rows
of one written in place (a batch's reset) by one compiled kernel."""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.core.seed_hash import seed_states
from socialzoo.core.state import WorldState
from socialzoo.scenarios.scenario import Scenario

# Mixed with a scenario's seed to derive its counter-based noise key (see core.noise).
_NOISE_STREAM = 0x6E6F697365  # "noise"


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
        scenarios: one per row, each with at least R robots and at most H humans.

    Raises:
        ValueError: a scenario with fewer than R robots or more than H humans.
        IndexError: a row outside 0..B-1.
    """
    if len(scenarios) == 0:
        return
    starts = _Starts.of(scenarios, state.num_robots, state.max_humans)
    state.widen_routes(max(s._route_width for s in scenarios))
    _write(state, rows, np.arange(len(scenarios)), starts, [s.seed for s in scenarios])


class StartStore:
    """The starts of the scenarios that a batch's rows are reset from again and again, each stored
    once: `write` is write_scenarios, but a reset from stored scenarios writes its rows from the store
    instead of gathering every scenario's arrays again (most of a recorded scene's write_scenarios).

    A scenario is stored the second time a reset meets it. What write_scenarios writes is a function of
    the scenario's arrays and its seed; a renamed copy (Scenario.with_seed, as a family that keeps its
    scenarios makes on every reset: the recorded scenes keep each track's episode) shares its origin's
    arrays, and every other scenario has arrays of its own (__post_init__ derives _route_points anew).
    So the store names a start by its _route_points array (held here, so that its id stays its own),
    and only the seed (the noise key) is read from the scenario on each reset. A family that makes new
    scenarios on every reset never meets one twice: its resets cost only a weak note of each. A stored
    scenario was checked by write_scenarios when it was met (the store's R and H are the states').

    Args:
        num_robots: R of the states the store writes.
        max_humans: H.
    """

    def __init__(self, num_robots: int, max_humans: int) -> None:
        self.num_robots, self.max_humans = num_robots, max_humans
        # _route_points' id -> its entry, and the arrays themselves (the ids stay theirs).
        self._entry: dict[int, int] = {}
        self._held: list[np.ndarray] = []
        # Scenarios met once, by their _route_points' id (the note dies with them).
        self._met: weakref.WeakValueDictionary[int, np.ndarray] = weakref.WeakValueDictionary()
        # Per entry its longest route; the store's arrays (longer than used) and the people and
        # route points used.
        self._width: list[int] = []
        self._starts = _Starts.of([], num_robots, max_humans)
        self._people = self._points = 0

    def __getstate__(self) -> dict[str, object]:
        # A copy (pickled with the env: vector envs' workers) holds the same arrays at other ids, and
        # weak notes do not pickle: the entries are named again and the notes start over.
        return {k: v for k, v in self.__dict__.items() if k not in ("_entry", "_met")}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._entry = {id(points): k for k, points in enumerate(self._held)}
        self._met = weakref.WeakValueDictionary()

    def write(self, state: WorldState, rows: np.ndarray, scenarios: Sequence[Scenario]) -> None:
        """write_scenarios(state, rows, scenarios): from the store where it holds every scenario, else
        as write_scenarios writes them, storing those met before."""
        entries = [self._entry.get(id(s._route_points)) for s in scenarios]
        if None not in entries:
            if entries:
                state.widen_routes(max([self._width[e] for e in entries]))  # type: ignore[index]
                _write(
                    state, rows, np.array(entries, dtype=np.intp), self._starts, [s.seed for s in scenarios]
                )
            return
        write_scenarios(state, rows, scenarios)  # checks them all
        for s in scenarios:
            key = id(s._route_points)
            if key in self._entry:
                continue
            if self._met.get(key) is s._route_points:
                self._add(s)
            else:
                self._met[key] = s._route_points

    def _add(self, scenario: Scenario) -> int:
        """Store `scenario`'s start and return its entry. The
        store's arrays grow by doubling (a scene's first resets add most of its episodes one by one)."""
        block = _Starts.of([scenario], self.num_robots, self.max_humans)
        entry, people, points = len(self._held), self._people, self._points
        grown: dict[str, np.ndarray] = {}
        for name, size, value in (
            ("count", entry, block.count), ("person_at", entry, block.person_at + people),
            ("point_at", entry, block.point_at + points), ("robot_starts", entry, block.robot_starts),
            ("robot_goals", entry, block.robot_goals), ("route_lens", people, block.route_lens),
            ("spawn", people, block.spawn), ("speed", people, block.speed), ("group", people, block.group),
            ("route_points", points, block.route_points),
        ):  # fmt: skip
            array = getattr(self._starts, name)
            if size + len(value) > len(array):
                wider = np.zeros(
                    (max(size + len(value), 2 * len(array)), *array.shape[1:]), dtype=array.dtype
                )
                wider[:size] = array[:size]
                array = wider
            array[size : size + len(value)] = value
            grown[name] = array
        self._starts = _Starts(**grown)
        self._people += len(block.route_lens)
        self._points += len(block.route_points)
        self._held.append(scenario._route_points)
        self._entry[id(scenario._route_points)] = entry
        self._width.append(scenario._route_width)
        return entry


@dataclass(frozen=True)
class _Starts:
    """Scenarios' starts end to end: per scenario its people's count and where its first person and
    first route point are; per person its route's length, spawn, speed and group; the routes' points;
    per scenario its R robots' starts and goals."""

    count: np.ndarray
    person_at: np.ndarray
    point_at: np.ndarray
    route_lens: np.ndarray
    spawn: np.ndarray
    speed: np.ndarray
    group: np.ndarray
    route_points: np.ndarray
    robot_starts: np.ndarray
    robot_goals: np.ndarray

    @staticmethod
    def of(scenarios: Sequence[Scenario], num_robots: int, max_humans: int) -> _Starts:
        """The starts of `scenarios`, refused (ValueError) for fewer than R robots or more than H people."""
        for i, s in enumerate(scenarios):
            if s.num_robots < num_robots:
                raise ValueError(
                    f"scenario {i} (seed {s.seed}) has {s.num_robots} robots, {num_robots} requested"
                )
        count = np.array([s.num_humans for s in scenarios], dtype=np.intp)
        if len(count) and count.max() > max_humans:
            bad = int(np.argmax(count))
            raise ValueError(f"scenario {bad} has {count[bad]} humans, more than max_humans={max_humans}")
        points = np.array([len(s._route_points) for s in scenarios], dtype=np.intp)
        robot_shape = (len(scenarios), num_robots, 3)
        # Each scenario's arrays end to end (a concatenate costs a fraction of a stack on a reset's few rows).
        return _Starts(
            count=count,
            person_at=np.cumsum(count) - count,
            point_at=np.cumsum(points) - points,
            route_lens=np.concatenate([s._route_lens for s in scenarios] or [np.zeros(0, dtype=np.intp)]),
            spawn=np.concatenate([s.human_spawn for s in scenarios] or [np.zeros((0, 2))]),
            speed=np.concatenate([s.human_speed for s in scenarios] or [np.zeros(0)]),
            group=np.concatenate([s.human_group for s in scenarios] or [np.zeros(0, dtype=np.int64)]),
            route_points=np.concatenate([s._route_points for s in scenarios] or [np.zeros((0, 2))]),
            robot_starts=np.concatenate(
                [s.robot_starts[:num_robots] for s in scenarios] or [np.zeros((0, 3))]
            ).reshape(robot_shape),
            robot_goals=np.concatenate(
                [s.robot_goals[:num_robots] for s in scenarios] or [np.zeros((0, 3))]
            ).reshape(robot_shape),
        )


def _write(
    state: WorldState, rows: np.ndarray, entries: np.ndarray, starts: _Starts, seeds: list[int]
) -> None:
    """Write `rows` of `state` from `starts`' scenarios `entries` (one per row) under `seeds`, the
    route axis wide enough (widen_routes first)."""
    _write_rows(
        np.asarray(rows, dtype=np.intp), entries, starts.count, starts.person_at, starts.point_at,
        starts.route_lens, starts.route_points, starts.spawn, starts.speed, starts.group, starts.robot_starts,
        starts.robot_goals, seed_states(seeds, _NOISE_STREAM),
        state.robot_pose, state.robot_vel, state.robot_goal, state.human_pos, state.human_vel,
        state.human_pref_speed, state.human_mask, state.human_route, state.human_route_len,
        state.human_waypoint, state.human_direction, state.step_count, state.noise_key, state.human_group,
    )  # fmt: skip


@kernel
def _write_rows(
    rows, entries, counts, person_at, point_at, route_lens, route_points, spawn, speed, group, robot_starts,
    robot_goals, noise_keys,
    robot_pose, robot_vel, robot_goal, human_pos, human_vel, human_pref_speed, human_mask, human_route,
    human_route_len, human_waypoint, human_direction, step_count, noise_key, human_group,
):  # fmt: skip
    """write_scenarios' writes, every field of every row in one compiled loop (a few dozen numpy
    calls per reset otherwise). Row rows[j] takes scenario e = entries[j] of the starts (_Starts):
    its counts[e] people from person_at[e] on, their routes end to end from point_at[e] on; only copies,
    no arithmetic."""
    h, width = human_mask.shape[1], human_route.shape[2]
    for j in range(rows.shape[0]):
        b, e = rows[j], entries[j]
        person, point = person_at[e], point_at[e]
        if b < 0 or b >= robot_pose.shape[0]:
            raise IndexError("write_scenarios: a row outside the batch")
        for r in range(robot_pose.shape[1]):
            for c in range(3):
                robot_pose[b, r, c] = robot_starts[e, r, c]
                robot_goal[b, r, c] = robot_goals[e, r, c]
            for c in range(2):
                robot_vel[b, r, c] = 0.0
        step_count[b] = 0
        noise_key[b] = noise_keys[j]
        for i in range(h):
            present = i < counts[e]
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
