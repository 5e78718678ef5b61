"""Observation layouts: visibility, robot frame, slot order, spaces (SPEC section 8)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from socialzoo.core.geometry import rotate, to_frame
from socialzoo.core.walls import WallIndex
from socialzoo.env.observation import (
    PAPER_GOAL,
    PAPER_HEADER_SIZE,
    PAPER_PREV_ACTION,
    PAPER_ROBOT_OMEGA,
    PAPER_ROBOT_V,
    PAPER_ROBOT_VEL,
    PAPER_SLOT_SIZE,
    PAPER_TARGET,
    SLOT_POS,
    SLOT_VEL,
    SLOT_VX,
    SLOT_VY,
    SLOT_X,
    SLOT_Y,
    SOCIALGYM1_SIZE,
    ObservationConfig,
    build_observation,
    describe_observation,
    observation_size,
    observation_space,
    paper_human_velocity,
    paper_num_slots,
    paper_slot_seen,
    paper_slots,
)
from socialzoo.nav.visibility import visible_humans


def scene(robot_pose, humans, human_vel=None, robot_vel=(0.0, 0.0), goal=(5.0, 0.0), carrot=(1.0, 0.0)):
    """A batch-of-one scene; every human present and visible unless told otherwise."""
    humans = np.asarray(humans, dtype=float).reshape(1, -1, 2)
    h = humans.shape[1]
    vel = np.zeros((1, h, 2)) if human_vel is None else np.asarray(human_vel, dtype=float).reshape(1, h, 2)
    return dict(
        robot_pose=np.asarray(robot_pose, dtype=float).reshape(1, 3),
        robot_vel=np.asarray(robot_vel, dtype=float).reshape(1, 2),
        goal=np.asarray(goal, dtype=float).reshape(1, 2),
        carrot=np.asarray(carrot, dtype=float).reshape(1, 2),
        prev_action=np.array([2]),
        human_pos=humans,
        human_vel=vel,
        visible=np.ones((1, h), dtype=bool),
    )


def slots(obs: np.ndarray, num_slots: int) -> np.ndarray:
    return obs[0, 7 : 7 + 4 * num_slots].reshape(num_slots, 4)


def test_visible_humans_wall_occludes_and_mask_hides():
    walls = WallIndex(np.array([[1.0, -1.0, 1.0, 1.0]]))
    robot = np.array([[0.0, 0.0, 0.0]])
    humans = np.array([[[2.0, 0.0], [0.0, 2.0], [-1.0, 0.0], [0.5, 0.0]]])
    mask = np.array([[True, True, True, False]])
    vis = visible_humans(robot, humans, mask, walls)
    assert vis.tolist() == [[False, True, True, False]]
    assert visible_humans(robot, humans, mask, None).tolist() == mask.tolist()


@pytest.mark.parametrize("extent", [6.0, 40.0])
def test_visible_humans_equals_whole_line_test(extent):
    # Short walls scattered over the area, sight lines from a few metres up to 110 m.
    rng = np.random.default_rng(int(extent))
    a = rng.uniform(-extent, extent, size=(300, 2))
    walls = WallIndex(np.concatenate((a, a + rng.uniform(-2, 2, size=(300, 2))), axis=1))
    b, h = 12, 20
    robot = np.concatenate((rng.uniform(-extent, extent, (b, 2)), rng.uniform(-3, 3, (b, 1))), axis=1)
    humans = rng.uniform(-extent, extent, (b, h, 2))
    humans[:, :4] = robot[:, None, :2] + rng.uniform(-3, 3, (b, 4, 2))
    mask = rng.random((b, h)) < 0.8
    vis = visible_humans(robot, humans, mask, walls)
    whole = ~walls.crosses(np.broadcast_to(robot[:, None, :2], humans.shape), humans)
    np.testing.assert_array_equal(vis, mask & whole)
    assert vis.any() and (mask & ~vis).any()
    for i in range(b):
        row = visible_humans(robot[i : i + 1], humans[i : i + 1], mask[i : i + 1], walls)
        np.testing.assert_array_equal(row[0], vis[i])


def test_occluded_human_slot_is_zero():
    walls = WallIndex(np.array([[1.0, -1.0, 1.0, 1.0]]))
    s = scene((0.0, 0.0, 0.0), [[2.0, 0.0], [0.0, 3.0]], human_vel=[[1.0, 1.0], [0.5, 0.0]])
    s["visible"] = visible_humans(s["robot_pose"], s["human_pos"], np.ones((1, 2), bool), walls)
    obs = build_observation(ObservationConfig(num_human_slots=3), **s)
    got = slots(obs, 3)
    np.testing.assert_allclose(got[0], [0.0, 3.0, 0.5, 0.0])
    assert np.all(got[1:] == 0.0)


def test_slots_sorted_by_distance_and_extra_humans_dropped():
    humans = [[3.0, 0.0], [1.0, 0.0], [0.0, -2.0], [5.0, 0.0], [0.0, 4.0]]
    s = scene((0.0, 0.0, 0.0), humans)
    got = slots(build_observation(ObservationConfig(num_human_slots=3), **s), 3)
    np.testing.assert_allclose(got[:, :2], [[1.0, 0.0], [0.0, -2.0], [3.0, 0.0]])
    # More slots than humans: the tail is zero.
    got = slots(build_observation(ObservationConfig(num_human_slots=7), **s), 7)
    np.testing.assert_allclose(got[:5, :2], [[1, 0], [0, -2], [3, 0], [0, 4], [5, 0]])
    assert np.all(got[5:] == 0.0)


def test_ties_keep_human_order():
    s = scene((0.0, 0.0, 0.0), [[0.0, 1.0], [1.0, 0.0], [0.0, -1.0]])
    got = slots(build_observation(ObservationConfig(num_human_slots=3), **s), 3)
    np.testing.assert_allclose(got[:, :2], [[0, 1], [1, 0], [0, -1]])


def test_human_behind_robot_is_observed():
    s = scene((0.0, 0.0, 0.0), [[-1.5, 0.0]])
    got = slots(build_observation(ObservationConfig(num_human_slots=2), **s), 2)
    np.testing.assert_allclose(got[0, :2], [-1.5, 0.0])


def test_invisible_and_absent_humans_take_no_slot():
    s = scene((0.0, 0.0, 0.0), [[0.5, 0.0], [2.0, 0.0]])
    s["visible"] = np.array([[False, True]])
    got = slots(build_observation(ObservationConfig(num_human_slots=2), **s), 2)
    np.testing.assert_allclose(got, [[2.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]])


def test_rotated_robot_frame_by_hand():
    # Robot at (1, 2) facing north (+y), moving at 1 m/s.
    s = scene(
        (1.0, 2.0, math.pi / 2),
        [[1.0, 3.0], [0.0, 2.0]],
        human_vel=[[1.0, 0.0], [0.0, 1.0]],
        robot_vel=(1.0, 0.3),
        goal=(1.0, 5.0),
        carrot=(0.0, 2.0),
    )
    obs = build_observation(ObservationConfig(num_human_slots=2), **s)[0]
    np.testing.assert_allclose(obs[0:2], [3.0, 0.0], atol=1e-6)  # goal straight ahead
    np.testing.assert_allclose(obs[2:4], [0.0, 1.0], atol=1e-6)  # west is on the left
    np.testing.assert_allclose(obs[4:7], [1.0, 0.3, 2.0], atol=1e-6)
    # Human 0: 1 m ahead, walking east (the robot's right) while the robot drives north:
    # relative velocity (1, -1) in the world, (-1, -1) in the robot frame.
    np.testing.assert_allclose(obs[7:11], [1.0, 0.0, -1.0, -1.0], atol=1e-6)
    # Human 1: 1 m to the left, walking with the robot: no relative velocity.
    np.testing.assert_allclose(obs[11:15], [0.0, 1.0, 0.0, 0.0], atol=1e-6)


def test_matches_to_frame_on_random_batch():
    rng = np.random.default_rng(3)
    b, h, k = 16, 12, 6
    pose = np.concatenate((rng.uniform(-10, 10, (b, 2)), rng.uniform(-4, 4, (b, 1))), axis=1)
    vel = rng.uniform(-2, 2, (b, 2))
    goal, carrot = rng.uniform(-10, 10, (b, 2)), rng.uniform(-10, 10, (b, 2))
    hp, hv = rng.uniform(-10, 10, (b, h, 2)), rng.uniform(-1.5, 1.5, (b, h, 2))
    visible = rng.random((b, h)) < 0.7
    action = rng.integers(0, 4, b)
    cfg = ObservationConfig(num_human_slots=k)
    obs = build_observation(cfg, pose, vel, goal, carrot, action, hp, hv, visible)
    assert obs.shape == (b, 7 + 4 * k) and obs.dtype == np.float32
    for i in range(b):
        np.testing.assert_allclose(obs[i, 0:2], to_frame(goal[i], pose[i]), atol=1e-4)
        np.testing.assert_allclose(obs[i, 2:4], to_frame(carrot[i], pose[i]), atol=1e-4)
        robot_world_vel = vel[i, 0] * np.array([math.cos(pose[i, 2]), math.sin(pose[i, 2])])
        seen = [
            j for j in np.argsort(np.linalg.norm(hp[i] - pose[i, :2], axis=1), kind="stable") if visible[i, j]
        ]
        for slot in range(k):
            got = obs[i, 7 + 4 * slot : 11 + 4 * slot]
            if slot >= len(seen):
                assert np.all(got == 0.0)
                continue
            j = seen[slot]
            np.testing.assert_allclose(got[:2], to_frame(hp[i, j], pose[i]), atol=1e-4)
            np.testing.assert_allclose(got[2:], rotate(hv[i, j] - robot_world_vel, -pose[i, 2]), atol=1e-4)
        row = build_observation(
            cfg,
            pose[i : i + 1],
            vel[i : i + 1],
            goal[i : i + 1],
            carrot[i : i + 1],
            action[i : i + 1],
            hp[i : i + 1],
            hv[i : i + 1],
            visible[i : i + 1],
        )
        np.testing.assert_array_equal(row[0], obs[i])


def test_socialgym1_layout():
    s = scene(
        (0.0, 0.0, 0.0),
        [[2.0, 1.0], [1.0, 0.0]],
        human_vel=[[0.5, -0.5], [1.0, 0.0]],
        robot_vel=(0.5, 0.2),
        carrot=(1.5, -0.5),
    )
    obs = build_observation(ObservationConfig(layout="socialgym1"), **s)
    assert obs.shape == (1, SOCIALGYM1_SIZE) == (1, 244) and obs.dtype == np.float32
    o = obs[0]
    assert np.all(o[2:120:3] == 0.0) and np.all(o[122:240:3] == 0.0)  # theta and omega
    np.testing.assert_allclose(o[0:6], [1.0, 0.0, 0.0, 2.0, 1.0, 0.0])
    np.testing.assert_allclose(o[120:126], [0.5, 0.0, 0.0, 0.0, -0.5, 0.0])
    assert np.all(o[6:120] == 0.0) and np.all(o[126:240] == 0.0)
    np.testing.assert_allclose(o[240:244], [1.5, -0.5, 0.0, 2.0])


def test_socialgym1_keeps_forty_nearest():
    rng = np.random.default_rng(1)
    hp = rng.uniform(-20, 20, (1, 50, 2))
    visible = np.ones((1, 50), bool)
    zero2 = np.zeros((1, 2))
    obs = build_observation(
        ObservationConfig(layout="socialgym1"),
        np.zeros((1, 3)),
        zero2,
        zero2,
        zero2,
        np.zeros(1, int),
        hp,
        np.zeros((1, 50, 2)),
        visible,
    )
    dist = np.sort(np.linalg.norm(hp[0], axis=1))[:40]
    np.testing.assert_allclose(np.hypot(obs[0, 0:120:3], obs[0, 1:120:3]), dist, rtol=1e-5)


def test_build_observation_dispatches():
    s = scene((0.0, 0.0, 0.0), [[1.0, 0.0]])
    for cfg in (
        ObservationConfig(),
        ObservationConfig(num_human_slots=4),
        ObservationConfig(layout="socialgym1"),
    ):
        obs = build_observation(cfg, **s)
        assert obs.shape == (1, observation_size(cfg)) == (1, cfg.size)
        assert len(describe_observation(cfg)) == cfg.size
    assert ObservationConfig(layout="socialgym1", num_human_slots=3).num_slots == 40


def test_describe_observation_names():
    names = describe_observation(ObservationConfig(num_human_slots=4))
    assert names[:7] == ["goal_x", "goal_y", "target_x", "target_y", "robot_v", "robot_omega", "prev_action"]
    assert names[7 + 4 * 3 + 3] == "human_3_vy"
    legacy = describe_observation(ObservationConfig(layout="socialgym1"))
    assert len(set(legacy)) == 244
    assert legacy[2] == "human_0_theta" and legacy[122] == "human_0_omega" and legacy[243] == "prev_action"


@pytest.mark.parametrize(
    "kwargs",
    [dict(layout="legacy"), dict(num_human_slots=-1), dict(num_human_slots=2.5), dict(num_human_slots=True)],
)
def test_config_rejects_bad_values(kwargs):
    field = next(iter(kwargs))
    with pytest.raises(ValueError, match=f"ObservationConfig.{field}"):
        ObservationConfig(**kwargs)


def test_space_is_fresh_float32_box():
    cfg = ObservationConfig()
    space = observation_space(cfg)
    assert space.shape == (cfg.size,) and space.dtype == np.float32
    assert space is not observation_space(cfg)
    assert space.low[6] == 0.0 and space.high[6] == 3.0


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    batch=st.integers(1, 4),
    num_humans=st.integers(0, 30),
    layout=st.sampled_from(["paper", "socialgym1"]),
    num_slots=st.integers(0, 30),
    scale=st.sampled_from([1.0, 10.0, 60.0]),
)
def test_space_contains_random_observations(seed, batch, num_humans, layout, num_slots, scale):
    rng = np.random.default_rng(seed)
    cfg = ObservationConfig(layout=layout, num_human_slots=num_slots)
    pose = np.concatenate((rng.uniform(-scale, scale, (batch, 2)), rng.uniform(-10, 10, (batch, 1))), axis=1)
    obs = build_observation(
        cfg,
        pose,
        rng.uniform(-3, 3, (batch, 2)),
        rng.uniform(-scale, scale, (batch, 2)),
        rng.uniform(-scale, scale, (batch, 2)),
        rng.integers(0, 4, batch),
        rng.uniform(-scale, scale, (batch, num_humans, 2)),
        rng.uniform(-2, 2, (batch, num_humans, 2)),
        rng.random((batch, num_humans)) < 0.7,
    )
    space = observation_space(cfg)
    assert obs.shape == (batch, cfg.size)
    assert np.all(np.isfinite(obs))
    for row in obs:
        assert space.contains(row)


def test_named_paper_pieces_match_the_entry_names():
    k = 3
    names = np.array(describe_observation(ObservationConfig(num_human_slots=k)))
    assert names[PAPER_GOAL].tolist() == ["goal_x", "goal_y"]
    assert names[PAPER_TARGET].tolist() == ["target_x", "target_y"]
    assert names[PAPER_ROBOT_VEL].tolist() == ["robot_v", "robot_omega"]
    assert names[PAPER_ROBOT_V] == "robot_v" and names[PAPER_ROBOT_OMEGA] == "robot_omega"
    assert names[PAPER_PREV_ACTION] == "prev_action"
    assert len(names) == PAPER_HEADER_SIZE + PAPER_SLOT_SIZE * k
    slot_names = paper_slots(names[None])[0]
    assert slot_names[2, SLOT_POS].tolist() == ["human_2_x", "human_2_y"]
    assert slot_names[2, SLOT_VEL].tolist() == ["human_2_vx", "human_2_vy"]
    assert [slot_names[1, i] for i in (SLOT_X, SLOT_Y, SLOT_VX, SLOT_VY)] == [
        "human_1_x",
        "human_1_y",
        "human_1_vx",
        "human_1_vy",
    ]


def test_paper_slots_read_an_observation():
    s = scene(
        (1.0, 2.0, 0.5), [(3.0, 2.0), (1.0, 5.0), (9.0, 9.0)], human_vel=[(1.0, 0.0), (0.0, 0.0), (0, 0)]
    )
    s["visible"][0, 2] = False
    s["robot_vel"][:] = (0.8, 0.1)
    obs = build_observation(ObservationConfig(num_human_slots=4), **s)
    view = paper_slots(obs)
    assert view.shape == (1, 4, 4) and np.shares_memory(view, obs)
    assert paper_num_slots(obs.shape[-1]) == 4
    assert paper_slot_seen(obs).tolist() == [[True, True, False, False]]
    np.testing.assert_allclose(
        view[0, 0, SLOT_POS], to_frame(np.array([3.0, 2.0]), s["robot_pose"][0]), atol=1e-6
    )
    # The humans' own velocities in robot axes: the first walks along +x, the second stands.
    own = paper_human_velocity(obs)
    np.testing.assert_allclose(own[0, 0], rotate(np.array([1.0, 0.0]), -0.5), atol=1e-6)
    np.testing.assert_allclose(own[0, 1], [0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(obs[0, PAPER_ROBOT_VEL], [0.8, 0.1], atol=1e-6)
    with pytest.raises(ValueError, match="7 \\+ 4K numbers, got 9"):
        paper_slots(np.zeros((2, 9), np.float32))
