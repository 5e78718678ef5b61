"""GoAlone alone (no humans) reaches the goal from every legal start to every legal goal.

On GDC1 all 26 x 25 ordered pairs of legal poses run as one batch (B = 650) through the
navigator, the GoAlone sub-policy and the robot motion model, within the benchmark's 3200-step
limit, and no robot's footprint ever touches a wall; likewise on the other shipped small maps.
"""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.core.config import WorldConfig
from socialzoo.core.robot import step_robot
from socialzoo.nav import maps
from socialzoo.nav.graph import NavGraph, graph_of
from socialzoo.nav.local_planner import LocalPlannerConfig
from socialzoo.nav.maps import Map
from socialzoo.nav.navigator import Navigator
from socialzoo.nav.subpolicies import GO_ALONE, HALT, SubPolicyConfig, subpolicy_commands

TIME_LIMIT = 3200  # steps (SPEC section 2)
SUCCESS_DISTANCE = 0.5  # m


def gdc1() -> tuple[Map, NavGraph]:
    """The shipped GDC1 map and its graph, or one built from the reference data before it ships."""
    m = maps.load_map("gdc1")
    return m, graph_of(m)


def go_alone_all_pairs(m: Map, graph: NavGraph) -> tuple[list[str], np.ndarray]:
    """Run GoAlone from every legal pose to every other one at once; (failures, steps taken)."""
    walls = m.wall_index
    world = WorldConfig()
    robot = world.robot
    poses = m.legal_poses
    start, goal = np.nonzero(~np.eye(len(poses), dtype=bool))
    n = len(start)
    pose = poses[start].copy()
    vel = np.zeros((n, 2))
    target = poses[goal, :2]
    nav = Navigator(graph, n)
    nav.reset(np.arange(n), pose[:, None, :2], target[:, None])
    no_humans = (np.zeros((n, 0, 2)), np.zeros((n, 0, 2)), np.zeros((n, 0), dtype=bool))
    sub, planner = SubPolicyConfig(), LocalPlannerConfig()
    done = np.zeros(n, dtype=bool)
    hit_wall = np.zeros(n, dtype=bool)
    steps = np.full(n, TIME_LIMIT)
    for t in range(TIME_LIMIT):
        carrot = nav.update(pose[:, None, :2])[:, 0]
        action = np.where(done, HALT, GO_ALONE)  # finished robots halt (and cost nothing)
        command, halt, _ = subpolicy_commands(
            action, pose, vel, carrot, *no_humans, walls, sub, planner, robot, world.dt
        )
        pose, vel = step_robot(pose, vel, command, halt, world.dt, robot)
        hit = walls.footprint_hits(pose, robot.half_length, robot.half_width) & ~done
        reached = (np.hypot(*(pose[:, :2] - target).T) < SUCCESS_DISTANCE) & ~done
        hit_wall |= hit
        steps[hit | reached] = t + 1
        done |= hit | reached
        if done.all():
            break
    why = np.where(hit_wall, "wall", "timeout")
    failed = [
        f"{m.name} {start[k]}->{goal[k]} ({why[k]} at {pose[k, :2].round(2).tolist()})"
        for k in np.flatnonzero(~done | hit_wall)
    ]
    return failed, steps


def test_go_alone_reaches_every_goal_on_gdc1():
    m, graph = gdc1()
    failed, steps = go_alone_all_pairs(m, graph)
    assert not failed, f"{len(failed)} of {len(steps)} pairs failed: " + ", ".join(failed)
    # A typical trip is well inside the limit.
    assert np.median(steps) * WorldConfig().dt < 40.0


SMALL_MAPS = [name for name in maps.list_maps() if name not in ("gdc1", "ghc3")]


@pytest.mark.parametrize("name", SMALL_MAPS)
def test_go_alone_reaches_every_goal_on_the_small_maps(name):
    m = maps.load_map(name)
    failed, steps = go_alone_all_pairs(m, graph_of(m))
    assert not failed, f"{len(failed)} of {len(steps)} pairs failed: " + ", ".join(failed)


def test_go_alone_reaches_every_goal_on_ghc3():
    """The transfer map's generated poses are all reachable from each other within 80 s."""
    m = maps.load_map("ghc3")
    failed, steps = go_alone_all_pairs(m, graph_of(m))
    assert not failed, f"{len(failed)} of {len(steps)} pairs failed: " + ", ".join(failed)
