"""Importing real floor plans: repairs of what the data gets wrong, and GoAlone on the result.

Each synthetic plan reproduces one failure of real buildings (a graph node on a wall, a stray
graph component, a 0.9 m doorway, a corridor longer than the time limit, a large open atrium, a
sharp corner); each imports with a repair report and GoAlone reaches its goals.
"""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.maps.floorplans import atrium, long_corridor, winding_corridor
from socialzoo.maps.map_completion import complete_map
from socialzoo.maps.map_file import MapError, load_map, nearest_walls, validate_map
from socialzoo.maps.repair import repair_map
from socialzoo.scenarios.feasibility import MAX_ROUTE_LENGTH, route_lengths
from socialzoo.scenarios.generator import generate_scenario


def box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


def two_rooms(door: float = 0.9, thickness: float = 0.15) -> np.ndarray:
    """Two 8 x 8 m rooms; the middle wall (thickness thick) has a door `door` wide at y = 4."""
    lo, hi = 4.0 - door / 2, 4.0 + door / 2
    x0, x1 = 8.0 - thickness / 2, 8.0 + thickness / 2
    return np.array([*box(0, 0, 16, 8), *box(x0, 0, x1, lo), *box(x0, hi, x1, 8)], dtype=np.float64)


def kinds(report) -> set[str]:
    return {r.kind for r in report.repairs}


def reach_all(go_alone, m, pairs: list[tuple[int, int]] | None = None, max_steps: int = 3200) -> None:
    """GoAlone reaches the goal on every pair of legal poses (default: all ordered pairs)."""
    poses = m.legal_poses
    if pairs is None:
        pairs = [(i, j) for i in range(len(poses)) for j in range(len(poses)) if i != j]
    start, goal = np.array(pairs).T
    reached, hit_wall, _, pose = go_alone(m, poses[start], poses[goal, :2], max_steps)
    bad = np.flatnonzero(~reached | hit_wall)
    assert len(bad) == 0, [
        f"{start[k]}->{goal[k]}: {'wall' if hit_wall[k] else 'timeout'} at {pose[k, :2].round(2).tolist()}"
        for k in bad
    ]


def test_graph_node_on_a_wall_is_moved_and_edges_through_walls_rerouted(go_alone):
    walls = two_rooms()
    # A navigation graph as real data has it: node 1 sits on the middle wall, edge 0-2 cuts
    # through it, node 3 stands 5 cm from the outer wall.
    nodes = np.array([[4.0, 4.0], [8.0, 2.0], [12.0, 4.0], [4.0, 7.95]])
    edges = np.array([[0, 1], [1, 2], [0, 2], [0, 3]])
    poses = np.array([[2.0, 2.0, 0.0], [14.0, 6.0, np.pi], [8.05, 6.0, 0.0]])
    with pytest.raises(MapError, match=r"graph.nodes\[1\] at \(8.00, 2.00\) is 0.07 m from wall"):
        complete_map("strict", walls, nodes=nodes, edges=edges, legal_poses=poses)
    m, report = repair_map("repaired", walls, nodes=nodes, edges=edges, legal_poses=poses)
    validate_map(m)
    assert {"node_moved", "edge_rerouted", "pose_moved"} <= kinds(report)
    assert any("graph.nodes[1] at (8.00, 2.00) is 0.07 m from wall" in r.message for r in report.repairs)
    assert m.provenance is not None and len(m.provenance["repairs"]) == len(report.repairs)
    # Moved nodes and poses stand clear of the walls; the rerouted edges go through the door.
    assert nearest_walls(m.wall_index, m.nodes)[0].min() >= 0.35
    assert nearest_walls(m.wall_index, m.legal_poses[:, :2])[0].min() >= 0.35
    reach_all(go_alone, m, [(0, 1), (1, 0), (2, 0)])


def test_stray_components_are_joined_through_the_free_space_or_dropped():
    walls = two_rooms(door=1.2)
    # Left-room chain, right-room chain (no edge through the door), and a pair outside the building.
    nodes = np.array([[2.0, 2.0], [5.0, 2.0], [11.0, 5.0], [14.0, 5.0], [30.0, 30.0], [32.0, 30.0]])
    edges = np.array([[0, 1], [2, 3], [4, 5]])
    m, report = repair_map("joined", walls, nodes=nodes, edges=edges, seed_point=(2.0, 4.0))
    assert {"component_joined", "component_dropped", "poses_generated"} <= kinds(report)
    dropped = [r.message for r in report.repairs if "dropped" in r.message]
    assert len(dropped) == 1 and "2 node(s) around (31.00, 30.00)" in dropped[0]
    assert m.nodes[:, 0].max() < 16 and len(m.legal_poses) >= 2
    assert np.isfinite(route_lengths(m)).all()


def test_a_0_9_m_doorway_is_passable(go_alone):
    walls = two_rooms(door=0.9, thickness=0.2)
    m, report = repair_map("door", walls, seed_point=(3.0, 4.0))
    assert {"graph_generated", "poses_generated"} <= kinds(report)
    left = np.flatnonzero(m.legal_poses[:, 0] < 8.0)
    right = np.flatnonzero(m.legal_poses[:, 0] > 8.0)
    assert len(left) and len(right)
    pairs = [(int(a), int(b)) for a in left[:3] for b in right[:3]]
    reach_all(go_alone, m, pairs + [(b, a) for a, b in pairs])


def test_a_corridor_longer_than_the_time_limit_gets_feasible_scenarios(go_alone):
    plan = long_corridor(150.0)
    m, _ = repair_map("corridor", plan.walls, seed_point=plan.inside)
    lengths = route_lengths(m)
    assert lengths.max() > MAX_ROUTE_LENGTH  # some pose pairs are too far apart ...
    for seed in range(20):  # ... and are never drawn
        s = generate_scenario(m, seed)
        assert np.hypot(*(s.robot_goal[:2] - s.robot_start[:2])) <= MAX_ROUTE_LENGTH
        assert max(np.hypot(*np.diff(r, axis=0).T).sum() for r in s.human_routes) <= MAX_ROUTE_LENGTH
    i, j = np.unravel_index(np.argmax(np.where(lengths <= MAX_ROUTE_LENGTH, lengths, 0)), lengths.shape)
    reach_all(go_alone, m, [(int(i), int(j))])  # the longest feasible route, in time


def test_a_large_open_atrium(go_alone):
    plan = atrium(1, size=(14.0, 14.0), num_rooms=2)
    m, report = repair_map("atrium", plan.walls, seed_point=plan.inside)
    assert "graph_generated" in kinds(report)
    rng = np.random.default_rng(0)
    pairs = [tuple(int(v) for v in rng.choice(len(m.legal_poses), 2, replace=False)) for _ in range(8)]
    reach_all(go_alone, m, pairs)


def test_sharp_corners_on_the_route(go_alone):
    plan = winding_corridor(3, num_legs=5, width=(1.4, 1.4), leg_length=(3.0, 6.0))
    m, _ = repair_map("winding", plan.walls, seed_point=plan.inside)
    lengths = route_lengths(m)
    i, j = np.unravel_index(np.argmax(lengths), lengths.shape)  # round every corner
    reach_all(go_alone, m, [(int(i), int(j)), (int(j), int(i))])


def test_repaired_map_round_trips_with_its_provenance(tmp_path):
    walls = two_rooms()
    m, report = repair_map(
        "p", walls, nodes=np.array([[4.0, 2.0], [12.0, 2.0]]), edges=np.array([[0, 1]]),
        provenance={"importer": "test"},
    )  # fmt: skip
    assert "edge_rerouted" in kinds(report)
    back = load_map(m.save(tmp_path / "p.json"))
    assert back.provenance == {"importer": "test", "repairs": report.to_json()}
    np.testing.assert_allclose(back.nodes, m.nodes, atol=1e-6)


def test_a_generated_graph_rasterises_the_free_space_once(monkeypatch):
    # repair_map rasterised the plan for its own checks and build_roadmap did it again with the
    # same arguments: a quarter of a large building's import (GDC2 without its graph).
    import socialzoo.maps.repair as repair
    import socialzoo.maps.roadmap as roadmap

    calls, original = [], roadmap.free_space

    def counted(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(repair, "free_space", counted)
    monkeypatch.setattr(roadmap, "free_space", counted)
    m, _ = repair_map("door", two_rooms(door=1.2), seed_point=(3.0, 4.0))
    monkeypatch.undo()
    assert len(calls) == 1
    again = roadmap.build_roadmap(two_rooms(door=1.2), seed_point=(3.0, 4.0))
    np.testing.assert_array_equal(m.nodes, again.nodes)


def test_a_region_of_a_building_imported_with_the_whole_graph():
    # A part of a building (--region) with the whole building's graph (--nav) was refused when the
    # map was validated: "graph.nodes[2] at (12.00, 4.00) lies outside region [...]".
    nodes = np.array([[2.0, 4.0], [5.0, 4.0], [12.0, 4.0], [14.0, 4.0]])
    edges = np.array([[0, 1], [1, 2], [2, 3]])
    m, report = repair_map(
        "left", two_rooms(door=1.2), nodes=nodes, edges=edges, region=(-1.0, -1.0, 8.5, 9.0)
    )
    np.testing.assert_array_equal(m.nodes, nodes[:2])
    np.testing.assert_array_equal(m.edges, [[0, 1]])
    dropped = [r.message for r in report.repairs if r.kind == "node_dropped"]
    assert dropped == [
        "2 of the graph's 4 nodes lie outside the region [-1.0, -1.0, 8.5, 9.0]: dropped (graph.nodes[2, 3])"
    ]
    assert (m.legal_poses[:, 0] < 8.0).all()
