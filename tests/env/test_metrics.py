"""Episode metrics of scripted episodes against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from socialzoo.env.metrics import SUMMARY_KEYS, EpisodeMetrics, MetricsConfig

DT = 0.5
# Row 0: drives towards the goal (4, 0), turns 0.5 rad and back, halts, reaches the goal.
POSES0 = [(1.0, 0.0, 0.0), (2.0, 0.0, 0.5), (3.0, 0.0, 0.0), (3.0, 0.0, 0.0), (3.6, 0.0, 0.0)]
SPEEDS0 = [1.0, 2.0, 2.0, 0.0, 1.2]
FORCE0 = [0.1, 0.5, 0.2, 0.0, 0.3]
BLAME0 = [0.0, 0.4, 0.1, 0.0, 0.2]
REWARD0 = [5.0, 5.0, 5.0, -0.1, 103.0]
CONTACTS0 = [0, 2, 0, 0, 0]
MIN_DIST0 = [2.0, 0.3, 0.6, 1.0, math.inf]
REACHED0 = [False, False, False, False, True]


def same(a: list[dict], b: list[dict]) -> bool:
    """Summaries equal, NaN equal to NaN."""
    return len(a) == len(b) and all(
        x.keys() == y.keys()
        and all(
            x[k] == y[k] or (isinstance(x[k], float) and math.isnan(x[k]) and math.isnan(y[k])) for k in x
        )
        for x, y in zip(a, b, strict=True)
    )


def run_episode(collisions=CONTACTS0, wall=(False,) * 5):
    """Row 0 scripted above; row 1 stands still facing away from its goal with nobody around."""
    m = EpisodeMetrics(2)
    m.reset(None, np.array([[0.0, 0.0, 0.0], [0.0, 0.0, math.pi / 2]]), np.array([[4.0, 0.0], [0.0, -2.0]]))
    for t in range(5):
        m.update(
            robot_pose=np.array([POSES0[t], (0.0, 0.0, math.pi / 2)]),
            robot_vel=np.array([[SPEEDS0[t], 0.0], [0.0, 0.0]]),
            reward=np.array([REWARD0[t], -0.5]),
            force=np.array([FORCE0[t], 0.0]),
            blame=np.array([BLAME0[t], 0.0]),
            human_collisions=np.array([collisions[t], 0]),
            wall_collision=np.array([wall[t], False]),
            min_human_distance=np.array([MIN_DIST0[t], math.inf]),
            reached=np.array([REACHED0[t], False]),
            done=np.array([t == 4, t == 4]),
            dt=DT,
        )
    return m


def test_scripted_episode_by_hand():
    s = run_episode().summaries([0])[0]
    assert list(s) == list(SUMMARY_KEYS)
    assert s["reached"] is True
    assert s["success"] is False  # two humans touched on step 2
    assert s["steps"] == 5 and s["duration"] == pytest.approx(2.5)
    assert s["time_to_goal"] == pytest.approx(2.5)
    assert s["distance_from_goal"] == pytest.approx(0.4)
    assert s["distance_travelled"] == pytest.approx(3.6)
    assert s["mean_force"] == pytest.approx(0.22) and s["max_force"] == pytest.approx(0.5)
    assert s["mean_blame"] == pytest.approx(0.14) and s["max_blame"] == pytest.approx(0.4)
    assert s["human_collisions"] == 1 and s["human_contacts"] == 2 and s["wall_collisions"] == 0
    assert s["total_reward"] == pytest.approx(117.9)
    assert s["average_step_reward"] == pytest.approx(117.9 / 5)
    assert s["min_human_distance"] == pytest.approx(0.3)
    # Centre distance below 0.45 + 0.2 m on steps 2 (0.3 m) and 3 (0.6 m).
    assert s["personal_space_intrusion_time"] == pytest.approx(2 * DT)
    # Turned 0.5 rad and back; facing the goal from the start needed no rotation.
    assert s["path_irregularity"] == pytest.approx(1.0)
    assert s["path_length_ratio"] == pytest.approx(4.0 / 3.6)
    # a = 2, 2, 0, -4, 2.4 m/s^2; |da|/dt = 4, 0, 4, 8, 12.8 m/s^3.
    assert s["jerk"] == pytest.approx((4 + 0 + 4 + 8 + 12.8) / 5)


def test_second_row_and_undefined_values():
    s = run_episode().summaries([1])[0]
    assert s["reached"] is False and s["success"] is False
    assert math.isnan(s["time_to_goal"])
    assert s["distance_from_goal"] == pytest.approx(2.0)
    assert s["distance_travelled"] == 0.0 and math.isnan(s["path_length_ratio"])
    assert math.isnan(s["min_human_distance"])
    assert s["personal_space_intrusion_time"] == 0.0
    # Needed a half turn and made none: no irregularity.
    assert s["path_irregularity"] == 0.0
    assert s["jerk"] == 0.0
    assert s["average_step_reward"] == pytest.approx(-0.5)


def test_success_needs_no_collision():
    assert run_episode(collisions=[0] * 5).summaries([0])[0]["success"] is True
    m = run_episode(collisions=[0] * 5, wall=(False, False, True, False, False))
    s = m.summaries([0])[0]
    assert s["wall_collisions"] == 1 and s["success"] is False


def test_summary_types_and_summaries():
    m = run_episode()
    both = m.summaries()
    assert same(both, [m.summaries([0])[0], m.summaries([1])[0]])
    assert same(m.summaries([1]), [m.summaries([1])[0]])
    for key, value in both[0].items():
        if key in ("success", "reached", "stuck"):
            assert type(value) is bool
        elif key in ("steps", "human_collisions", "human_contacts", "wall_collisions"):
            assert type(value) is int
        else:
            assert type(value) is float
    arrays = m.arrays()
    assert set(arrays) == set(SUMMARY_KEYS) and all(len(v) == 2 for v in arrays.values())


def test_finished_rows_stop_until_reset_and_reset_one_row():
    m = run_episode()
    before = m.summaries()
    step = dict(
        robot_pose=np.array([[9.0, 9.0, 1.0], [5.0, 5.0, 0.0]]),
        robot_vel=np.array([[1.0, 0.0], [1.0, 0.0]]),
        reward=np.ones(2),
        force=np.ones(2),
        blame=np.ones(2),
        human_collisions=np.array([3, 3]),
        wall_collision=np.array([True, True]),
        min_human_distance=np.zeros(2),
        reached=np.ones(2, bool),
        done=np.zeros(2, bool),
        dt=DT,
    )
    m.update(**step)
    assert same(m.summaries(), before)
    m.reset(np.array([1]), np.array([[5.0, 4.0, 0.0]]), np.array([[8.0, 5.0]]))
    m.update(**step)
    assert same([m.summaries([0])[0]], before[:1])
    s = m.summaries([1])[0]
    assert s["steps"] == 1 and s["reached"] and s["human_collisions"] == 1 and s["human_contacts"] == 3
    assert s["distance_travelled"] == pytest.approx(1.0) and s["distance_from_goal"] == pytest.approx(3.0)
    assert s["time_to_goal"] == pytest.approx(DT)


def test_bool_mask_reset():
    m = EpisodeMetrics(3)
    m.reset(np.array([True, True, True]), np.zeros((3, 3)), np.ones((3, 2)))
    m.update(
        robot_pose=np.array([[1.0, 0.0, 0.0]] * 3),
        robot_vel=np.zeros((3, 2)),
        reward=np.ones(3),
        force=np.zeros(3),
        blame=np.zeros(3),
        human_collisions=np.zeros(3, int),
        wall_collision=np.zeros(3, bool),
        min_human_distance=np.full(3, 5.0),
        reached=np.zeros(3, bool),
        done=np.zeros(3, bool),
        dt=0.025,
    )
    assert [s["steps"] for s in m.summaries()] == [1, 1, 1]


def test_bad_arguments():
    with pytest.raises(ValueError, match="batch_size"):
        EpisodeMetrics(0)
    with pytest.raises(ValueError, match=r"MetricsConfig\.personal_space"):
        MetricsConfig(personal_space=-1.0)
    assert MetricsConfig().intrusion_distance == pytest.approx(0.65)


def _stuck_run(route_left, halted, dt=1.0, config=None):
    """One row stepped with the given route lengths left (m) and halt flags; its summary."""
    m = EpisodeMetrics(1, config)
    m.reset(None, np.zeros((1, 3)), np.array([[20.0, 0.0]]))
    for t, (left, halt) in enumerate(zip(route_left, halted, strict=True)):
        m.update(
            robot_pose=np.zeros((1, 3)), robot_vel=np.zeros((1, 2)), reward=np.zeros(1), force=np.zeros(1),
            blame=np.zeros(1), human_collisions=np.zeros(1, dtype=int), wall_collision=np.zeros(1, dtype=bool),
            min_human_distance=np.full(1, math.inf), reached=np.zeros(1, dtype=bool),
            done=np.array([t == len(route_left) - 1]), dt=dt, route_left=np.array([left]), halted=np.array([halt]),
        )  # fmt: skip
    return m.summaries([0])[0]


def test_stuck_is_no_progress_for_ten_seconds_while_not_halting():
    # Progress for 5 s, then 10 s without (the route left stays at 15 m): stuck.
    left = [19.0, 18.0, 17.0, 16.0, 15.0] + [15.0] * 10
    s = _stuck_run(left, [False] * len(left))
    assert s["stuck"] is True and s["max_time_without_progress"] == 10.0
    # 9 s without progress is not stuck; halted steps pause the clock (the policy waits).
    assert _stuck_run(left[:-1], [False] * (len(left) - 1))["stuck"] is False
    waiting = _stuck_run(left, [False] * 5 + [True] * 5 + [False] * 5)
    assert waiting["stuck"] is False and waiting["max_time_without_progress"] == 5.0
    # Less than stuck_progress (0.25 m) below the least so far is no progress (rocking in place);
    # a detour that comes back below the least in time is.
    rocking = [15.0] + [15.1, 14.9] * 6
    assert _stuck_run(rocking, [False] * len(rocking))["stuck"] is True
    detour = [15.0] + [16.0 + k for k in range(5)] + [14.0]
    assert _stuck_run(detour, [False] * len(detour))["stuck"] is False
    # Documented settings.
    quick = MetricsConfig(stuck_time=3.0)
    assert _stuck_run([15.0] * 5, [False] * 5, config=quick)["stuck"] is True


def test_failure_cause_precedence():
    from socialzoo.env.metrics import FAILURE_CAUSES, failure_cause

    base = {"success": False, "reached": False, "wall_collisions": 0, "human_collisions": 0, "stuck": False}
    assert failure_cause({**base, "success": True, "reached": True}) == "success"
    assert (
        failure_cause({**base, "wall_collisions": 1, "human_collisions": 4, "stuck": True})
        == "wall_collision"
    )
    assert failure_cause({**base, "human_collisions": 2, "stuck": True, "reached": True}) == "human_collision"
    assert failure_cause({**base, "stuck": True}) == "stuck"
    assert failure_cause(base) == "timeout"
    # Rows stored before `stuck` existed (None or NaN from the store) count as not stuck.
    assert failure_cause({**base, "stuck": None}) == failure_cause({**base, "stuck": math.nan}) == "timeout"
    assert FAILURE_CAUSES == ("success", "wall_collision", "human_collision", "stuck", "timeout")
