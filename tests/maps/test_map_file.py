"""Shipped maps load and validate; malformed maps fail with errors naming the file and entry."""

import json

import networkx as nx
import numpy as np
import pytest

from socialzoo.maps.map_file import MapError, list_maps, load_map, validate_map

SHIPPED = ["gdc1", "ghc3", "open_room", "hallway", "doorway", "intersection"]


def test_every_shipped_map_is_listed_loads_and_validates():
    assert set(SHIPPED) <= set(list_maps())
    for name in SHIPPED:
        m = load_map(name)
        validate_map(m)
        assert m.source and m.licence, name
        graph = nx.Graph(m.edges.tolist())
        graph.add_nodes_from(range(m.num_nodes))
        assert nx.is_connected(graph), name


def test_gdc1_keeps_the_reference_nodes_and_poses(reference_dir):
    m = load_map("gdc1")
    assert m.num_nodes == 77 and len(m.legal_poses) == 26
    ref_nodes = np.loadtxt(reference_dir / "gdc1_nav_nodes.txt")
    np.testing.assert_allclose(m.nodes, ref_nodes, atol=1e-6)
    assert "Autonomous Mobile Robotics Laboratory" in m.licence
    assert m.walls[:, [1, 3]].min() > -5.0, "the second floor plan must be cropped away"


def test_ghc3_graph_lies_inside_the_building():
    m = load_map("ghc3")
    assert m.num_walls == 2082
    # The building spans about x in [-20, 36], y in [-35, 26]; outdoor fragments lie outside it.
    for points in (m.nodes, m.legal_poses[:, :2]):
        assert np.all((points[:, 0] > -20) & (points[:, 0] < 36) & (points[:, 1] > -35) & (points[:, 1] < 26))
    assert m.num_nodes >= 50 and len(m.legal_poses) >= 20


def test_load_is_cached_per_name():
    assert load_map("gdc1") is load_map("gdc1")


def test_a_map_file_read_again_unchanged_is_the_same_map(tmp_path):
    # Its wall index and the tables keyed on the map object are built once, not by every env.
    path = _write(tmp_path, _room(), name="room.json")
    m = load_map(path)
    assert load_map(str(path)) is m and m.wall_index is load_map(path).wall_index
    data = _room()
    data["walls"] = [*data["walls"], [2.0, 2.0, 3.0, 2.0]]
    _write(tmp_path, data, name="room.json")  # the file changed: read anew
    changed = load_map(path)
    assert changed is not m and changed.num_walls == m.num_walls + 1


def _write(tmp_path, data, name="bad.json"):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return path


def _room(**changes):
    data = load_map("open_room").to_json()
    data.update(changes)
    return data


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"walls": [[0, 0, "x", 1]]}, "walls"),
        ({"walls": [[0, 0, float("nan"), 1]]}, r"walls\[0\]"),
        pytest.param(
            {"walls": [[0, 0, 10**400, 1]]}, r"walls\[0\]: coordinate is an int beyond", id="int-beyond-float"
        ),
        pytest.param({"walkable_area": 10**400}, "walkable_area must be a positive", id="area-beyond-float"),
        ({"format": "other/1"}, "format"),
        pytest.param({"name": "../elsewhere"}, "must be usable as a file name", id="name-leaves-folder"),
        pytest.param({"name": ".."}, "must be usable as a file name", id="name-dotdot"),
        ({"graph": {"nodes": [[5, 5], [6, 6]], "edges": [[0, 7]]}}, r"graph.edges\[0\]"),
        ({"graph": {"nodes": [[5, 5], [6, 6]], "edges": [[1, 1]]}}, "to itself"),
        ({"graph": {"nodes": [[5, 5], [0.05, 5]], "edges": [[0, 1]]}}, r"graph.nodes\[1\]"),
        ({"graph": {"nodes": [[5, 5], [5, 7], [8, 8]], "edges": [[0, 1]]}}, "disconnected"),
        ({"legal_poses": [[5, 5, 0], [0.1, 5, 0]]}, r"legal_poses\[1\]"),
        ({"legal_poses": [[5, 5, 0]]}, "at least 2 poses"),
    ],
)
def test_bad_maps_fail_naming_the_entry(tmp_path, change, message):
    path = _write(tmp_path, _room(**change))
    with pytest.raises(MapError, match=message) as err:
        load_map(path)
    assert "bad.json" in str(err.value)


def test_a_map_in_millimetres_is_refused_naming_the_file_and_its_extent(tmp_path):
    # Its 25 cm wall grid would take 1.6e9 cells: a bare MemoryError (or the kernel's kill) before.
    data = _room()
    del data["region"]
    data["walls"] = [[1000 * v for v in w] for w in data["walls"]]
    data["graph"]["nodes"] = [[1000 * v for v in n] for n in data["graph"]["nodes"]]
    data["legal_poses"] = [[1000 * x, 1000 * y, theta] for x, y, theta in data["legal_poses"]]
    with pytest.raises(
        MapError, match=r"bad\.json: the walls span 10000 x 10000 m .* coordinates are metres"
    ):
        load_map(_write(tmp_path, data))


def test_edge_through_a_wall_is_named(tmp_path):
    data = _room()
    data["walls"] = [*data["walls"], [5, 0, 5, 10]]  # split the room in two
    data["graph"] = {"nodes": [[2, 5], [8, 5]], "edges": [[0, 1]]}
    data["legal_poses"] = [[2, 2, 0], [2, 8, 0]]
    with pytest.raises(MapError, match=r"graph.edges\[0\] \(node 0 - node 1\) passes through wall 4"):
        load_map(_write(tmp_path, data))


def test_unreachable_pose_is_named(tmp_path):
    data = _room()
    data["walls"] = [*data["walls"], [5, 0, 5, 10]]
    data["graph"] = {"nodes": [[2, 5], [2.5, 7]], "edges": [[0, 1]]}
    data["legal_poses"] = [[2, 2, 0], [8, 8, 0]]
    with pytest.raises(MapError, match=r"legal_poses\[1\]"):
        load_map(_write(tmp_path, data))


@pytest.mark.parametrize(
    ("text", "message"),
    [("{not json", r"not a map file \(not JSON"), ("[]", "JSON object"), ("{}", "format")],
)
def test_malformed_files(tmp_path, text, message):
    with pytest.raises(MapError, match=message):
        load_map(_write(tmp_path, text))


def test_missing_field_and_unknown_name(tmp_path):
    data = _room()
    del data["legal_poses"]
    with pytest.raises(MapError, match="missing field 'legal_poses'"):
        load_map(_write(tmp_path, data))
    with pytest.raises(MapError, match="unknown map 'nowhere'"):
        load_map("nowhere")
    with pytest.raises(FileNotFoundError, match=r"missing\.json"):
        load_map(tmp_path / "missing.json")


def test_round_trip(tmp_path):
    m = load_map("hallway")
    again = load_map(m.save(tmp_path / "copy.json"))
    for field in ("walls", "nodes", "edges", "legal_poses"):
        np.testing.assert_array_equal(getattr(m, field), getattr(again, field))


def test_a_map_argument_names_a_file_by_its_suffix_or_a_folder():
    from socialzoo.cli.benchmark_cmd import _map_names
    from socialzoo.maps.map_file import names_a_file

    assert not any(names_a_file(a) for a in ("gdc1", "GDC1", "b.JSON"))
    assert all(names_a_file(a) for a in ("b.json", "dir/b", "./b"))
    # The benchmark lower-cases shipped names only (the same rule as load_map's).
    assert list(_map_names("GDC1,Dir/B,My.json")) == ["gdc1", "Dir/B", "My.json"]
