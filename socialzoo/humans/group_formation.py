"""Walking groups in a scenario: some of its people walk together, in groups of 2 to 4 (`with_groups`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from socialzoo.maps.map_file import Map
from socialzoo.scenarios.generator import spawn_points
from socialzoo.scenarios.scenario import Scenario

# Sizes a group may have, and the spacing of members walking abreast, m.
GROUP_SIZES = (2, 3, 4)
ABREAST_SPACING = 0.7
# Mixed with the scenario's seed for the groups' generator.
_GROUP_STREAM = 0x67726F757073  # "groups"


def draw_group_sizes(num_people: int, weights: tuple[float, ...], rng: np.random.Generator) -> list[int]:
    """Sizes of consecutive groups covering `num_people` people: each drawn from GROUP_SIZES with
    `weights`, the last one cut to the people left; one person left over walks alone (size 1)."""
    p = np.asarray(weights, dtype=np.float64)
    p = p / p.sum()
    sizes: list[int] = []
    left = num_people
    while left > 0:
        size = min(int(rng.choice(GROUP_SIZES, p=p)), left)
        sizes.append(size)
        left -= size
    return sizes


def with_groups(
    scenario: Scenario, m: Map, members: np.ndarray, weights: tuple[float, ...], spawn_clearance: float = 0.2
) -> Scenario:
    """The scenario with the people `members` marks walking in groups.

    The chosen people form groups in their order: each group takes a size drawn from the size weights,
    and its members take the first member's start, goal and route and spawn abreast of it (Moussaid et
    al. 2010: small groups walk side by side at low density), 0.7 m apart across the first walking
    direction, or jittered around the first member where a wall is in the way. The draws come from a
    generator of the scenario's seed, so the groups of a scenario are the same every time.

    Args:
        scenario: the scenario.
        m: its map (walls for the spawns).
        members: (n,) bool, the people who walk in groups.
        weights: weights of groups of 2, 3 and 4 people.
        spawn_clearance: a member's spawn closer than this to a wall is jittered instead, m.

    Returns:
        A new scenario (Scenario.human_group set, members' routes and spawns replaced), or
        `scenario` itself when nobody walks in a group.
    """
    chosen = np.flatnonzero(np.asarray(members, dtype=bool))
    if len(chosen) < 2:
        return scenario
    rng = np.random.default_rng([int(scenario.seed), _GROUP_STREAM])
    group = np.array(scenario.human_group)
    start = np.array(scenario.human_start_index)
    goal = np.array(scenario.human_goal_index)
    speed = np.array(scenario.human_speed)
    spawn = np.array(scenario.human_spawn)
    routes = list(scenario.human_routes)
    poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)
    first = 0
    for size in draw_group_sizes(len(chosen), weights, rng):
        people = chosen[first : first + size]
        first += size
        if size < 2:
            continue
        leader, others = int(people[0]), people[1:]
        group[people] = leader
        start[others] = start[leader]
        goal[others] = goal[leader]
        # A group walks at its slowest member's pace (Moussaid: groups are slower than singles).
        speed[people] = speed[people].min()
        route = routes[leader]
        for k in others:
            routes[int(k)] = route
        ahead = route[1] if len(route) > 1 else route[0]
        heading = ahead - spawn[leader]
        norm = float(np.hypot(*heading))
        across = np.array([-heading[1], heading[0]]) / norm if norm > 1e-9 else np.array([0.0, 1.0])
        rank = np.arange(1, size)
        offset = ((rank + 1) // 2 * np.where(rank % 2 == 1, 1.0, -1.0))[:, None] * ABREAST_SPACING * across
        # Re-drawn members fall back to the leader's start pose, like every spawn of the generator.
        home = poses[start[leader], :2] if start[leader] >= 0 else spawn[leader]
        anchor = np.repeat(home[None], size - 1, axis=0)
        target = np.repeat(ahead[None], size - 1, axis=0)
        abreast = [spawn[leader] - home + offset]

        def draw(k: int, _first: list[np.ndarray] = abreast) -> np.ndarray:
            # The abreast places first, then jitter around the leader.
            return _first.pop() if _first and len(_first[0]) == k else rng.uniform(-0.5, 0.5, size=(k, 2))

        placed = spawn_points(m.wall_index, anchor, target, draw, spawn_clearance, 10)
        # Two people on the same point would feel no force from each other: part them a little.
        same = np.all(placed == spawn[leader], axis=1) | np.all(placed == home, axis=1)
        placed[same] += 0.05 * rank[same, None] * across
        spawn[others] = placed
    return dataclasses.replace(
        scenario,
        human_group=group,
        human_start_index=start,
        human_goal_index=goal,
        human_speed=speed,
        human_spawn=spawn,
        human_routes=tuple(routes),
    )
