"""Imports of plans with tight spaces: corridors narrower than 1.2 m get legal poses, a plan with
no place for one is refused with a message naming the part of the plan and why, and a given
graph that lies in a wing with an open outline keeps its free space."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.maps import floorplans
from socialzoo.maps.legal_poses import generate_legal_poses
from socialzoo.maps.map_file import MapError
from socialzoo.maps.repair import repair_map


@pytest.mark.parametrize("width", [1.1, 0.95])
def test_tight_corridors_get_legal_poses(width):
    # No point is 0.6 m from the walls (the preferred pose clearance): the poses come down to
    # the passable clearance plus a grid cell instead of refusing ("found 0 places" before).
    m, _ = repair_map("tight", floorplans.long_corridor(20.0, width=width).walls)
    clearance = m.wall_index.nearest(m.legal_poses[:, :2])[1]
    assert len(m.legal_poses) >= 5
    assert (clearance >= 0.44 - 1e-9).all() and (clearance < 0.6).all()


def test_no_place_for_a_pose_is_refused_naming_the_part_and_why():
    with pytest.raises(MapError) as err:
        repair_map("too_tight", floorplans.long_corridor(20.0, width=0.85).walls)
    message = str(err.value)
    assert "found 0 places for legal poses with 0.44 m clearance" in message
    assert "between (0.4, 0.4) and (19.6, 0.4)" in message and "at most 0.42 m from a wall" in message
    assert "narrower than the 0.88 m a pose needs" in message


def test_a_given_graph_in_a_wing_with_an_open_outline_keeps_its_free_space():
    # A closed room (larger) and a wing whose west wall has a 3.5 m gap: the enclosed area used
    # to be the room, the graph was dropped and no pose could join it (AHGM). Now the free space
    # is where the graph lies, with the wing's outline closed up to 4 m.
    closed = [(0, 0, 12, 0), (12, 0, 12, 12), (12, 12, 0, 12), (0, 12, 0, 0)]
    wing = [(20, 0, 32, 0), (32, 0, 32, 6), (32, 6, 20, 6), (20, 6, 20, 4.75), (20, 1.25, 20, 0)]
    wing += [(24, 0, 24, 2.5), (28, 6, 28, 3.5)]
    nodes = np.array([[22.0, 3.0], [26.0, 3.0], [30.0, 3.0]])
    m, report = repair_map(
        "wing", np.array(closed + wing, float), nodes=nodes, edges=np.array([[0, 1], [1, 2]])
    )
    assert [r.kind for r in report.repairs] == ["outline_closed", "poses_generated"]
    assert "openings in the building's outline up to 4 m wide count as closed" in report.repairs[0].message
    np.testing.assert_array_equal(m.nodes, nodes)
    assert (m.legal_poses[:, 0] > 20.0).all() and len(m.legal_poses) >= 5


def _square_room(side: float) -> np.ndarray:
    return np.array([[0, 0, side, 0], [side, 0, side, side], [side, side, 0, side], [0, side, 0, 0]], float)


def test_a_small_room_gets_a_start_and_a_goal_in_its_corners():
    # A 3 m room: its places 0.6 m from the walls are all within 1.5 m of each other, and the
    # tight pass's farthest-point sampling stopped at its roomy middle, so the import failed
    # validation ("legal_poses: needs at least 2 poses ..., got 1", the ROS TurtleBot3 world too).
    # The second pose is the best place at least pose_separation (2 m) from the first.
    m, _ = repair_map("small_room", _square_room(3.0))
    assert len(m.legal_poses) == 2
    assert np.hypot(*(m.legal_poses[0, :2] - m.legal_poses[1, :2])) >= 2.0
    assert (m.wall_index.nearest(m.legal_poses[:, :2])[1] >= 0.44 - 1e-9).all()


def test_a_room_too_small_for_two_poses_is_refused_naming_why():
    with pytest.raises(MapError) as err:
        repair_map("closet", _square_room(2.4))
    message = str(err.value)
    assert "legal_poses: needs at least 2 poses" not in message
    assert "found 14 places for legal poses with 0.44 m clearance" in message
    assert "between (0.4, 0.4) and (2.0, 2.0)" in message
    assert "too small for a start and a goal 2.0 m apart" in message


def test_a_free_space_without_a_reachable_graph_node_is_not_called_narrow():
    # A 10 m room whose only graph node lies in another room: the refusal said "its rooms and
    # passages are narrower than the 0.88 m a pose needs" beside "at most 5.00 m from a wall"
    # (pedsim_ros's airport imported with --region). It names the missing join instead.
    rooms = np.concatenate((_square_room(10.0), _square_room(10.0) + [20.0, 0.0, 20.0, 0.0]))
    with pytest.raises(MapError) as err:
        generate_legal_poses(rooms, np.array([[25.0, 5.0]]), np.zeros((0, 2), int), seed_point=(5.0, 5.0))
    message = str(err.value)
    assert "at most 5.00 m from a wall" in message and "narrower than" not in message
    assert "0 of the graph nodes lie in it, and no place with room for a pose sees one" in message
