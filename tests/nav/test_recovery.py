"""Recovery of robots without progress: when a back-off starts and ends, which edge is avoided, how
a backing-off robot drives (socialzoo.nav.recovery)."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.nav.distance_field import build_distance_field
from socialzoo.nav.recovery import RecoveryConfig, RecoveryState, backoff_commands

DT = 0.5


def test_a_robot_without_progress_backs_off_then_asks_for_a_plan():
    cfg = RecoveryConfig(after=1.0, backoff_time=1.0)
    state = RecoveryState(cfg, batch_size=2, num_robots=1)
    moving = np.ones((2, 1), dtype=bool)
    started_at, ended_at = {}, {}
    for step in range(8):
        # Row 0 stands still on its route; row 1 gets 0.5 m closer every step.
        left = np.array([[10.0], [10.0 - 0.5 * step]])
        started, ended = state.step(left, moving, DT)
        for row in np.flatnonzero(started[:, 0]):
            started_at.setdefault(int(row), step)
        for row in np.flatnonzero(ended[:, 0]):
            ended_at.setdefault(int(row), step)
    # The first step sets the best route left; idle reaches 1 s two steps later.
    assert started_at == {0: 2} and ended_at == {0: 4}
    assert state.recoveries[:, 0].tolist() == [2, 0]  # idle again after the back-off: a second one
    state.reset(np.array([0]))
    assert state.recoveries[0, 0] == 0 and not state.backing_off[0, 0]


def test_a_robot_not_driving_its_plan_never_recovers():
    state = RecoveryState(RecoveryConfig(after=1.0), batch_size=1, num_robots=1)
    for _ in range(10):
        started, _ = state.step(np.array([[5.0]]), np.zeros((1, 1), dtype=bool), DT)
        assert not started.any()


def test_the_edge_avoided_is_the_nearest_within_a_metre():
    nodes = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    edges = np.array([[0, 1], [1, 2]])
    state = RecoveryState(RecoveryConfig(max_avoided=2), batch_size=1, num_robots=1)
    state.avoid_edge_at(nodes, edges, 0, 0, np.array([9.5, 3.0]))
    assert state.avoid[0, 0].tolist() == [1, -1]
    state.avoid_edge_at(nodes, edges, 0, 0, np.array([5.0, 4.0]))  # 4 m from both: none
    assert state.avoid[0, 0].tolist() == [1, -1]
    state.avoid_edge_at(nodes, edges, 0, 0, np.array([9.5, 0.5]))  # edge 1 is taken: the other
    assert state.avoid[0, 0].tolist() == [1, 0]


def test_people_close_by_make_a_crowd():
    state = RecoveryState(RecoveryConfig(crowd_radius=1.5), batch_size=2, num_robots=1)
    pos = np.zeros((2, 2))
    humans = np.array([[[1.0, 0.0]], [[3.0, 0.0]]])
    assert state.in_crowd(pos, humans, np.ones((2, 1), dtype=bool)).tolist() == [True, False]
    assert state.in_crowd(pos, humans, np.zeros((2, 1), dtype=bool)).tolist() == [False, False]
    assert state.in_crowd(pos, None, None).tolist() == [False, False]


@pytest.mark.parametrize(
    ("human_x", "speed"),
    [(None, -0.3), (-0.4, 0.0), (3.0, -0.3)],
    ids=["clear", "person-behind", "person-far"],
)
def test_backing_off_drives_backwards_only_where_the_way_is_clear(human_x, speed):
    field = build_distance_field(np.array([[-5.0, 2.0, 5.0, 2.0]]), resolution=0.05, max_range=3.0)
    cfg = RecoveryConfig(backoff_speed=0.3, backoff_time=1.0, human_gap=0.6)
    pose = np.array([[0.0, 0.0, 0.0]])  # facing +x: backwards is -x
    if human_x is None:
        humans, mask = np.zeros((1, 0, 2)), np.zeros((1, 0), dtype=bool)
    else:
        humans, mask = np.array([[[human_x, 0.0]]]), np.ones((1, 1), dtype=bool)
    command = backoff_commands(pose, field, 0.5, cfg, humans, mask)
    assert command.tolist() == [[speed, 0.0]]


def test_backing_off_stops_at_a_wall_behind():
    field = build_distance_field(np.array([[-0.5, -5.0, -0.5, 5.0]]), resolution=0.05, max_range=3.0)
    cfg = RecoveryConfig(backoff_speed=0.3, backoff_time=1.0)
    pose = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, np.pi]])  # the wall behind the first, ahead of the second
    command = backoff_commands(pose, field, 0.4, cfg, np.zeros((2, 0, 2)), np.zeros((2, 0), dtype=bool))
    assert command[:, 0].tolist() == [0.0, -0.3]
