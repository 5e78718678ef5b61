"""Importers: AMRL vector maps and navigation JSON, pedsim scenes; the roadmap builder."""

import json

import networkx as nx
import numpy as np
import pytest

from socialzoo.core.geometry import segments_intersect
from socialzoo.nav.importers import read_amrl_nav_graph, read_pedsim_scene, read_vector_map, write_vector_map
from socialzoo.nav.maps import MapError, load_map, validate_map
from socialzoo.nav.roadmap import build_roadmap, complete_map


def test_vector_map_round_trip_and_formats(tmp_path):
    walls = load_map("doorway").walls
    np.testing.assert_allclose(read_vector_map(write_vector_map(tmp_path / "d.txt", walls)), walls, atol=1e-6)
    (tmp_path / "spaces.txt").write_text("# comment\n0 0 1 0\n\n1 0 1 1  # tail\n")
    np.testing.assert_array_equal(read_vector_map(tmp_path / "spaces.txt"), [[0, 0, 1, 0], [1, 0, 1, 1]])


def test_vector_map_errors_name_file_and_line(tmp_path):
    (tmp_path / "bad.txt").write_text("0, 0, 1, 0\n0, 0, 1\n")
    with pytest.raises(MapError, match=r"bad.txt:2: expected 4 numbers"):
        read_vector_map(tmp_path / "bad.txt")
    (tmp_path / "nan.txt").write_text("0, 0, nope, 0\n")
    with pytest.raises(MapError, match=r"nan.txt:1:"):
        read_vector_map(tmp_path / "nan.txt")


def test_amrl_nav_graph(tmp_path):
    data = {
        "nodes": [{"id": 10, "loc": {"x": 1.0, "y": 2.0}}, {"id": 4, "loc": {"x": 3.0, "y": 2.0}}],
        "edges": [{"s0_id": 10, "s1_id": 4, "max_speed": 1.0}],
    }
    (tmp_path / "nav.json").write_text(json.dumps(data))
    nodes, edges = read_amrl_nav_graph(tmp_path / "nav.json")
    np.testing.assert_array_equal(nodes, [[1.0, 2.0], [3.0, 2.0]])
    np.testing.assert_array_equal(edges, [[0, 1]])
    (tmp_path / "broken.json").write_text('{"nodes": [')
    with pytest.raises(MapError, match=r"broken\.json"):
        read_amrl_nav_graph(tmp_path / "broken.json")


def test_pedsim_scene(tmp_path):
    (tmp_path / "scene.xml").write_text(
        '<scenario><obstacle x1="0" y1="0" x2="10" y2="0"/><obstacle x1="10" y1="0" x2="10" y2="5"/>'
        '<waypoint id="a" x="2" y="2" r="1"/></scenario>'
    )
    scene = read_pedsim_scene(tmp_path / "scene.xml")
    np.testing.assert_array_equal(scene.walls, [[0, 0, 10, 0], [10, 0, 10, 5]])
    np.testing.assert_array_equal(scene.nodes, [[2, 2]])
    (tmp_path / "bad.xml").write_text('<scenario><obstacle x1="0" y1="zero" x2="1" y2="0"/></scenario>')
    with pytest.raises(MapError, match=r"bad\.xml"):
        read_pedsim_scene(tmp_path / "bad.xml")


@pytest.mark.parametrize("name", ["hallway", "ghc3"])
def test_roadmap_is_connected_and_never_crosses_walls(name):
    source = load_map(name)
    seed_point = {"hallway": (4.0, 4.5), "ghc3": (-5.0, -10.0)}[name]
    roadmap = build_roadmap(source.walls, region=source.region, seed_point=seed_point)
    graph = nx.Graph(roadmap.edges.tolist())
    graph.add_nodes_from(range(len(roadmap.nodes)))
    assert nx.is_connected(graph)
    a, b = roadmap.nodes[roadmap.edges[:, 0]], roadmap.nodes[roadmap.edges[:, 1]]
    crossing = segments_intersect(
        a[:, None], b[:, None], source.walls[None, :, :2], source.walls[None, :, 2:]
    )
    assert not crossing.any()


def test_complete_map_is_deterministic_and_valid():
    walls = load_map("doorway").walls
    one = complete_map("d", walls, region=(-1, -1, 17, 9), seed_point=(4, 4))
    two = complete_map("d", walls, region=(-1, -1, 17, 9), seed_point=(4, 4))
    validate_map(one)
    np.testing.assert_array_equal(one.nodes, two.nodes)
    np.testing.assert_array_equal(one.legal_poses, two.legal_poses)
    spacing = np.linalg.norm(one.legal_poses[:, None, :2] - one.legal_poses[None, :, :2], axis=-1)
    assert spacing[~np.eye(len(spacing), dtype=bool)].min() >= 2.0
