"""Importers: AMRL vector maps and navigation JSON, pedsim scenes (roadmap tests: test_roadmap.py)."""

import json

import numpy as np
import pytest

from socialzoo.maps.importers import (
    merge_duplicate_walls,
    read_amrl_nav_graph,
    read_pedsim_scene,
    read_vector_map,
    write_vector_map,
)
from socialzoo.maps.map_file import MapError, load_map


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


def test_zero_length_walls_are_dropped_on_import(tmp_path):
    (tmp_path / "w.txt").write_text("0, 0, 1, 0\n2, 2, 2, 2\n1,0,1,1\n")
    np.testing.assert_array_equal(read_vector_map(tmp_path / "w.txt"), [[0, 0, 1, 0], [1, 0, 1, 1]])


def test_repeated_wall_pieces_merge_within_a_millimetre():
    walls = np.array(
        [
            [0, 0, 10, 0],  # 0: kept, grown to the overlapping piece 4's far end
            [0, 5, 10, 5],  # 1: repeats nothing
            [0, 0, 10, 0],  # a duplicate
            [10, 0, 0, 0],  # a reversed duplicate
            [8, 0, 14, 0],  # overlaps 0 by 2 m: merged into (0, 0)-(14, 0)
            [2, 0, 3, 0],  # lies inside 0
            [0, 0.0005, 10, 0.0005],  # 0.5 mm off: within the tolerance
            [14, 0, 20, 0],  # only touches the merged wall end to end: kept
            [0, 0.005, 10, 0.005],  # 5 mm off (a wall's other face): kept
            [0, 10, 4, 10],  # 9: a chain of overlaps, each with the next: one wall (0, 10)-(9, 10)
            [3, 10, 7, 10],
            [9, 10, 6, 10],
            [5, -1, 5, 1],  # crosses 0: kept
        ],
        dtype=np.float64,
    )
    merged, count = merge_duplicate_walls(walls)
    expected = [
        [0, 0, 14, 0],
        [0, 5, 10, 5],
        [14, 0, 20, 0],
        [0, 0.005, 10, 0.005],
        [0, 10, 9, 10],
        [5, -1, 5, 1],
    ]
    np.testing.assert_array_equal(merged, expected)
    assert count == len(walls) - len(expected)
    # The longest piece gives the direction; a plan without repeats comes back as it was.
    np.testing.assert_array_equal(merge_duplicate_walls(walls[[3, 2]])[0], [[10, 0, 0, 0]])
    again, none = merge_duplicate_walls(merged)
    assert none == 0
    np.testing.assert_array_equal(again, merged)


def test_amrl_nav_graph_errors_name_the_entry(tmp_path):
    nodes = [{"id": 1, "loc": {"x": 0.0, "y": 0.0}}, {"id": 2, "loc": {"x": 1.0, "y": 0.0}}]
    cases = [
        ({"nodes": nodes, "edges": [{"s0_id": 1, "s1_id": 9}]}, r"edges\[0\]: s1_id 9 is not a node id"),
        ({"nodes": nodes, "edges": [{"s0_id": 2, "s1_id": 2}]}, r"edges\[0\]: joins node 2 to itself"),
        ({"nodes": [*nodes, nodes[0]], "edges": []}, r"nodes\[2\]: node id 1 repeats nodes\[0\]"),
        ({"nodes": [{"id": 1, "loc": {"x": "a", "y": 0}}], "edges": []}, r"nodes\[0\]: loc.x"),
    ]
    for data, message in cases:
        (tmp_path / "nav.json").write_text(json.dumps(data))
        with pytest.raises(MapError, match=message):
            read_amrl_nav_graph(tmp_path / "nav.json")


def test_pedsim_errors_name_the_line(tmp_path):
    (tmp_path / "scene.xml").write_text(
        '<?xml version="1.0"?>\n<scenario>\n  <obstacle x1="0" y1="0" x2="1" y2="0"/>\n'
        '  <obstacle x1="0" y1="0" x2="1"/>\n</scenario>\n'
    )
    with pytest.raises(MapError, match=r"scene\.xml:4: <obstacle>: missing attribute 'y2'"):
        read_pedsim_scene(tmp_path / "scene.xml")
    (tmp_path / "broken.xml").write_text("<scenario>\n<obstacle x1='0'\n</scenario>\n")
    with pytest.raises(MapError, match=r"broken\.xml:3: malformed XML"):
        read_pedsim_scene(tmp_path / "broken.xml")


def test_files_with_a_byte_order_mark_and_windows_line_ends_read(tmp_path):
    # Windows editors and Excel's "CSV UTF-8" start a file with a BOM: the first line read as
    # "not a number in '\ufeff0, 0, 10, 0'", a navigation JSON as invalid JSON.
    bom = b"\xef\xbb\xbf"
    (tmp_path / "w.txt").write_bytes(bom + b"0, 0, 10, 0\r\n10\t0\t10\t10\r\n")
    np.testing.assert_array_equal(read_vector_map(tmp_path / "w.txt"), [[0, 0, 10, 0], [10, 0, 10, 10]])
    data = {"nodes": [{"id": 1, "loc": {"x": 1.0, "y": 2.0}}, {"id": 2, "loc": {"x": 3.0, "y": 2.0}}]}
    (tmp_path / "nav.json").write_bytes(bom + json.dumps(data).encode())
    np.testing.assert_array_equal(read_amrl_nav_graph(tmp_path / "nav.json")[0], [[1, 2], [3, 2]])
    (tmp_path / "scene.xml").write_bytes(bom + b'<?xml version="1.0"?><s><waypoint id="a" x="2" y="2"/></s>')
    np.testing.assert_array_equal(read_pedsim_scene(tmp_path / "scene.xml").nodes, [[2, 2]])
    saved = load_map("doorway").save(tmp_path / "m.json")
    saved.write_bytes(bom + saved.read_bytes())
    np.testing.assert_array_equal(load_map(saved).walls, load_map("doorway").walls)
