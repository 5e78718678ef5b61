"""`socialzoo map ...` and `socialzoo demo` run in-process."""

import imageio.v3 as iio
import numpy as np

from socialzoo.cli import main
from socialzoo.nav.importers import write_vector_map
from socialzoo.nav.maps import load_map


def test_map_show_writes_a_png(tmp_path, capsys):
    out = tmp_path / "gdc1.png"
    assert main(["map", "show", "gdc1", "--out", str(out)]) == 0
    image = iio.imread(out)
    assert image.ndim == 3 and image.shape[0] > 200
    assert "77 nodes" in capsys.readouterr().out


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
    # A graph edge through the middle wall is refused, naming the entry.
    nav.write_text(
        '{"nodes": [{"id": 7, "loc": {"x": 4, "y": 1}}, {"id": 8, "loc": {"x": 12, "y": 1}}],'
        ' "edges": [{"s0_id": 7, "s1_id": 8}]}'
    )
    assert (
        main(["map", "import", "--walls", str(vector), "--nav", str(nav), "--name", "n", "--out", str(out)])
        == 2
    )
    assert "passes through wall" in capsys.readouterr().err
