"""The map that checks itself by driving, on small synthetic plans: a door too narrow for the robot
is reported, a 0.8 m door that used to wedge the robot is passed, a goal behind a crack is reported
and repaired, and a robot stuck at a narrow door recovers over another edge."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.bench.drive_check import DRIVE_CAUSES, drive_map, pose_pairs
from socialzoo.bench.map_repair import repair_by_driving
from socialzoo.maps import floorplans
from socialzoo.maps.map_file import Map, validate_map


def _map(name: str, walls: np.ndarray, nodes, edges, poses) -> Map:
    m = Map(
        name=name,
        walls=np.asarray(walls, dtype=np.float64),
        nodes=np.asarray(nodes, dtype=np.float64),
        edges=np.asarray(edges, dtype=np.int64),
        legal_poses=np.asarray(poses, dtype=np.float64),
    )
    validate_map(m)
    return m


def narrow_door_map(door: float = 0.6) -> Map:
    """Two rooms joined by one door (0.6 m: too narrow for the robot's 0.74 m), two poses in each."""
    plan = floorplans.two_rooms(door)
    nodes = [(2.5, 2.0), (7.5, 2.0)]
    poses = [(1.2, 1.0, 0.0), (3.5, 3.0, 0.0), (6.5, 1.0, 0.0), (8.8, 3.0, 0.0)]
    return _map("narrow_door", plan.walls, nodes, [(0, 1)], poses)


def test_a_door_too_narrow_is_reported_where_it_is():
    m = narrow_door_map()
    report = drive_map(m)
    done = {(r.start, r.goal) for r in report.routes if r.reached}
    assert done == {(0, 1), (1, 0), (2, 3), (3, 2)}  # within each room
    assert len(report.failures) == 8 and set(report.counts()) == {"blocked_doorway"}
    for r in report.failures:
        assert np.hypot(*(r.where - (5.0, 2.0))) < 0.3  # the door
        assert r.gap < report.wall_distance
        assert r.describe().startswith(f"pose {r.start} -> pose {r.goal}: blocked doorway at (")
    assert report.lines()[0].startswith("drive: 4 of 12 routes completed (33%)")
    assert set(report.counts()) <= set(DRIVE_CAUSES)


def test_map_check_drive_reports_the_door(tmp_path, capsys):
    from socialzoo.cli import main

    path = narrow_door_map().save(tmp_path / "narrow.json")
    assert main(["map", "check", str(path), "--drive", "--no-picture"]) == 1
    out = capsys.readouterr().out
    assert "drive: 4 of 12 routes completed" in out and "blocked_doorway 8" in out
    assert "blocked doorway at (" in out
    assert main(["map", "check", str(path), "--drive", "3", "--seed", "1", "--no-picture"]) in (0, 1)
    assert "of 3 routes completed" in capsys.readouterr().out


def wedge_map() -> Map:
    """An office floor with 0.8 m doors and a plan that turns into a door from the corridor and
    sharply again just past it: the robot used to stop in the doorway pressed against the jamb,
    turning to and fro (Sight's 2 cm tolerance let the carrot sit across the jamb)."""
    plan = floorplans.office_corridor(1, num_offices=6, door_width=0.8, thickness=0.15)
    nodes = [
        (17.18, 1.95),
        (16.95, 1.12),
        (16.95, 0.0),
        (18.05, 0.0),
        (18.05, -1.0),
        (18.05, -1.18),
        (17.16, -3.02),
    ]
    edges = [(k, k + 1) for k in range(len(nodes) - 1)]
    return _map("wedge", plan.walls, nodes, edges, [(16.9, 2.023, 1.22), (16.35, -2.63, 0.5)])


def test_the_robot_passes_a_door_it_used_to_wedge_beside():
    report = drive_map(wedge_map())
    assert report.complete, report.lines()
    assert max(r.time for r in report.routes) < 10.0  # straight through, no recovery needed


def crack_map(outside_route: bool) -> Map:
    """A room whose top wall has a 2 cm crack; a pose above the room sees the room's node only
    through the crack (a wall-free line the robot cannot drive). With outside_route, the graph
    also runs round the room outside, and the pose joins it there."""
    box = [(0, 0, 10, 0), (10, 0, 10, 8), (10, 8, 0, 8), (0, 8, 0, 0)]
    room = [(2, 2, 3.5, 2), (4.5, 2, 6, 2), (6, 2, 6, 5), (6, 5, 4.01, 5), (3.99, 5, 2, 5), (2, 5, 2, 2)]
    nodes = [(4.0, 3.5), (4.0, 1.0), (8.0, 1.0)]
    edges = [(0, 1), (1, 2)]
    if outside_route:
        nodes.append((8.0, 6.5))
        edges.append((2, 3))
    poses = [(4.0, 6.5, 0.0), (1.0, 1.0, 0.0), (8.8, 1.0, 0.0), (4.0, 3.0, 0.0)]
    return _map("crack", box + room, nodes, edges, poses)


def test_a_goal_behind_a_crack_is_reported_and_repaired():
    m = crack_map(outside_route=False)
    report = drive_map(m)
    failed = {(r.start, r.goal): r for r in report.failures}
    assert failed and all(0 in pair for pair in failed)  # only pose 0, above the room
    causes = {r.cause for r in failed.values()}
    assert causes <= {"goal_unreachable", "start_unleavable"} and "goal_unreachable" in causes
    for r in failed.values():
        assert np.hypot(*(r.where - (4.0, 5.0))) < 0.5  # at the crack
    repaired, repairs, first = repair_by_driving(m, report=report)
    assert first is report
    assert [r.kind for r in repairs] == ["pose_dropped"]
    assert "legal_poses[0] at (4.00, 6.50)" in repairs[0].message
    assert len(repaired.legal_poses) == 3
    assert repaired.provenance["drive"]["routes_completed"] == len(report.routes) - len(report.failures)
    assert drive_map(repaired).complete


def test_a_robot_joins_the_graph_by_a_line_it_can_drive():
    # The same pose, with the graph also outside the room: its plans join there, not through the
    # crack (NavGraph.attach with the robot's clearance), so every route is completed.
    assert drive_map(crack_map(outside_route=True)).complete


def two_doors_map() -> Map:
    """Two rooms joined by a 0.6 m door on the short route and a 1.0 m door on a longer one."""
    walls = [(0, 0, 10, 0), (10, 0, 10, 6), (10, 6, 0, 6), (0, 6, 0, 0)]
    walls += [(5, 0, 5, 1.2), (5, 1.8, 5, 4.5), (5, 5.5, 5, 6)]
    nodes = [(2.5, 1.5), (7.5, 1.5), (2.5, 5.0), (5.0, 5.0), (7.5, 5.0)]
    edges = [(0, 1), (0, 2), (2, 3), (3, 4), (4, 1)]
    return _map("two_doors", walls, nodes, edges, [(1.0, 1.0, 0.0), (9.0, 1.0, 0.0)])


def test_a_stuck_robot_recovers_over_another_edge():
    from socialzoo.bench.drive_check import _scenario, drive_config
    from socialzoo.env.tasks.action_selection import ActionSelectionTask

    m = two_doors_map()
    report = drive_map(m)
    assert report.complete, report.lines()
    # It drove to the narrow door first, backed off and went round by the wide one.
    task = ActionSelectionTask(drive_config(m), 1, map_data=m)
    task.reset_rows([0], [_scenario(m, m.legal_poses, 0, 1)])
    ys = []
    while not task.core.done[0, 0]:
        task.step(np.zeros((1, 1), dtype=np.int64))
        ys.append(task.core.state.robot_pose[0, 0, 1])
    assert task.episode_metrics([0])[0]["reached"]
    assert task.core.navigator.recovery_state.recoveries[0, 0] >= 1 and max(ys) > 4.0


def test_pose_pairs_are_the_feasible_ones_or_a_seeded_sample():
    m = narrow_door_map()
    pairs = pose_pairs(m)
    assert len(pairs) == 12 and (pairs[:, 0] != pairs[:, 1]).all()
    sample = pose_pairs(m, 5, seed=3)
    assert len(sample) == 5 and np.array_equal(sample, pose_pairs(m, 5, seed=3))
    assert len(pose_pairs(m, max_route_length=3.0)) < 12  # only the short routes


def test_import_drives_the_map_and_records_it(tmp_path, capsys):
    import json

    from socialzoo.cli import main
    from socialzoo.maps.importers import write_vector_map
    from socialzoo.maps.map_file import read_map

    m = crack_map(outside_route=False)
    walls = write_vector_map(tmp_path / "crack.txt", m.walls)
    graph = tmp_path / "crack.navigation.json"
    nodes = [{"id": k, "loc": {"x": x, "y": y}} for k, (x, y) in enumerate(m.nodes.tolist())]
    graph.write_text(
        json.dumps({"nodes": nodes, "edges": [{"s0_id": i, "s1_id": j} for i, j in m.edges.tolist()]})
    )
    out = tmp_path / "crack.json"
    args = ["map", "import", "--walls", str(walls), "--nav", str(graph), "--name", "crack", "--out", str(out)]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "driving: the robot alone over" in text and "routes completed (100%)" in text
    back = read_map(out)
    # Generated poses join the graph by lines the robot can drive: none stands behind the crack.
    drive = back.provenance["drive"]
    assert drive["routes_completed"] == drive["routes_driven"] == drive["pairs_completed_after_repairs"] > 0
    assert main([*args, "--no-drive", "--out", str(tmp_path / "quick.json")]) == 0
    assert "driving" not in capsys.readouterr().out


def test_strict_import_refuses_a_route_it_cannot_drive():
    from socialzoo.cli.map_cmd import _drive_and_repair
    from socialzoo.maps.map_file import MapError

    with pytest.raises(MapError, match=r"(?s)--strict: failed: .*pose 1 -> pose 0: goal unreachable"):
        _drive_and_repair(crack_map(outside_route=False), strict=True)


# ------------------------------------------------------------------ buildings with people (map drive)


def test_the_builtin_buildings_are_the_reference_floors_and_seeded_plans():
    from socialzoo.bench.drive_check import builtin_buildings

    buildings = builtin_buildings()
    assert list(buildings)[:3] == ["gdc1_floor2", "ghc3_raw", "office_corridor_1"]
    assert len(buildings) == 11 and "long_corridor" in buildings
    assert all(w.ndim == 2 and w.shape[1] == 4 and len(w) >= 4 for w in buildings.values())
    assert (buildings["gdc1_floor2"][:, [1, 3]] < -5.0).all()  # the floor the benchmark never uses
    again = builtin_buildings()
    assert all(np.array_equal(buildings[k], again[k]) for k in buildings)  # seeded


def test_a_building_row_gives_the_import_and_every_outcome():
    from socialzoo.bench.drive_check import BuildingEpisodes, building_row, building_table_head

    head, rule = building_table_head()
    columns = head.count("|") - 1
    assert "human collision" in head and "never moved" in head and rule.count("---") == columns
    m = narrow_door_map()
    outcomes = {"success": 8, "wall_collision": 0, "human_collision": 1, "stuck": 1, "timeout": 0}
    row = building_row("door", True, "ok", m, BuildingEpisodes(10, outcomes, 2, 1), 12.3)
    assert row == f"| door | yes | ok | {m.num_walls} | 2 | 4 | - | 0 | 80 | 0 | 1 | 1 | 0 | 2 | 1 | 12 |"
    refused = building_row("bad", False, "error: no walls", None, None, 1.0)
    assert refused.startswith("| bad | no | error: no walls |") and refused.count("|") == columns + 1


def test_a_failure_picture_shows_the_episode(tmp_path):
    from socialzoo.bench.drive_check import draw_failure
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.scenario_sets import validation_set

    scenario = validation_set("gdc1").scenario(0)
    start, goal = scenario.robot_start[:2], scenario.robot_goal[:2]
    path = draw_failure(load_map("gdc1"), scenario, np.stack((start, start + 1.0)), np.stack((start, goal)),
                        "gdc1 scenario 0", tmp_path / "fail.png")  # fmt: skip
    assert path.is_file() and path.stat().st_size > 1000


def test_map_drive_imports_a_folder_and_reports_goalone(tmp_path, capsys):
    from socialzoo.cli import main
    from socialzoo.maps.importers import write_vector_map

    folder, out = tmp_path / "buildings", tmp_path / "out"
    folder.mkdir()
    plan = floorplans.winding_corridor(1, num_legs=8, leg_length=(3.0, 10.0))
    write_vector_map(folder / "wind.vectormap.txt", plan.walls)
    (folder / "empty.vectormap.txt").write_text("")
    status = main(["map", "drive", str(folder), "--out", str(out), "--episodes", "3"])
    lines = capsys.readouterr().out.splitlines()
    assert status == 1  # the empty building's import was refused
    rows = {line.split(" | ")[0][2:]: line.split(" | ") for line in lines[2:]}
    assert set(rows) == {"empty", "wind"}
    wind = rows["wind"]
    assert wind[1:3] == ["no", "ok"]
    # Every episode is a success or a failure of one cause.
    assert sum(int(v) for v in wind[9:13]) == round(3 * (100 - int(wind[8])) / 100)
    assert (out / "wind.json").is_file() and (out / "wind.import.txt").is_file()
    assert (out / "test_sets" / "wind-test.json").is_file()
    assert rows["empty"][2] != "ok"
    assert main(["map", "drive", str(folder), "--out", str(out), "--only", "nope"]) == 2
    assert "no building nope" in capsys.readouterr().err
    assert main(["map", "drive", str(tmp_path / "missing"), "--out", str(out)]) == 2
