"""Global-plan tracking: distance to the path, the carrot on hand-built paths, replanning."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from socialzoo.core.geometry import closest_point_on_segment
from socialzoo.nav.navigator import GlobalPlans, Navigator, track

L_PATH = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])


def padded(path: np.ndarray, width: int) -> np.ndarray:
    return np.concatenate((path, np.repeat(path[-1:], width - len(path), axis=0)))


def carrot(*args, **kwargs):  # the carrot alone of `track`
    return track(*args, **kwargs)[0]


class StraightGraph:
    """A stand-in navigation graph: the straight line from start to goal, counting its calls."""

    def __init__(self) -> None:
        self.calls: list[int] = []

    def plan_batch(self, starts: np.ndarray, goals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.calls.append(len(starts))
        return np.stack((starts, goals), axis=1), np.full(len(starts), 2)


def test_carrot_on_a_straight_line():
    path = np.array([[0.0, 0.0], [10.0, 0.0]])
    c = carrot(np.array([2.0, 0.3]), path, np.array(2))
    assert c[1] == pytest.approx(0.0)
    assert np.hypot(c[0] - 2.0, c[1] - 0.3) == pytest.approx(1.5)
    assert c[0] > 2.0  # forward, not backward


def test_carrot_turns_the_corner_of_an_l_shape():
    # Near the corner the circle leaves the path on its second leg.
    c = carrot(np.array([9.5, 0.0]), L_PATH, np.array(3))
    assert c[0] == pytest.approx(10.0)
    assert np.hypot(c[0] - 9.5, c[1]) == pytest.approx(1.5)
    assert c[1] > 0
    # Before the corner it stays on the first leg.
    c = carrot(np.array([5.0, 0.2]), L_PATH, np.array(3))
    assert c[1] == pytest.approx(0.0) and c[0] > 5.0


def test_carrot_is_the_goal_inside_the_circle():
    c = carrot(np.array([10.0, 9.0]), L_PATH, np.array(3))
    np.testing.assert_allclose(c, [10.0, 10.0])
    # Also for a one-waypoint path.
    np.testing.assert_allclose(carrot(np.array([0.5, 0.0]), np.array([[1.0, 0.0]]), np.array(1)), [1.0, 0.0])


def test_carrot_far_from_the_path_is_the_closest_path_point():
    c = carrot(np.array([3.0, 4.0]), L_PATH, np.array(3))
    np.testing.assert_allclose(c, [3.0, 0.0])


def test_carrot_ignores_padding_and_batches():
    paths = np.stack((padded(L_PATH, 5), padded(np.array([[0.0, 0.0], [0.0, -8.0]]), 5)))
    lengths = np.array([3, 2])
    pos = np.array([[9.5, 0.0], [0.0, -7.0]])
    c = carrot(pos, paths, lengths)
    np.testing.assert_allclose(c[1], [0.0, -8.0])  # goal inside the circle
    np.testing.assert_allclose(c[0], carrot(pos[0], L_PATH, np.array(3)))
    # (B, R) leading axes.
    c2 = carrot(pos[:, None], paths[:, None], lengths[:, None])
    np.testing.assert_allclose(c2[:, 0], c)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(st.floats(-10, 10), st.floats(-10, 10)), min_size=2, max_size=6),
    st.tuples(st.floats(-12, 12), st.floats(-12, 12)),
)
def test_distance_and_carrot_properties(points, robot):
    path = np.array(points)
    pos = np.array(robot)
    width = len(path) + 2
    lengths = np.array(len(path))
    dist = track(pos, padded(path, width), lengths)[1]
    _, brute = closest_point_on_segment(pos, path[:-1], path[1:])
    assert dist == pytest.approx(brute.min(), abs=1e-9)
    c = carrot(pos, padded(path, width), lengths)
    _, on_path = closest_point_on_segment(c, path[:-1], path[1:])
    assert on_path.min() < 1e-6  # the carrot lies on the path
    goal_dist = np.hypot(*(path[-1] - pos))
    if goal_dist < 1.5:
        np.testing.assert_allclose(c, path[-1])
    elif dist <= 1.5:
        assert np.hypot(*(c - pos)) == pytest.approx(1.5, abs=1e-6)


def test_global_plans_assign_pads_both_ways():
    plans = GlobalPlans.empty(3, 1)
    plans.assign((np.array([0]),), L_PATH[None], np.array([3]))
    assert plans.paths.shape == (3, 1, 3, 2)
    np.testing.assert_allclose(plans.paths[1, 0], 0.0)  # padded with its last (only) waypoint
    plans.assign((np.array([2]),), np.array([[[1.0, 1.0], [2.0, 2.0]]]), np.array([2]))
    np.testing.assert_allclose(plans.paths[2, 0], [[1, 1], [2, 2], [2, 2]])
    assert plans.lengths.tolist() == [[3], [1], [2]]


def test_navigator_replans_only_strayed_rows():
    graph = StraightGraph()
    nav = Navigator(graph, batch_size=3)
    starts = np.zeros((3, 2))
    goals = np.array([[10.0, 0.0], [0.0, 10.0], [-10.0, 0.0]])
    nav.reset(np.arange(3), starts, goals)
    assert graph.calls == [3]
    pos = np.array([[[2.0, 0.1]], [[0.2, 3.0]], [[-4.0, 0.0]]])
    c = nav.update(pos)
    assert graph.calls == [3]  # nobody strayed
    np.testing.assert_allclose(c[0, 0], [2.0 + np.sqrt(1.5**2 - 0.1**2), 0.0])
    pos[1, 0] = [2.0, 3.0]  # 2 m off its plan
    c = nav.update(pos)
    assert graph.calls == [3, 1]
    np.testing.assert_allclose(nav.plans.paths[1, 0, 0], [2.0, 3.0])  # replanned from where it is
    np.testing.assert_allclose(nav.plans.paths[1, 0, nav.plans.lengths[1, 0] - 1], [0.0, 10.0])
    assert track(c[1, 0], nav.plans.paths[1, 0], nav.plans.lengths[1, 0])[1] < 1e-9
    # Resetting one row leaves the others.
    nav.reset(np.array([2]), np.array([[5.0, 5.0]]), np.array([[6.0, 5.0]]))
    np.testing.assert_allclose(nav.goals[2, 0], [6.0, 5.0])
    np.testing.assert_allclose(nav.goals[0, 0], [10.0, 0.0])


def test_navigator_rejects_bad_parameters():
    with pytest.raises(ValueError, match="carrot_radius"):
        Navigator(StraightGraph(), 1, carrot_radius=0.0)
    with pytest.raises(ValueError, match="replan_distance"):
        Navigator(StraightGraph(), 1, replan_distance=-1.0)


def test_max_skip_keeps_the_carrot_out_of_a_u_turn():
    # Up one leg, across, and back down a parallel leg 1.2 m away (a wall between the legs).
    path = np.array([[0.0, 0.0], [0.0, 2.0], [1.2, 2.0], [1.2, 0.0], [1.2, -5.0]])
    pos = np.array([0.0, 1.2])
    np.testing.assert_allclose(carrot(pos, path, np.array(5)), [1.2, 0.3], atol=1e-9)  # SPEC: cuts across
    np.testing.assert_allclose(carrot(pos, path, np.array(5), max_skip=0), [0.0, 2.0])
    # A first segment end nearer than radius / 2 does not count: the next waypoint does.
    np.testing.assert_allclose(carrot(np.array([0.0, 1.5]), path, np.array(5), max_skip=0), [1.2, 2.0])


def test_tolerance_follows_a_path_that_doubles_back():
    # Out to x = 3 and back just beside the way out: near the first leg the robot is about as
    # close to the second, and the carrot should lead on along the path, not back to its start.
    path = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 0.2], [-4.0, 0.2]])
    pos = np.array([1.0, 0.05])
    assert carrot(pos, path, np.array(4))[0] > 1.0  # the plain carrot: outwards on leg one
    assert carrot(pos, path, np.array(4), tolerance=0.3)[0] < 1.0  # back along leg two


def test_carrot_in_sight_waits_at_a_door_frame_but_never_at_the_robot():
    from socialzoo.core.walls import WallIndex
    from socialzoo.nav.distance_field import distance_field
    from socialzoo.nav.navigator import Sight

    # A wall along y = 0 with a 0.9 m door at x 2.05..2.95; the path comes along y = 0.6, turns
    # down through the door at x = 2.5 and back left below the wall (a hairpin round the jamb).
    walls = WallIndex(np.array([[-5.0, 0.0, 2.05, 0.0], [2.95, 0.0, 8.0, 0.0]]))
    sight = Sight(distance_field(walls, 0.025, 1.37, 3.0), clearance=0.37)
    path = np.array([[-3.0, 0.6], [2.5, 0.6], [2.5, -0.6], [-3.0, -0.6]])
    pos = np.array([2.0, 0.6])  # 0.5 m before the turn
    plain = track(pos, path, np.array(4), max_skip=0, tolerance=0.3)[0]
    kept = track(pos, path, np.array(4), max_skip=0, tolerance=0.3, sight=sight)[0]
    # The plain carrot lies beyond the door, behind its frame as seen from the robot ...
    assert plain[1] < 0.0
    # ... the carrot in sight stays on this side, on the path, where the robot can drive straight.
    assert kept[1] > 0.0 and np.isclose(kept[0], 2.5)
    assert np.hypot(*(kept - pos)) >= 0.5 - 1e-9
    # With the line clear (open space), the carrot is the plain one.
    far = np.array([-2.0, 0.6])
    np.testing.assert_allclose(
        track(far, path, np.array(4), sight=sight)[0], track(far, path, np.array(4))[0]
    )
    # Hugging the wall with the path on it, the carrot still lies min_ahead along the path.
    grazing = np.array([[-3.0, 0.05], [4.0, 0.05]])
    near_wall = track(np.array([0.0, 0.05]), grazing, np.array(2), sight=sight)[0]
    assert near_wall[0] >= 0.5 - 1e-9
    with pytest.raises(ValueError, match=r"Sight\.min_ahead must be >= 0, got -1"):
        Sight(sight.field, 0.37, min_ahead=-1)
