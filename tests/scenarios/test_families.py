"""The scenario-family interface and its registry: the map families, CrowdNav's cases, splits."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.catalogue import FAMILIES, ScenarioFamily, SeedSplit, get_family, register_family
from socialzoo.scenarios.crowd_cases import (
    CrowdCaseConfig,
    CrowdNavCircleCrossing,
    crowd_family,
)
from socialzoo.scenarios.families import antipode, circle_point


def test_every_registered_family_loads_under_its_own_name():
    for name in sorted(FAMILIES):
        family = get_family(name)
        assert isinstance(family, ScenarioFamily) and family.name == name
        assert family.map_name and family.description
    with pytest.raises(KeyError, match="unknown scenario family 'stampede'"):
        get_family("stampede")


def test_crowdnav_families_draw_crowdnavs_cases_and_declare_its_splits():
    family = get_family("crowdnav_circle_crossing")
    assert family.map_name == "arena"
    assert family.splits == {"val": SeedSplit(0, 100), "test": SeedSplit(1000, 500), "train": SeedSplit(2000)}
    assert family.case_seed("test", 3) == 1003
    with pytest.raises(ValueError, match="holds 100"):
        family.case_seed("val", 100)
    config = CrowdCaseConfig(layout="square_crossing", num_humans=7)
    square = crowd_family(config)
    assert square.name == "crowdnav_square_crossing"
    case = square.make(1004, num_robots=2)
    assert case == crowd_family(config).make(1004, 2) and case.family == "crowdnav_square_crossing"
    arrays = square.arrays(1004, 2)
    np.testing.assert_array_equal(arrays.human_starts, case.human_spawn)
    with pytest.raises(ValueError, match="draws circle_crossing"):
        CrowdNavCircleCrossing(config)
    with pytest.raises(ValueError, match="open arena, not on map 'hallway'"):
        family.make(0, m=load_map("hallway"))


def test_circle_crossing_geometry_is_shared():
    # The map family and CrowdNav's cases both put people on a circle heading for the antipode.
    x, y = circle_point(1.0, 2.0, 3.0, np.array([0.0, np.pi / 2]))
    np.testing.assert_allclose(np.stack((x, y), -1), [[4.0, 2.0], [1.0, 5.0]], atol=1e-12)
    assert antipode(1.0, 2.0, 4.0, 2.0) == (-2.0, 2.0)
    room = get_family("circle_crossing").make(3, m=load_map("open_room"))
    centre = (room.robot_starts[0, :2] + room.robot_goals[0, :2]) / 2
    ends = room.human_spawn + [r[-1] for r in room.human_routes]
    np.testing.assert_allclose(ends, np.broadcast_to(2 * centre, ends.shape), atol=1e-9)
    case = get_family("crowdnav_circle_crossing").make(3)
    np.testing.assert_array_equal([r[0] for r in case.human_routes], -case.human_spawn)


def test_register_family_refuses_nameless_and_clashing_families():
    class Nameless(ScenarioFamily):
        pass

    class Impostor(ScenarioFamily):
        name = "doorway"

    with pytest.raises(ValueError, match="name must be set"):
        register_family(Nameless)
    with pytest.raises(ValueError, match="'doorway' is already registered"):
        register_family(Impostor)
    with pytest.raises(ValueError, match="needs a ScenarioFamily"):
        register_family("doorway")  # type: ignore[arg-type]
