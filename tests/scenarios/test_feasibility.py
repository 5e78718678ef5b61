"""The feasibility rule: route lengths between legal poses, feasible pairs, statistics, map check."""

import dataclasses

import numpy as np
import pytest

from socialzoo.maps.map_file import Map, load_map
from socialzoo.scenarios.feasibility import (
    MAX_ROUTE_LENGTH,
    feasible_pairs,
    route_lengths,
    route_stats,
)
from socialzoo.scenarios.map_check import check_map


def corridor(length: float = 60.0) -> Map:
    """Four poses along a straight corridor, 20 m apart, and a fifth shut in a box."""
    xs = np.array([0.5, 20.5, 40.5, 60.5])
    walls = [[0, 0, length + 1, 0], [length + 1, 0, length + 1, 3], [length + 1, 3, 0, 3], [0, 3, 0, 0]]
    walls += [[100, 0, 102, 0], [102, 0, 102, 2], [102, 2, 100, 2], [100, 2, 100, 0]]
    return Map(
        name="corridor",
        walls=np.array(walls, float),
        nodes=np.column_stack((xs, np.full(4, 1.5))),
        edges=np.array([[0, 1], [1, 2], [2, 3]]),
        legal_poses=np.vstack((np.column_stack((xs, np.full(4, 1.5), np.zeros(4))), [[101.0, 1.0, 0.0]])),
    )


def test_rule_and_route_lengths():
    assert MAX_ROUTE_LENGTH == 0.75 * 80 * 1.5
    m = corridor()
    lengths = route_lengths(m)
    assert route_lengths(m) is lengths and not lengths.flags.writeable  # cached, read-only
    np.testing.assert_allclose(lengths[:4, :4], np.abs(np.subtract.outer(np.arange(4), np.arange(4))) * 20.0)
    assert np.isinf(lengths[4, :4]).all() and np.isinf(lengths[:4, 4]).all()
    ok = feasible_pairs(m, 25.0)
    assert ok.sum() == 6 and not ok.diagonal().any() and not ok[4].any()


def test_route_stats_and_the_map_check():
    m = corridor()
    stats = route_stats(m, 25.0)
    assert (stats.num_pairs, stats.num_feasible, stats.num_unreachable) == (20, 6, 8)
    assert (stats.shortest, stats.longest) == (20.0, 60.0) and stats.stranded == (4,)
    check = check_map(m, 25.0)
    assert not check.valid  # the boxed pose sees no node
    assert any("legal_poses[4]" in p for p in check.problems)
    fine = dataclasses.replace(m, legal_poses=m.legal_poses[:4])
    check = check_map(fine, 25.0)
    assert check.valid and check.num_components == 1 and check.routes is not None
    assert check.routes.feasible_share == pytest.approx(6 / 12)
    assert check.tight_edges == ()
    text = "\n".join(check.lines())
    assert "6 of 12 pose pairs feasible (50%, route <= 25 m)" in text


@pytest.mark.parametrize("edge", [(0, 99), (0, -1)])
def test_map_check_reports_an_edge_to_a_missing_node(edge):
    # It lists the problem and counts the components of the other edges (it raised IndexError).
    m = dataclasses.replace(load_map("doorway"), edges=np.array([edge, (0, 1)]))
    check = check_map(m)
    assert any("names a node outside" in p for p in check.problems)
    assert check.num_components == len(m.nodes) - 1


def test_benchmark_maps_have_every_pair_feasible():
    for name in ("gdc1", "ghc3"):
        m = load_map(name)
        stats = route_stats(m)
        assert stats.num_feasible == stats.num_pairs, name
        assert stats.longest < MAX_ROUTE_LENGTH


def test_crowd_keeps_the_benchmark_density_on_maps_with_a_walkable_area(tmp_path):
    from socialzoo.scenarios.feasibility import CROWD_DENSITY, max_humans_for
    from socialzoo.scenarios.generator import generate_scenario

    m = corridor()
    assert max_humans_for(m, 5, 25) == 25  # no area: the SPEC's head count
    small = dataclasses.replace(m, walkable_area=400.0, legal_poses=m.legal_poses[:4])
    assert max_humans_for(small, 5, 25) == round(400.0 * CROWD_DENSITY) == 7
    assert max_humans_for(dataclasses.replace(small, walkable_area=10.0), 5, 25) == 5
    assert max_humans_for(dataclasses.replace(small, walkable_area=1e5), 5, 25) == 25
    counts = {generate_scenario(small, seed).num_humans for seed in range(40)}
    assert counts == {5, 6, 7}
    back = load_map(small.save(tmp_path / "small.json"))
    assert back.walkable_area == 400.0
    assert load_map("gdc1").walkable_area is None
