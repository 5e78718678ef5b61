"""The scenario suite's shipped maps: they load, list their doors, and have room where the suite needs it."""

import numpy as np
import pytest

from socialzoo.maps.map_file import list_maps, load_map

# name -> its doors, as drawn in tools/build_maps.py
DOORS = {
    "corner": [],
    "narrow_hallway": [],
    "room": [[7.4, 3.0, 8.6, 3.0]],
    "elevator": [[5.4, 5.0, 6.6, 5.0]],
    "plaza": [],
    "doorway": [[8.0, 3.4, 8.0, 4.6]],
}


def _inside(points: np.ndarray, box: tuple[float, float, float, float]) -> np.ndarray:
    x0, y0, x1, y1 = box
    return (points[:, 0] > x0) & (points[:, 0] < x1) & (points[:, 1] > y0) & (points[:, 1] < y1)


@pytest.mark.parametrize("name", sorted(DOORS))
def test_each_map_loads_with_its_doors(name):
    assert name in list_maps()
    m = load_map(name)
    assert m.licence.startswith("CC0") and m.source
    np.testing.assert_allclose(m.doors.reshape(-1, 4), np.reshape(DOORS[name], (-1, 4)))
    assert len(m.legal_poses) >= 2
    for x1, y1, x2, y2 in m.doors:
        # A door spans an opening: no wall crosses it, and walls end at both of its ends.
        a, b = np.array([[x1, y1]]), np.array([[x2, y2]])
        inset = 0.01 * (b - a)
        assert not m.wall_index.crosses(a + inset, b - inset)[0], name
        ends = np.concatenate((m.walls[:, :2], m.walls[:, 2:]))
        for end in (a, b):
            assert np.hypot(*(ends - end).T).min() < 1e-9, name


@pytest.mark.parametrize("name", ["room", "elevator", "doorway"])
def test_a_legal_pose_lies_on_each_side_of_the_door_near_it(name):
    m = load_map(name)
    (x1, y1, x2, y2), mid = m.doors[0], m.doors[0].reshape(2, 2).mean(axis=0)
    pos = m.legal_poses[:, :2]
    side = np.sign((x2 - x1) * (pos[:, 1] - y1) - (y2 - y1) * (pos[:, 0] - x1))
    near = np.hypot(*(pos - mid).T) < 3.0
    assert (near & (side > 0)).any() and (near & (side < 0)).any(), name


def test_elevator_car_holds_poses_and_a_node_and_the_lobby_has_poses_either_side_of_its_door():
    m = load_map("elevator")
    car = (4.8, 5.0, 7.2, 7.2)
    assert _inside(m.legal_poses[:, :2], car).sum() >= 2
    assert _inside(m.nodes, car).any()
    lobby = m.legal_poses[_inside(m.legal_poses[:, :2], (0.0, 0.0, 12.0, 5.0))]
    assert (lobby[:, 0] < 5.4).any() and (lobby[:, 0] > 6.6).any()


def test_room_has_poses_in_the_room_and_along_the_corridor_both_ways():
    m = load_map("room")
    pos = m.legal_poses[:, :2]
    assert _inside(pos, (5.0, 3.0, 11.0, 8.0)).sum() >= 2
    corridor = pos[_inside(pos, (0.0, 0.0, 16.0, 3.0))]
    assert (corridor[:, 0] < 7.4).any() and (corridor[:, 0] > 8.6).any()


def test_corner_legs_cannot_see_each_other():
    m = load_map("corner")
    # Points on the centre lines of the two legs, 3-10 m from where they meet, (1, 1).
    along = np.linspace(3.0, 10.0, 8)
    leg_x = np.stack([1.0 + along, np.ones_like(along)], axis=1)
    leg_y = leg_x[:, ::-1]
    a = np.repeat(leg_x, len(leg_y), axis=0)
    b = np.tile(leg_y, (len(leg_x), 1))
    assert m.wall_index.crosses(a, b).all()
    pos = m.legal_poses[:, :2]
    # Poses at both far ends of the L.
    assert (pos[:, 0] > 9.0).any() and (pos[:, 1] > 9.0).any()


def test_narrow_hallway_has_poses_in_its_corridor_and_both_rooms():
    m = load_map("narrow_hallway")
    pos = m.legal_poses[:, :2]
    assert _inside(pos, (6.0, 2.3, 16.0, 3.7)).any()
    assert _inside(pos, (0.0, 0.0, 6.0, 6.0)).any() and _inside(pos, (16.0, 0.0, 22.0, 6.0)).any()


def test_plaza_is_an_open_area():
    m = load_map("plaza")
    assert m.num_walls == 4
    assert len(m.legal_poses) >= 10
