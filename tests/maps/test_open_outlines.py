"""Plans whose outline is open to space the plan does not map (issue 36, item 7): a room whose
doorways lead nowhere imports, its openings closed by virtual walls that the import reports, and a
plan with no room for the robot is still refused by name. Synthetic geometry only."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.bench.drive_check import drive_map
from socialzoo.cli import main
from socialzoo.maps.importers import write_vector_map
from socialzoo.maps.map_file import MapError, graph_components, load_map
from socialzoo.maps.repair import repair_map
from socialzoo.maps.roadmap import free_space

WIDTH, HEIGHT = 10.0, 7.5


def gapped_room(gap: float) -> np.ndarray:
    """A 10 x 7.5 m room with a doorway of `gap` m in the middle of each side, leading outside."""
    cx, cy, h = WIDTH / 2, HEIGHT / 2, gap / 2
    return np.array(
        [
            (0, 0, cx - h, 0), (cx + h, 0, WIDTH, 0),
            (WIDTH, 0, WIDTH, cy - h), (WIDTH, cy + h, WIDTH, HEIGHT),
            (WIDTH, HEIGHT, cx + h, HEIGHT), (cx - h, HEIGHT, 0, HEIGHT),
            (0, HEIGHT, 0, cy + h), (0, cy - h, 0, 0),
        ],
        dtype=np.float64,
    )  # fmt: skip


def in_room(points: np.ndarray) -> np.ndarray:
    x, y = points[:, 0], points[:, 1]
    return (x > 0) & (x < WIDTH) & (y > 0) & (y < HEIGHT)


@pytest.mark.parametrize("gap", [1.0, 2.5, 3.0, 4.0, 5.0])
def test_a_room_with_doorways_to_nowhere_imports_inside_the_room(gap):
    # Gaps of 3 m and more let the outside in: the enclosed area was a corner sliver (0.0 m^2)
    # and the import refused the plan. Now the openings are closed by virtual walls.
    m, report = repair_map("room", gapped_room(gap))
    assert 55.0 < m.walkable_area < 70.0  # the 75 m^2 room less the 0.39 m strip along its walls
    assert in_room(m.legal_poses[:, :2]).all() and len(m.legal_poses) >= 5
    assert in_room(m.nodes).all()
    assert len(np.unique(graph_components(m.num_nodes, m.edges))) == 1
    np.testing.assert_array_equal(m.walls, gapped_room(gap))  # the plan's walls stay as drawn
    closed = [r.message for r in report.repairs if r.kind == "outline_closed"]
    if gap < 3.0:  # narrower than 2 x closing_radius: closed as before, nothing to report
        assert closed == []
    else:
        assert len(closed) == 1 and "4 opening(s) closed by virtual walls" in closed[0]
        assert closed[0].count(f"{gap:.1f} m from") == 4


def test_the_virtual_walls_span_the_doorways():
    closures = free_space(gapped_room(3.0)).closures
    h = 1.5
    expected = {
        ((5 - h, 0.0), (5 + h, 0.0)), ((5 - h, 7.5), (5 + h, 7.5)),
        ((0.0, 3.75 - h), (0.0, 3.75 + h)), ((10.0, 3.75 - h), (10.0, 3.75 + h)),
    }  # fmt: skip
    found = {tuple(sorted(((c[0], c[1]), (c[2], c[3])))) for c in np.round(closures, 6).tolist()}
    assert found == expected


def test_doorways_at_the_corners_are_closed_diagonally():
    g = 3.0
    walls = np.array([(g, 0, 10 - g, 0), (10, g, 10, 7.5 - g), (10 - g, 7.5, g, 7.5), (0, 7.5 - g, 0, g)])
    m, report = repair_map("corners", walls)
    assert [r.kind for r in report.repairs].count("outline_closed") == 1
    assert in_room(m.legal_poses[:, :2]).all() and m.walkable_area > 40.0
    closures = free_space(walls).closures
    lengths = np.hypot(closures[:, 2] - closures[:, 0], closures[:, 3] - closures[:, 1])
    np.testing.assert_allclose(lengths, [g * np.sqrt(2)] * 4)


def test_an_enclosed_closet_does_not_hide_the_open_room_around_it():
    # The closet (2.5 x 2.5 m, closed) was the largest enclosed area; the room around it is
    # twice as large once its 4 m doorways are closed, so the room is the building.
    closet = [(0.5, 0.5, 3.0, 0.5), (3.0, 0.5, 3.0, 3.0), (3.0, 3.0, 0.5, 3.0), (0.5, 3.0, 0.5, 0.5)]
    m, report = repair_map("closet", np.concatenate((gapped_room(4.0), np.array(closet, float))))
    assert [r.kind for r in report.repairs].count("outline_closed") == 1
    assert m.walkable_area > 45.0
    assert (m.legal_poses[:, 0] > 3.0).any() and in_room(m.legal_poses[:, :2]).all()


def test_a_corner_pocket_is_not_taken_for_the_room():
    # A room open at its top-left corner (5 m) with a narrow gap at its bottom-right: with the outside
    # let in at the first closing radius, only a pocket by the bottom-right corner stayed enclosed. It
    # has the clearance for one pose but not for a start and a goal, and was taken for the building
    # (0.05 m^2; the import then refused the plan, "needs at least 2 poses"). Found on a real
    # reading-room plan whose outline is open the same way.
    walls = np.array(
        [
            (-0.475, 6.062, -0.35, -0.3), (-0.35, -0.4, 9.175, -0.587),
            (10.138, -0.326, 9.9, 7.25), (9.9, 7.25, 4.264, 7.128),
        ]
    )  # fmt: skip
    space = free_space(walls)
    assert space.interior.sum() * space.resolution**2 > 55.0
    # Virtual walls from the top wall's end to the left wall, and across the bottom-right gap.
    ends = {tuple(p) for p in np.round(space.closures.reshape(-1, 2), 2).tolist()}
    assert {(4.26, 7.13), (10.14, -0.33), (9.18, -0.59)} <= ends and len(space.closures) == 2
    m, _ = repair_map("pocket", walls)
    assert len(m.legal_poses) >= 5


def test_goalone_drives_the_gapped_room():
    m, _ = repair_map("room", gapped_room(3.0))
    report = drive_map(m)
    assert len(report.routes) >= 20 and report.complete, report.lines()


def test_map_import_reports_what_it_closed(tmp_path, capsys):
    walls = write_vector_map(tmp_path / "room.vectormap.txt", gapped_room(4.0))
    out = tmp_path / "room.json"
    assert (
        main(["map", "import", "--walls", str(walls), "--name", "room", "--out", str(out), "--no-drive"]) == 0
    )
    text = capsys.readouterr().out
    assert "repaired: the building's outline is open to space the plan does not map" in text
    assert (
        "4.0 m from (3.00, 0.00) to (7.00, 0.00)" in text or "4.0 m from (7.00, 0.00) to (3.00, 0.00)" in text
    )
    m = load_map(out)
    assert m.walkable_area > 55.0 and in_room(m.legal_poses[:, :2]).all()
    assert [r["kind"] for r in m.provenance["repairs"]].count("outline_closed") == 1


@pytest.mark.parametrize("gap", [0.5, 0.85])
def test_a_gapped_plan_without_room_for_the_robot_is_still_refused(gap):
    # A 0.85 m corridor whose west end has a doorway to nowhere (0.85: the end is open): no place
    # inside is 0.44 m from every wall, whatever closes the doorway.
    length, w = 20.0, 0.85
    walls = [(0, 0, length, 0), (0, w, length, w), (length, 0, length, w)]
    if gap < w:
        walls += [(0, 0, 0, (w - gap) / 2), (0, (w + gap) / 2, 0, w)]
    with pytest.raises(MapError, match=r"narrower than the 0\.88 m a pose needs"):
        repair_map("too_tight", np.array(walls, dtype=np.float64))


def test_strict_import_says_what_it_closed(tmp_path, capsys):
    walls = write_vector_map(tmp_path / "room.vectormap.txt", gapped_room(3.0))
    out = tmp_path / "room.json"
    args = [
        "map",
        "import",
        "--walls",
        str(walls),
        "--name",
        "room",
        "--out",
        str(out),
        "--no-drive",
        "--strict",
    ]
    assert main(args) == 0
    assert "closed: the building's outline is open to space the plan does not map" in capsys.readouterr().out
    m = load_map(out)
    assert len(m.provenance["outline_closed"]) == 4 and m.provenance["repairs"] == []
    assert in_room(m.legal_poses[:, :2]).all()
