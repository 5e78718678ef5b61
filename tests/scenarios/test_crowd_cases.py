"""CrowdNav's cases: circle and square crossing drawn by CrowdNav's rules from its case seeds."""

import math

import numpy as np
import pytest

from socialzoo.scenarios.crowd_cases import CrowdCaseConfig, crowd_family


def crowd_case(config, seed):
    return crowd_family(config).make(seed)


def case_seed(split, index):
    return crowd_family(CrowdCaseConfig()).case_seed(split, index)


def _agents(case):
    starts = np.vstack([case.robot_starts[:, :2], case.human_spawn])
    goals = np.vstack([case.robot_goals[:, :2], np.array([r[0] for r in case.human_routes])])
    return starts, goals


@pytest.mark.parametrize("layout", ["circle_crossing", "square_crossing"])
def test_cases_keep_crowdnavs_spacing_and_are_fixed_by_their_seed(layout):
    config = CrowdCaseConfig(layout=layout, num_humans=5)
    for k in range(20):
        case = crowd_case(config, case_seed("test", k))
        assert case == crowd_case(config, case_seed("test", k))
        starts, goals = _agents(case)
        gap = 0.3 + 0.3 + 0.2
        for i in range(1, 6):
            # Each person keeps clear of every earlier agent's start (and, for its goal, goal).
            assert all(np.hypot(*(starts[i] - starts[j])) >= gap for j in range(i))
            assert all(np.hypot(*(goals[i] - goals[j])) >= gap for j in range(i))
        assert case.robot_starts[0].tolist() == [0.0, -4.0, math.pi / 2]
        assert all(len(r) == 1 for r in case.human_routes)  # walk to the goal and stay


def test_circle_crossing_people_start_near_the_circle_and_walk_to_the_antipode():
    case = crowd_case(CrowdCaseConfig(num_humans=20), case_seed("val", 3))
    starts, goals = _agents(case)
    radius = np.hypot(starts[1:, 0], starts[1:, 1])
    assert np.all(np.abs(radius - 4.0) <= math.sqrt(2) * 0.5 + 1e-9)  # noise +-v_pref/2 per axis
    np.testing.assert_array_equal(goals[1:], -starts[1:])


def test_square_crossing_people_cross_to_the_other_half():
    case = crowd_case(CrowdCaseConfig(layout="square_crossing"), case_seed("train", 7))
    starts, goals = _agents(case)
    assert np.all(np.sign(starts[1:, 0]) == -np.sign(goals[1:, 0]))
    assert np.all(np.abs(starts[1:]) <= 5.0) and np.all(np.abs(goals[1:]) <= 5.0)


def test_splits_use_crowdnavs_seeds_and_sizes():
    assert case_seed("val", 0) == 0 and case_seed("test", 0) == 1000 and case_seed("train", 0) == 2000
    with pytest.raises(ValueError, match="holds 500"):
        case_seed("test", 500)
    with pytest.raises(ValueError, match="split"):
        case_seed("dev", 0)
    with pytest.raises(ValueError, match="layout"):
        CrowdCaseConfig(layout="corridor")
    with pytest.raises(ValueError, match="human_radius"):
        CrowdCaseConfig(human_radius=-0.3)


def test_a_case_with_no_room_left_is_refused_by_name_not_drawn_forever():
    from socialzoo.scenarios.crowd_cases import crowd_case_arrays

    # 20 people on a 1 m circle: after a few people every start is taken (CrowdNav's loop never ends).
    with pytest.raises(
        ValueError, match=r"crowd case 0: person \d+ of 20 found no place .* too full for 20 people"
    ):
        crowd_case_arrays(CrowdCaseConfig(num_humans=20, circle_radius=1.0), 0)
    # CrowdNav's own 4 m circle jams for a few seeds of 20 people (213 of the first 3000).
    with pytest.raises(ValueError, match="crowd case 213"):
        crowd_case_arrays(CrowdCaseConfig(num_humans=20), 213)
    assert crowd_case_arrays(CrowdCaseConfig(num_humans=20), 212).human_starts.shape == (20, 2)
