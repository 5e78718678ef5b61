"""`socialzoo map ...` and `socialzoo demo` run in-process."""

import imageio.v3 as iio
import numpy as np
import pytest

from socialzoo.cli import main
from socialzoo.maps.importers import write_vector_map
from socialzoo.maps.map_file import load_map


def test_map_show_writes_a_png_where_asked(tmp_path, capsys):
    out = tmp_path / "pictures" / "gdc1.png"  # a missing folder is created
    assert main(["map", "show", "gdc1", "--picture", str(out)]) == 0
    image = iio.imread(out)
    assert image.ndim == 3 and image.shape[0] > 200
    text = capsys.readouterr().out
    assert "77 nodes" in text and f"picture: {out}" in text


def test_map_show_draws_beside_a_map_file_and_nothing_for_a_shipped_name(tmp_path, monkeypatch, capsys):
    work, maps = tmp_path / "work", tmp_path / "maps"
    work.mkdir()
    maps.mkdir()
    monkeypatch.chdir(work)  # not the map's folder: no picture may land here
    mine = load_map("doorway").save(maps / "mine.json")
    assert main(["map", "show", str(mine)]) == 0
    assert iio.imread(maps / "mine-map.png").shape[0] > 200
    assert f"picture: {maps / 'mine-map.png'}" in capsys.readouterr().out
    assert main(["map", "show", "gdc1"]) == 0
    assert "picture: none (gdc1 is a shipped map: ask for one with --picture gdc1-map.png)" in (
        capsys.readouterr().out
    )
    assert list(work.iterdir()) == []


def test_map_list_and_validate(capsys):
    assert main(["map", "list"]) == 0
    assert "ghc3" in capsys.readouterr().out
    assert main(["map", "validate", "hallway"]) == 0


def test_map_errors_exit_2_without_traceback(tmp_path, capsys):
    assert main(["map", "show", "nowhere"]) == 2
    assert "unknown map 'nowhere'" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("{oops")
    assert main(["map", "validate", str(bad)]) == 2
    assert "bad.json" in capsys.readouterr().err


def test_map_import_from_walls(tmp_path):
    walls = write_vector_map(tmp_path / "building.txt", load_map("doorway").walls)
    out = tmp_path / "mine.json"
    assert (
        main(
            [
                "map",
                "import",
                "--walls",
                str(walls),
                "--name",
                "mine",
                "--seed-point",
                "4",
                "4",
                "--region",
                "-1",
                "-1",
                "17",
                "9",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    m = load_map(out)
    assert m.name == "mine" and m.num_nodes >= 2 and len(m.legal_poses) >= 2


def test_map_import_merges_repeated_walls_and_says_how_many(tmp_path, capsys):
    doorway = load_map("doorway").walls
    # Every wall again reversed (6), then the first wall's first half and the first wall reversed again.
    repeats = [
        [*doorway[0, :2], *doorway[0, :2] / 2 + doorway[0, 2:] / 2],
        [*doorway[0, 2:], *doorway[0, :2]],
    ]
    source = write_vector_map(
        tmp_path / "building.txt", np.vstack((doorway, doorway[:, [2, 3, 0, 1]], repeats))
    )
    out = tmp_path / "mine.json"
    argv = ["map", "import", "--walls", str(source), "--name", "mine", "--out", str(out), "--no-drive"]
    assert main([*argv, "--seed-point", "4", "4"]) == 0
    assert f"{out}: 6 walls (8 repeated pieces merged), " in capsys.readouterr().out
    m = load_map(out)
    np.testing.assert_array_equal(m.walls, doorway)
    assert m.provenance is not None and m.provenance["walls_merged"] == 8


def test_demo_writes_a_gif(tmp_path, capsys):
    out = tmp_path / "episode.gif"
    assert (
        main(
            [
                "demo",
                "--policy",
                "goalone",
                "--map",
                "open_room",
                "--seed",
                "1",
                "--max-frames",
                "30",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    frames = iio.imread(out, index=None)
    assert frames.ndim == 4 and 2 <= len(frames) <= 30
    assert np.ptp(frames) > 0
    assert main(["demo", "--policy", "nobody", "--out", str(out)]) == 2


def test_map_import_from_pedsim_waypoints_and_amrl_nav(tmp_path, capsys):
    walls = load_map("doorway").walls
    obstacles = "".join(f'<obstacle x1="{a}" y1="{b}" x2="{c}" y2="{d}"/>\n' for a, b, c, d in walls)
    scene = tmp_path / "scene.xml"
    scene.write_text(
        f'<scenario>\n{obstacles}<waypoint id="w1" x="4" y="4" r="1"/>\n'
        '<waypoint id="w2" x="12" y="4" r="1"/>\n</scenario>\n'
    )
    out = tmp_path / "scene.json"
    assert main(["map", "import", "--pedsim", str(scene), "--name", "scene", "--out", str(out)]) == 0
    m = load_map(out)
    np.testing.assert_array_equal(m.nodes, [[4, 4], [12, 4]])
    np.testing.assert_array_equal(m.edges, [[0, 1]])

    nav = tmp_path / "nav.json"
    nav.write_text(
        '{"nodes": [{"id": 7, "loc": {"x": 4, "y": 4}}, {"id": 8, "loc": {"x": 12, "y": 4}}],'
        ' "edges": [{"s0_id": 7, "s1_id": 8}]}'
    )
    vector = write_vector_map(tmp_path / "doorway.txt", walls)
    out = tmp_path / "nav_map.json"
    assert (
        main(["map", "import", "--walls", str(vector), "--nav", str(nav), "--name", "n", "--out", str(out)])
        == 0
    )
    assert load_map(out).num_nodes == 2
    capsys.readouterr()
    # A graph edge through the middle wall: --strict refuses it, naming the entry; by default it
    # is rerouted through the door.
    nav.write_text(
        '{"nodes": [{"id": 7, "loc": {"x": 4, "y": 1}}, {"id": 8, "loc": {"x": 12, "y": 1}}],'
        ' "edges": [{"s0_id": 7, "s1_id": 8}]}'
    )
    argv = ["map", "import", "--walls", str(vector), "--nav", str(nav), "--name", "n", "--out", str(out)]
    assert main([*argv, "--strict"]) == 2
    assert "passes through wall" in capsys.readouterr().err
    assert main(argv) == 0
    assert "passes through wall 4: rerouted along a" in capsys.readouterr().out
    assert load_map(out).num_nodes == 3


def _bad_graph_files(tmp_path):
    """A two-room building (0.9 m door) whose navigation graph has a node on the middle wall, an
    edge through it and a stray component far outside."""
    walls = np.array(
        [[0, 0, 16, 0], [16, 0, 16, 8], [16, 8, 0, 8], [0, 8, 0, 0], [8, 0, 8, 3.55], [8, 4.45, 8, 8]], float
    )
    vector = write_vector_map(tmp_path / "building.txt", walls)
    nav = tmp_path / "building.navigation.json"
    nodes = [(1, 4.0, 4.0), (2, 8.0, 2.0), (3, 12.0, 4.0), (4, 30.0, 30.0), (5, 31.0, 30.0)]
    nav.write_text(
        '{"nodes": ['
        + ", ".join(f'{{"id": {i}, "loc": {{"x": {x}, "y": {y}}}}}' for i, x, y in nodes)
        + '], "edges": [{"s0_id": 1, "s1_id": 2}, {"s0_id": 2, "s1_id": 3}, {"s0_id": 4, "s1_id": 5}]}'
    )
    return vector, nav


def test_map_import_repairs_a_real_graph_and_reports_it(tmp_path, capsys):
    vector, nav = _bad_graph_files(tmp_path)
    out = tmp_path / "b.json"
    argv = ["map", "import", "--walls", str(vector), "--nav", str(nav), "--name", "b", "--out", str(out)]
    assert main([*argv, "--strict"]) == 2
    assert "graph.nodes[1] at (8.00, 2.00) lies on wall" in capsys.readouterr().err
    assert not out.exists()
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "repaired: graph.nodes[1] at (8.00, 2.00) lies on wall" in text
    assert "cannot be joined to the rest" in text and "generated: legal poses generated" in text
    m = load_map(out)
    assert m.provenance["importer"] == "socialzoo map import"
    assert m.provenance["inputs"] == {"walls": "building.txt", "nav": "building.navigation.json"}
    kinds = {r["kind"] for r in m.provenance["repairs"]}
    assert {"node_moved", "component_dropped", "poses_generated"} <= kinds


def test_map_check_reports_clearance_routes_and_draws(tmp_path, capsys):
    out = tmp_path / "check.png"
    assert main(["map", "check", "hallway", "--picture", str(out)]) == 0
    text = capsys.readouterr().out
    assert "valid" in text and "routes: 600 of 600 pose pairs feasible" in text
    assert "connectivity: 1 graph component(s)" in text
    assert f"picture: {out}" in text
    assert iio.imread(out).shape[0] > 200
    # A tighter route limit makes most pairs infeasible and says so.
    assert main(["map", "check", "hallway", "--max-route", "12", "--no-picture"]) == 0
    assert "warning: only 46% of pose pairs have a feasible route (<= 12 m)" in capsys.readouterr().out
    # An invalid map lists its problems and exits 2.
    bad = load_map("doorway").to_json()
    bad["graph"]["nodes"][0] = [8.0, 1.0]
    (tmp_path / "bad.json").write_text(__import__("json").dumps(bad))
    assert main(["map", "check", str(tmp_path / "bad.json"), "--no-picture"]) == 2
    assert "INVALID" in capsys.readouterr().out


def test_map_import_from_a_png_floor_plan(tmp_path, capsys):
    img = np.full((160, 320), 255, np.uint8)  # 16 x 8 m at 5 cm per pixel
    img[:4], img[-4:], img[:, :4], img[:, -4:] = 0, 0, 0, 0
    img[:, 158:162] = 0
    img[62:98, 158:162] = 255  # a 1.8 m door in the middle wall
    png = tmp_path / "plan.png"
    iio.imwrite(png, img)
    out = tmp_path / "plan.json"
    argv = ["map", "import", "--png", str(png), "--name", "plan", "--out", str(out)]
    assert main(argv) == 2
    assert "--png needs --scale" in capsys.readouterr().err
    assert main([*argv, "--scale", "0.05", "--origin", "10", "20"]) == 0
    m = load_map(out)
    lo, hi = m.walls.reshape(-1, 2).min(axis=0), m.walls.reshape(-1, 2).max(axis=0)
    np.testing.assert_allclose(lo, [10.0, 20.0], atol=1e-9)
    np.testing.assert_allclose(hi, [26.0, 28.0], atol=1e-9)
    assert (m.legal_poses[:, 0] < 18).any() and (m.legal_poses[:, 0] > 18).any()  # both rooms
    assert m.provenance["inputs"]["scale"] == 0.05


def test_map_import_refuses_image_options_for_a_vector_map(tmp_path, capsys):
    # --walls plan.txt --scale 0.3048 (a plan in feet) imported the plan in feet as metres.
    walls = write_vector_map(tmp_path / "plan.txt", load_map("doorway").walls)
    argv = ["map", "import", "--walls", str(walls), "--name", "plan", "--out", str(tmp_path / "p.json")]
    for extra in (
        ["--scale", "0.3048"],
        ["--origin", "1", "2"],
        ["--threshold", "0.3"],
        ["--min-wall-area", "1"],
    ):
        assert main([*argv, *extra]) == 2
        assert f"only --png takes {extra[0]}: --walls and --pedsim coordinates are read as metres" in (
            capsys.readouterr().err
        )
    assert not (tmp_path / "p.json").exists()


def test_map_check_draws_beside_a_map_file(tmp_path, capsys):
    (tmp_path / "maps").mkdir()
    mine = load_map("hallway").save(tmp_path / "maps" / "mine.json")
    assert main(["map", "check", str(mine)]) == 0
    beside = tmp_path / "maps" / "mine-check.png"
    assert iio.imread(beside).shape[0] > 200
    assert f"picture: {beside}" in capsys.readouterr().out


def test_map_check_of_a_shipped_name_writes_nothing_and_says_how(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["map", "check", "hallway"]) == 0
    assert list(tmp_path.iterdir()) == []
    assert "picture: none (hallway is a shipped map: ask for one with --picture hallway-check.png)" in (
        capsys.readouterr().out
    )


def test_map_check_no_picture_writes_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    mine = load_map("hallway").save(tmp_path / "mine.json")
    assert main(["map", "check", str(mine), "--no-picture"]) == 0
    assert list(tmp_path.iterdir()) == [mine]
    assert "picture: none (--no-picture)" in capsys.readouterr().out
    assert main(["map", "check", str(mine), "--no-picture", "--picture", "x.png"]) == 2
    assert "contradict" in capsys.readouterr().err


def test_map_check_out_is_a_hidden_deprecated_alias_of_picture(tmp_path, capsys):
    out = tmp_path / "old.png"
    assert main(["map", "check", "hallway", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert out.is_file() and f"picture: {out}" in captured.out
    assert "--out is deprecated: use --picture" in captured.err
    with pytest.raises(SystemExit):
        main(["map", "check", "--help"])
    usage = capsys.readouterr().out
    assert "--picture PATH" in usage and "--out" not in usage


def _ros_map(tmp_path, yaml_lines: list[str]):
    """A 16 x 8 m two-room plan as ROS map_server saves one: a PGM (0 occupied, 254 free, 205
    unknown around the building) and its YAML."""
    img = np.full((200, 360), 205, np.uint8)  # 18 x 10 m at 5 cm, unknown
    plan = np.full((160, 320), 254, np.uint8)
    plan[:4], plan[-4:], plan[:, :4], plan[:, -4:] = 0, 0, 0, 0
    plan[:, 158:162] = 0
    plan[62:98, 158:162] = 254  # a 1.8 m door in the middle wall
    plan[20:40, 40:60] = 205  # an unknown patch inside: free space, not a wall
    img[20:180, 20:340] = plan
    iio.imwrite(tmp_path / "lab.pgm", img)
    (tmp_path / "lab.yaml").write_text("\n".join(yaml_lines) + "\n")
    return tmp_path / "lab.yaml"


def test_map_import_reads_a_ros_map_server_yaml_and_its_pgm(tmp_path, capsys):
    # ROS map_server maps are the common robot map: before, --png needed their resolution and
    # origin copied by hand into --scale and --origin, and the threshold converted.
    yaml = _ros_map(
        tmp_path,
        ["image: lab.pgm  # saved by map_saver", "mode: trinary", "resolution: 0.05",
         "origin: [9.0, 19.0, 0.0]", "negate: 0", "occupied_thresh: 0.65", "free_thresh: 0.196"],
    )  # fmt: skip
    out = tmp_path / "lab.json"
    argv = ["map", "import", "--png", str(yaml), "--name", "lab", "--out", str(out), "--no-drive"]
    assert main(argv) == 0
    m = load_map(out)
    lo, hi = m.walls.reshape(-1, 2).min(axis=0), m.walls.reshape(-1, 2).max(axis=0)
    np.testing.assert_allclose(lo, [10.0, 20.0], atol=1e-9)  # the image's lower-left corner at the origin
    np.testing.assert_allclose(hi, [26.0, 28.0], atol=1e-9)
    assert (m.legal_poses[:, 0] < 18).any() and (m.legal_poses[:, 0] > 18).any()  # both rooms
    inputs = m.provenance["inputs"]
    assert inputs["png"] == "lab.yaml" and inputs["image"] == "lab.pgm" and inputs["scale"] == 0.05
    assert inputs["origin"] == [9.0, 19.0] and inputs["threshold"] == pytest.approx(0.35)
    # The same image through --scale and --origin gives the same walls.
    plain = tmp_path / "plain.json"
    argv = ["map", "import", "--png", str(tmp_path / "lab.pgm"), "--scale", "0.05", "--origin", "9", "19"]
    assert main([*argv, "--threshold", "0.35", "--name", "p", "--out", str(plain), "--no-drive"]) == 0
    np.testing.assert_array_equal(load_map(plain).walls, m.walls)
    # The YAML gives the scale and origin: giving them too is refused.
    assert main(["map", "import", "--png", str(yaml), "--scale", "0.1", "--name", "lab"]) == 2
    assert "a map YAML gives the scale and origin" in capsys.readouterr().err


def test_map_import_ros_yaml_yaw_negate_and_errors(tmp_path, capsys):
    yaml = _ros_map(
        tmp_path,
        ["image: lab.pgm", "resolution: 0.05", "origin: [9.0, 19.0, 1.5707963267948966]", "negate: 0"],
    )
    out = tmp_path / "lab.json"
    assert main(["map", "import", "--png", str(yaml), "--name", "lab", "--out", str(out), "--no-drive"]) == 0
    lo, hi = load_map(out).walls.reshape(-1, 2).min(axis=0), load_map(out).walls.reshape(-1, 2).max(axis=0)
    np.testing.assert_allclose(lo, [9.0 - 9.0, 20.0], atol=1e-9)  # turned a quarter about (9, 19)
    np.testing.assert_allclose(hi, [9.0 - 1.0, 36.0], atol=1e-9)
    # negate: white is occupied; the inverted image gives the same plan.
    img = iio.imread(tmp_path / "lab.pgm")
    iio.imwrite(tmp_path / "lab.pgm", (255 - img).astype(np.uint8))
    (tmp_path / "lab.yaml").write_text(
        "image: lab.pgm\nresolution: 0.05\norigin: [9.0, 19.0, 0]\nnegate: 1\n"
    )
    assert main(["map", "import", "--png", str(yaml), "--name", "lab", "--out", str(out), "--no-drive"]) == 0
    np.testing.assert_allclose(load_map(out).walls.reshape(-1, 2).min(axis=0), [10.0, 20.0], atol=1e-9)
    capsys.readouterr()
    (tmp_path / "lab.yaml").write_text("image: lab.pgm\nresolution: 0.05\norigin: [9.0, 19.0]\n")
    assert main(["map", "import", "--png", str(yaml), "--name", "lab"]) == 2
    assert f"{yaml}: origin: expected [x, y, yaw], got [9.0, 19.0]" in capsys.readouterr().err
    (tmp_path / "lab.yaml").write_text("image: gone.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    assert main(["map", "import", "--png", str(yaml), "--name", "lab"]) == 2
    assert f"gone.pgm: no such file (the image named by {yaml})" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["a/b", "../up", ".."])
def test_import_refuses_a_name_that_is_not_one_file_name(tmp_path, capsys, name):
    # The name names files (DIR/test_sets/<name>-test.json): '../up' would write outside DIR, and
    # the import wrote a map that then loaded, or (now) would not load.
    source = write_vector_map(
        tmp_path / "w.txt", np.array([[0, 0, 10, 0], [10, 0, 10, 10], [10, 10, 0, 10], [0, 10, 0, 0]])
    )
    out = tmp_path / "m.json"
    assert (
        main(["map", "import", "--walls", str(source), "--name", name, "--out", str(out), "--no-drive"]) == 2
    )
    assert "--name: name" in capsys.readouterr().err and not out.exists()
