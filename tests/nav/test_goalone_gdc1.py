"""GoAlone alone (no humans) reaches the goal from every legal start to every legal goal.

On GDC1 all 26 x 25 ordered pairs of legal poses run as one batch (B = 650) through the
navigator, the GoAlone sub-policy and the robot motion model, within the benchmark's 3200-step
limit, and no robot's footprint ever touches a wall; likewise on the other shipped small maps.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from socialzoo.core.config import WorldConfig
from socialzoo.maps import map_file as maps
from socialzoo.maps.map_file import Map
from socialzoo.nav.graph import NavGraph, graph_of

TIME_LIMIT = 3200  # steps (SPEC section 2)
SUCCESS_DISTANCE = 0.5  # m


def gdc1() -> tuple[Map, NavGraph]:
    """The shipped GDC1 map and its graph, or one built from the reference data before it ships."""
    m = maps.load_map("gdc1")
    return m, graph_of(m)


def go_alone_all_pairs(
    m: Map, go_alone: Callable[..., tuple[np.ndarray, ...]]
) -> tuple[list[str], np.ndarray]:
    """Run GoAlone from every legal pose to every other one at once; (failures, steps taken)."""
    poses = m.legal_poses
    start, goal = np.nonzero(~np.eye(len(poses), dtype=bool))
    reached, hit_wall, steps, pose = go_alone(m, poses[start], poses[goal, :2], TIME_LIMIT)
    why = np.where(hit_wall, "wall", "timeout")
    failed = [
        f"{m.name} {start[k]}->{goal[k]} ({why[k]} at {pose[k, :2].round(2).tolist()})"
        for k in np.flatnonzero(~reached | hit_wall)
    ]
    return failed, steps


def test_go_alone_reaches_every_goal_on_gdc1(go_alone):
    m, _ = gdc1()
    failed, steps = go_alone_all_pairs(m, go_alone)
    assert not failed, f"{len(failed)} of {len(steps)} pairs failed: " + ", ".join(failed)
    # A typical trip is well inside the limit.
    assert np.median(steps) * WorldConfig().dt < 40.0


SMALL_MAPS = [name for name in maps.list_maps() if name not in ("gdc1", "ghc3")]


@pytest.mark.parametrize("name", SMALL_MAPS)
def test_go_alone_reaches_every_goal_on_the_small_maps(name, go_alone):
    m = maps.load_map(name)
    failed, steps = go_alone_all_pairs(m, go_alone)
    assert not failed, f"{len(failed)} of {len(steps)} pairs failed: " + ", ".join(failed)


def test_go_alone_reaches_every_goal_on_ghc3(go_alone):
    """The transfer map's generated poses are all reachable from each other within 80 s."""
    m = maps.load_map("ghc3")
    failed, steps = go_alone_all_pairs(m, go_alone)
    assert not failed, f"{len(failed)} of {len(steps)} pairs failed: " + ", ".join(failed)
