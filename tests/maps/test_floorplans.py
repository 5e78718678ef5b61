"""Synthetic floor plans: seeded, doors as wide as asked, the inside point in the free space."""

import numpy as np
import pytest

from socialzoo.core.walls import WallIndex
from socialzoo.maps import floorplans
from socialzoo.maps.roadmap import free_space


@pytest.mark.parametrize("name", sorted(floorplans.PLANS))
def test_plans_are_seeded_and_their_inside_is_free(name):
    make = floorplans.PLANS[name]
    a, b, c = make(3), make(3), make(4)
    np.testing.assert_array_equal(a.walls, b.walls)
    assert a.walls.shape != c.walls.shape or not np.array_equal(a.walls, c.walls)
    assert a.walls.shape[1] == 4 and np.isfinite(a.walls).all()
    space = free_space(a.walls, seed_point=a.inside)
    assert space.contains(np.array([a.inside]))[0]


def test_thick_walls_keep_the_door_width():
    plan = floorplans.office_corridor(0, num_offices=2, door_width=0.9, thickness=0.2)
    index = WallIndex(plan.walls)
    # Along the corridor wall (y = 1.0) the widest gap between wall pieces is a 0.9 m door.
    xs = np.arange(0.0, 8.0, 0.005)
    blocked = index.crosses(
        np.column_stack((xs, np.full(len(xs), 0.5))), np.column_stack((xs, np.full(len(xs), 1.5)))
    )
    runs = np.diff(np.flatnonzero(np.diff(np.concatenate(([1], blocked.astype(int), [1]))) != 0))[::2]
    assert np.isclose(runs.max() * 0.005, 0.9, atol=0.011)
