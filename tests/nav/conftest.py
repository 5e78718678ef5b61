"""Fixtures shared by the navigation tests."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest


def _random_building(rng: np.random.Generator) -> np.ndarray:
    """A grid of rooms: walls every 4 m with 1 m door gaps, plus a few random segments; (W, 4)."""
    walls = []
    for x in range(0, 21, 4):
        for y0 in range(0, 20, 4):
            walls.append((x, y0, x, y0 + 1.5))
            walls.append((x, y0 + 2.5, x, y0 + 4))
            walls.append((y0, x, y0 + 1.5, x))
            walls.append((y0 + 2.5, x, y0 + 4, x))
    a = rng.uniform(0, 20, (15, 2))
    extra = np.hstack((a, a + rng.uniform(-1.5, 1.5, (15, 2))))
    return np.vstack((np.array(walls, float), extra))


@pytest.fixture
def random_building() -> Callable[[np.random.Generator], np.ndarray]:
    """Walls of a 20 m x 20 m building of 4 m rooms with doors, drawn from a generator."""
    return _random_building


def run_go_alone(m, starts: np.ndarray, goals: np.ndarray, max_steps: int = 3200) -> tuple[np.ndarray, ...]:
    """GoAlone without humans from each start (K, 3) to each goal (K, 2), as one batch, through the
    navigator (its carrot kept in sight, as the envs do), the sub-policy and the robot motion model.

    Returns:
        (reached (K,) bool, hit_wall (K,) bool, steps (K,) int, final pose (K, 3)).
    """
    from socialzoo.core.config import WorldConfig
    from socialzoo.core.robot import step_robot
    from socialzoo.nav.distance_field import distance_field
    from socialzoo.nav.graph import graph_of
    from socialzoo.nav.local_planner import LocalPlannerConfig
    from socialzoo.nav.navigator import Navigator, Sight
    from socialzoo.nav.subpolicies import GO_ALONE, HALT, SubPolicyConfig, subpolicy_commands

    walls = m.wall_index
    world = WorldConfig()
    robot = world.robot
    sub, planner = SubPolicyConfig(), LocalPlannerConfig()
    n = len(starts)
    pose = np.asarray(starts, dtype=np.float64).copy()
    vel = np.zeros((n, 2))
    target = np.asarray(goals, dtype=np.float64)[:, :2]
    field = distance_field(walls, planner.field_resolution, planner.field_range, planner.field_pad)
    nav = Navigator(graph_of(m), n, sight=Sight(field, planner.wall_distance))
    nav.reset(np.arange(n), pose[:, None, :2], target[:, None])
    no_humans = (np.zeros((n, 0, 2)), np.zeros((n, 0, 2)), np.zeros((n, 0), dtype=bool))
    done = np.zeros(n, dtype=bool)
    reached = np.zeros(n, dtype=bool)
    hit_wall = np.zeros(n, dtype=bool)
    steps = np.full(n, max_steps)
    for t in range(max_steps):
        carrot = nav.update(pose[:, None, :2])[:, 0]
        action = np.where(done, HALT, GO_ALONE)  # finished robots halt (and cost nothing)
        command, halt, _ = subpolicy_commands(
            action, pose, vel, carrot, *no_humans, walls, sub, planner, robot, world.dt
        )
        pose, vel = step_robot(pose, vel, command, halt, world.dt, robot)
        hit = walls.footprint_hits(pose, robot.half_length, robot.half_width) & ~done
        arrived = (np.hypot(*(pose[:, :2] - target).T) < 0.5) & ~done
        hit_wall |= hit
        reached |= arrived
        steps[hit | arrived] = t + 1
        done |= hit | arrived
        if done.all():
            break
    return reached, hit_wall, steps, pose


@pytest.fixture
def go_alone() -> Callable[..., tuple[np.ndarray, ...]]:
    """`run_go_alone`: GoAlone without humans on a batch of start/goal pairs."""
    return run_go_alone
