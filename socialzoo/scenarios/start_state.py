"""Scenarios into the batched WorldState: each row as it stands at the start of its scenario, a new state or rows
of one written in place (a batch's reset) by one compiled kernel."""

from __future__ import annotations

from collections.abc import Sequence

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
    state.widen_routes(max(s._route_width for s in scenarios))
    robot_shape = (len(scenarios), num_robots, 3)
    # Each scenario's arrays end to end (a concatenate costs a fraction of a stack on a reset's few rows).
    _write_rows(
        np.asarray(rows, dtype=np.intp), counts, np.concatenate([s._route_lens for s in scenarios]),
        np.concatenate([s._route_points for s in scenarios]),
        np.concatenate([s.human_spawn for s in scenarios]),
        np.concatenate([s.human_speed for s in scenarios]),
        np.concatenate([s.human_group for s in scenarios]),
        np.concatenate([s.robot_starts[:num_robots] for s in scenarios]).reshape(robot_shape),
        np.concatenate([s.robot_goals[:num_robots] for s in scenarios]).reshape(robot_shape),
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
