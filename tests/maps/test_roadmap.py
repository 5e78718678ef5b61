"""The roadmap builder: free space, nodes, edges, joining components, legal poses, determinism."""

import networkx as nx
import numpy as np
import pytest

from socialzoo.core.geometry import segments_intersect
from socialzoo.core.walls import WallIndex
from socialzoo.maps.importers import read_table, read_vector_map
from socialzoo.maps.legal_poses import generate_legal_poses
from socialzoo.maps.map_completion import complete_map
from socialzoo.maps.map_file import load_map, nearest_walls, reaches_graph, segment_clearance, validate_map
from socialzoo.maps.roadmap import (
    MAX_GRID_CELLS,
    RoadmapConfig,
    build_edges,
    build_roadmap,
    free_space,
)


def _connected(num_nodes: int, edges: np.ndarray) -> bool:
    graph = nx.Graph(np.asarray(edges).tolist())
    graph.add_nodes_from(range(num_nodes))
    return nx.is_connected(graph)


def _box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


@pytest.mark.parametrize("name", ["hallway", "ghc3"])
def test_roadmap_is_connected_and_never_crosses_walls(name):
    source = load_map(name)
    seed_point = {"hallway": (4.0, 4.5), "ghc3": (-5.0, -10.0)}[name]
    roadmap = build_roadmap(source.walls, region=source.region, seed_point=seed_point)
    assert _connected(len(roadmap.nodes), roadmap.edges)
    a, b = roadmap.nodes[roadmap.edges[:, 0]], roadmap.nodes[roadmap.edges[:, 1]]
    crossing = segments_intersect(
        a[:, None], b[:, None], source.walls[None, :, :2], source.walls[None, :, 2:]
    )
    assert not crossing.any()
    # Every node lies in the flood-filled interior, so none is out among the outdoor fragments.
    assert roadmap.space.contains(roadmap.nodes).all()


def test_ghc3_interior_excludes_the_outdoor_fragments():
    walls = load_map("ghc3").walls
    space = free_space(walls, region=(-25.0, -37.0, 40.0, 27.0), seed_point=(-5.0, -10.0))
    outdoors = np.array([[-22.0, -20.0], [-30.0, -35.0], [10.0, -40.0], [0.0, 10.0], [35.0, -30.0]])
    indoors = np.array([[-5.0, -10.0], [20.0, -20.0], [20.0, 15.0], [-10.0, -30.0]])
    assert not space.contains(outdoors).any()
    assert space.contains(indoors).all()


def test_free_space_stops_at_doors_too_narrow_for_the_robot():
    # Two 6 x 6 m rooms; the door in the middle wall is 0.5 m wide (the robot needs 0.7 m).
    walls = np.array([*_box(0, 0, 12, 6), [6, 0, 6, 2.75], [6, 3.25, 6, 6]], dtype=np.float64)
    space = free_space(walls, seed_point=(3.0, 3.0))
    assert space.contains(np.array([[3.0, 3.0], [1.0, 5.0]])).all()
    assert not space.contains(np.array([[9.0, 3.0]])).any()
    wide = np.array([*_box(0, 0, 12, 6), [6, 0, 6, 2.4], [6, 3.6, 6, 6]], dtype=np.float64)
    assert free_space(wide, seed_point=(3.0, 3.0)).contains(np.array([[9.0, 3.0]])).all()


def test_a_plan_too_large_for_the_grid_is_refused_before_any_is_made():
    # An 850 m pedsim scene (pedsim_ros's airport) asked for a 305 M-cell grid: the kernel killed
    # the import without a word (or numpy failed deep in a distance transform under a memory
    # limit). The refusal names the extent and the way out, before allocating anything.
    walls = np.array(_box(0, 0, 600, 500), dtype=np.float64)
    assert (604 / 0.05) * (504 / 0.05) > MAX_GRID_CELLS
    with pytest.raises(ValueError) as err:
        free_space(walls)
    message = str(err.value)
    assert "the plan spans 604 x 504 m (from (-2.0, -2.0) to (602.0, 502.0), margin included)" in message
    assert "122 M cells, more than the 100 M" in message and "--region XMIN YMIN XMAX YMAX" in message
    assert "metres" in message
    # A region within the limit is the way out.
    assert free_space(walls, region=(-1.0, -1.0, 20.0, 20.0)).interior.any()
    # A plan in the wrong units is refused the same way: the cells of a span of 1e200 m, and the span
    # of walls at -1e308 and 1e308 (inf m), were an OverflowError (math.ceil(inf), int to float).
    for far in (_box(0, 0, 1e200, 1e200), [[-1e308, 0, 1e308, 0], [1e308, 0, 1e308, 5]]):
        with pytest.raises(ValueError, match=r"M cells, more than the 100 M"):
            free_space(np.array(far, dtype=np.float64))


def test_a_region_beside_the_plan_is_refused_by_name():
    # A region in other coordinates (or units) than the plan's said "found 0 places for legal
    # poses ... (1.0 m^2 ..., at most inf m from a wall ...) has no point 0.44 m from every wall".
    walls = np.array(_box(10, 10, 30, 20), dtype=np.float64)
    with pytest.raises(
        ValueError,
        match=r"region \[0.0, 0.0, 1.0, 1.0\] holds no part of the plan, whose "
        r"walls span \(10.00, 10.00\) to \(30.00, 20.00\)",
    ):
        complete_map("r", walls, region=(0, 0, 1, 1))
    # A region that holds a part of it, or a region round a map without walls, is as before.
    assert free_space(walls, region=(5.0, 5.0, 20.0, 25.0)).interior.any()
    assert free_space(np.zeros((0, 4)), region=(0.0, 0.0, 5.0, 5.0)).clearance.shape == (100, 100)


def test_seed_point_must_be_free():
    walls = np.array(_box(0, 0, 10, 10), dtype=np.float64)
    with pytest.raises(ValueError, match=r"seed point \(0.10, 5.00\) is 0.10 m from a wall"):
        free_space(walls, seed_point=(0.1, 5.0))
    with pytest.raises(ValueError, match="outside the grid"):
        free_space(walls, seed_point=(50.0, 5.0))


def test_build_edges_joins_the_gdc1_nodes_with_clearance(reference_dir):
    walls = read_vector_map(reference_dir / "gdc1_walls.txt")
    nodes = read_table(reference_dir / "gdc1_nav_nodes.txt", 2, "x y")
    index = WallIndex(walls)
    edges = build_edges(nodes, index, clearance=0.3)
    assert _connected(len(nodes), edges)
    assert (edges[:, 0] < edges[:, 1]).all()
    clearance, _ = segment_clearance(index, nodes[edges[:, 0]], nodes[edges[:, 1]])
    assert (clearance >= 0.3).all()
    # Sparse: about as many edges as a corridor network needs, not every visible pair.
    assert len(edges) < 2 * len(nodes)


def test_build_edges_prefers_short_hops_over_long_shortcuts():
    walls = np.array(_box(-1, -1, 11, 1), dtype=np.float64)
    nodes = np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])
    np.testing.assert_array_equal(build_edges(nodes, walls), [[0, 1], [1, 2]])
    with pytest.raises(ValueError, match="clearance"):
        build_edges(nodes, walls, clearance=0.8)


def test_missing_edges_are_joined_around_corners():
    # An L-shaped corridor: its two end nodes cannot see each other, so a corner node is added.
    walls = np.array(
        [[0, 0, 10, 0], [10, 0, 10, 10], [10, 10, 8, 10], [8, 10, 8, 2], [8, 2, 0, 2], [0, 2, 0, 0]],
        dtype=np.float64,
    )
    nodes = np.array([[1.0, 1.0], [9.0, 9.0]])
    m = complete_map("corner", walls, nodes=nodes, seed_point=(1.0, 1.0))
    assert m.num_nodes > 2
    np.testing.assert_array_equal(m.nodes[:2], nodes)
    assert _connected(m.num_nodes, m.edges)


def test_generated_poses_are_clear_spread_reachable_and_face_open_space():
    m = load_map("intersection")
    config = RoadmapConfig(num_poses=8)
    index = WallIndex(m.walls)
    poses = generate_legal_poses(
        m.walls, m.nodes, m.edges, region=m.region, seed_point=(0.0, 0.0), config=config
    )
    assert 2 <= len(poses) <= 8
    assert (nearest_walls(index, poses[:, :2])[0] >= config.pose_clearance).all()
    assert reaches_graph(index, poses[:, :2], m.nodes, m.edges).all()
    gap = np.linalg.norm(poses[:, None, :2] - poses[None, :, :2], axis=-1)
    assert gap[~np.eye(len(poses), dtype=bool)].min() >= config.pose_separation
    ahead = index.cast_rays(poses[:, :2], poses[:, 2:3], max_range=5.0)
    assert (ahead >= 2.0).all(), "every pose faces along its corridor"


@pytest.mark.parametrize("seed", [0, 3])
def test_complete_map_is_deterministic_and_valid(seed):
    walls = load_map("doorway").walls
    one = complete_map("d", walls, region=(-1, -1, 17, 9), seed_point=(4, 4), seed=seed)
    two = complete_map("d", walls, region=(-1, -1, 17, 9), seed_point=(4, 4), seed=seed)
    validate_map(one)
    np.testing.assert_array_equal(one.nodes, two.nodes)
    np.testing.assert_array_equal(one.edges, two.edges)
    np.testing.assert_array_equal(one.legal_poses, two.legal_poses)
    spacing = np.linalg.norm(one.legal_poses[:, None, :2] - one.legal_poses[None, :, :2], axis=-1)
    assert spacing[~np.eye(len(spacing), dtype=bool)].min() >= 2.0


@pytest.mark.parametrize(
    ("field", "value"),
    [("resolution", 0.0), ("edge_clearance", 0.9), ("num_poses", 1), ("node_clearance", 0.1)],
)
def test_config_errors_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        RoadmapConfig(**{field: value})


def test_keep_clearance_zero_is_allowed_and_bounded():
    # 0 turns the straightening limit off (the shipped maps were built that way: tools/build_maps.py).
    assert RoadmapConfig(keep_clearance=0.0).keep_clearance == 0.0
    for bad in (-0.1, 0.6):
        with pytest.raises(ValueError, match="keep_clearance"):
            RoadmapConfig(keep_clearance=bad)
