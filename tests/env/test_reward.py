"""Reward terms against the SPEC section 9 formulas computed by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from socialzoo.env.reward import (
    RewardConfig,
    compute_reward,
    erf,
    erf_approx,
    force_and_blame,
    progress,
    social_force_term,
)

ORIGIN = np.zeros((1, 2))


def humans(*points):
    return np.asarray(points, dtype=float).reshape(1, -1, 2)


def test_force_nearest_visible_human():
    hp = humans((1.0, 0.0), (0.5, 0.5), (0.1, 0.0))
    visible = np.array([[True, True, False]])  # the nearest one is occluded
    got = social_force_term(ORIGIN, hp, visible, np.array([-1]))
    assert got[0] == pytest.approx(math.exp(-(math.sqrt(0.5) ** 4)), rel=1e-12)


def test_force_skips_followed_human():
    hp = humans((1.0, 0.0), (0.5, 0.5))
    got = social_force_term(ORIGIN, hp, np.ones((1, 2), bool), np.array([1]))
    assert got[0] == pytest.approx(math.exp(-1.0), rel=1e-12)


def test_force_zero_without_humans():
    assert social_force_term(ORIGIN, humans((1.0, 0.0)), np.zeros((1, 1), bool), np.array([-1]))[0] == 0.0
    assert social_force_term(ORIGIN, humans((1.0, 0.0)), np.ones((1, 1), bool), np.array([0]))[0] == 0.0
    assert social_force_term(ORIGIN, np.zeros((1, 0, 2)), np.zeros((1, 0), bool), np.array([-1]))[0] == 0.0


def test_force_batched():
    pos = np.array([[0.0, 0.0], [10.0, 0.0]])
    hp = np.array([[[0.0, 2.0], [3.0, 0.0]], [[10.0, 0.7], [0.0, 0.0]]])
    got = social_force_term(pos, hp, np.ones((2, 2), bool), np.array([-1, -1]))
    np.testing.assert_allclose(got, [math.exp(-16.0), math.exp(-(0.7**4))], rtol=1e-12)


def blame(hp, visible=None, skip=-1, vel=(1.0, 0.0), halted=False, horizon=0.5):
    hp = humans(*hp)
    visible = np.ones(hp.shape[:2], bool) if visible is None else np.asarray([visible])
    return force_and_blame(
        ORIGIN, np.array([vel], float), np.array([halted]), hp, visible, np.array([skip]), horizon
    )[1][0]


def test_blame_takes_the_first_of_equally_near_people():
    # Both 1 m from the robot; the first lies 0.5 m beyond the segment's end, the second 1 m behind it.
    assert blame([(1.0, 0.0), (-1.0, 0.0)]) == pytest.approx(1.0 - math.erf(0.5), abs=1e-12)
    assert blame([(-1.0, 0.0), (1.0, 0.0)]) == pytest.approx(1.0 - math.erf(1.0), abs=1e-12)


def test_force_and_blame_force_is_the_social_force_term():
    rng = np.random.default_rng(0)
    pos, people = rng.normal(size=(8, 2)), rng.normal(size=(8, 5, 2))
    visible, skip = rng.random((8, 5)) < 0.7, rng.integers(-1, 5, 8)
    force, _ = force_and_blame(pos, rng.normal(size=(8, 2)), np.zeros(8, bool), people, visible, skip, 0.5)
    assert np.array_equal(force, social_force_term(pos, people, visible, skip))
    assert (force > 0).any()


def test_blame_by_hand():
    # S runs from (0, 0) to (0.5, 0).
    assert blame([(0.25, 0.3)]) == pytest.approx(1.0 - math.erf(0.3), abs=1e-12)
    assert blame([(2.0, 1.0)]) == pytest.approx(1.0 - math.erf(math.hypot(1.5, 1.0)), abs=1e-12)
    assert blame([(-0.4, 0.3)]) == pytest.approx(1.0 - math.erf(0.5), abs=1e-12)
    # A longer horizon stretches the segment.
    assert blame([(2.0, 1.0)], horizon=2.0) == pytest.approx(1.0 - math.erf(1.0), abs=1e-12)


def test_blame_uses_human_nearest_to_robot():
    # A is nearer the robot (0.8 m vs 0.877 m), B nearer the segment (0.72 m vs 0.8 m).
    assert blame([(-0.8, 0.0), (0.5, 0.72)]) == pytest.approx(1.0 - math.erf(0.8), abs=1e-12)


def test_blame_skip_and_visibility():
    pts = [(-0.8, 0.0), (0.5, 0.72)]
    assert blame(pts, skip=0) == pytest.approx(1.0 - math.erf(0.72), abs=1e-12)
    assert blame(pts, visible=[False, True]) == pytest.approx(1.0 - math.erf(0.72), abs=1e-12)
    assert blame(pts, visible=[False, True], skip=1) == 0.0


def test_blame_zero_when_halted_or_still_or_alone():
    assert blame([(0.25, 0.3)], halted=True) == 0.0
    assert blame([(0.25, 0.3)], vel=(0.0, 0.0), halted=True) == 0.0
    assert blame([], vel=(1.0, 0.0)) == 0.0


def test_progress_is_euclidean():
    prev = np.array([[0.0, 0.0], [0.0, 0.0]])
    pos = np.array([[1.0, 1.0], [0.0, 1.0]])
    goal = np.array([[3.0, 4.0], [5.0, 0.0]])
    got = progress(prev, pos, goal)
    np.testing.assert_allclose(got, [5.0 - math.sqrt(13.0), 5.0 - math.sqrt(26.0)], rtol=1e-12)
    assert got[1] < 0.0  # moving sideways loses Euclidean distance; |dx| alone would say 0


def test_reward_by_hand():
    cfg = RewardConfig()
    d_g = np.array([0.1, -0.1, 0.05, 0.0])
    b = np.array([0.5, 0.0, 0.2, 1.0])
    f = np.array([0.3, 0.9, 0.0, 1.0])
    success = np.array([False, False, True, False])
    coll = np.array([0, 2, 0, 1])
    reward, terms = compute_reward(d_g, b, f, success, coll, cfg)
    expect = [
        5.0 * 0.1 - 0.1 * 0.5 - 0.01 * 0.3,
        10.0 * -0.1 - 0.01 * 0.9,
        5.0 * 0.05 - 0.1 * 0.2 + 100.0,
        -0.1 - 0.01,
    ]
    np.testing.assert_allclose(reward, expect, rtol=1e-12)
    assert set(terms) == {"progress", "blame", "force", "success", "collision"}
    total = terms["progress"] + terms["blame"] + terms["force"] + terms["success"] + terms["collision"]
    np.testing.assert_array_equal(total, reward)
    np.testing.assert_allclose(terms["progress"], [0.5, -1.0, 0.25, 0.0])
    assert np.all(terms["collision"] == 0.0)  # SPEC section 11: weight 0 by default


def test_reward_collision_weight_and_custom_weights():
    cfg = RewardConfig(w_collision=-2.0, w_progress=1.0, w_progress_negative=3.0, success_bonus=7.0)
    reward, _ = compute_reward(
        np.array([0.2, -0.2]), np.zeros(2), np.zeros(2), np.array([True, False]), np.array([1, 3]), cfg
    )
    np.testing.assert_allclose(reward, [0.2 + 7.0 - 2.0, -0.6 - 6.0])


def test_erf_matches_math_erf():
    x = np.linspace(-4.0, 6.0, 2001)
    expect = np.array([math.erf(v) for v in x])
    assert np.max(np.abs(erf_approx(x) - expect)) < 1.5e-7
    assert np.max(np.abs(erf(x) - expect)) < 1.5e-7


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(w_blame=math.nan),
        dict(w_force=math.inf),
        dict(success_bonus="100"),
        dict(blame_horizon=0.0),
        dict(blame_horizon=-1.0),
        dict(w_progress=True),
    ],
)
def test_config_rejects_bad_values(kwargs):
    field = next(iter(kwargs))
    with pytest.raises(ValueError, match=f"RewardConfig.{field}"):
        RewardConfig(**kwargs)
