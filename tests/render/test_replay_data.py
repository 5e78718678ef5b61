"""The viewer's data: traces validate their arrays, and encode into compact JSON (kept frames,
rounded numbers, fewer laser rays)."""

import json
from importlib import resources

import numpy as np
import pytest

from socialzoo.core.metrics import metric
from socialzoo.render.replay_data import (
    REPLAY_FORMAT,
    VIEWER_METRICS,
    Encoding,
    encode_episode,
    encode_replay,
    frame_steps,
)


def test_frame_steps():
    assert frame_steps(9, 2).tolist() == [0, 2, 4, 6, 8, 9]
    assert frame_steps(8, 2).tolist() == [0, 2, 4, 6, 8]
    assert frame_steps(0, 3).tolist() == [0]
    assert frame_steps(5, 1).tolist() == [0, 1, 2, 3, 4, 5]


def test_trace_checks_its_arrays(make_trace):
    trace = make_trace(steps=9, humans=2)
    assert (trace.num_steps, trace.num_humans) == (9, 2)
    assert not trace.robot_pose.flags.writeable
    with pytest.raises(ValueError, match=r"EpisodeTrace.robot_vel must have shape \(10, 2\), got \(9, 2\)"):
        make_trace(robot_vel=np.zeros((9, 2)))
    with pytest.raises(ValueError, match=r"EpisodeTrace.reward must have shape \(9,\)"):
        make_trace(reward=np.zeros(10))
    with pytest.raises(ValueError, match=r"action values must be -1 or action indices, got -2"):
        make_trace(action=np.full(9, -2))
    with pytest.raises(ValueError, match=r"target_human values must be -1 or human indices 0..1"):
        make_trace(target_human=np.full(9, 2))
    with pytest.raises(ValueError, match=r"plan_index must index the 2 plans"):
        make_trace(plan_index=np.full(10, 2))
    with pytest.raises(ValueError, match=r"laser_steps must increase from 0"):
        make_trace(laser_steps=np.array([1, 2]), laser_ranges=np.zeros((2, 8)))
    with pytest.raises(ValueError, match=r"laser_ranges must have shape \(10, 8\)"):
        make_trace(laser_ranges=np.zeros((10, 7)))
    with pytest.raises(ValueError, match=r"EpisodeTrace.dt must be > 0, got 0.0"):
        make_trace(dt=0.0)


def test_scene_checks(make_scene):
    with pytest.raises(ValueError, match=r"ReplayScene.bounds must be finite"):
        make_scene(bounds=(0, 0, 0, 1))
    with pytest.raises(ValueError, match=r"ReplayScene.robot_width must be > 0, got -1"):
        make_scene(robot_width=-1)
    assert make_scene(walls=np.zeros((0, 4))).walls.shape == (0, 4)


def test_encoding_checks():
    with pytest.raises(ValueError, match=r"Encoding.stride must be an int >= 1, got 0"):
        Encoding(stride=0)
    with pytest.raises(ValueError, match=r"Encoding.laser_rays must be an int >= 0"):
        Encoding(laser_rays=-2)


def test_the_default_stride_keeps_a_state_every_50_ms_of_the_episodes_own_steps(make_trace):
    """2 of the action-selection task's 25 ms steps; every one of the CrowdNav task's 0.25 s steps
    (before, 2 steps whatever their length: half a second between the CrowdNav task's frames)."""
    assert encode_episode(make_trace(steps=9))["frameSteps"] == [0, 2, 4, 6, 8, 9]
    assert encode_episode(make_trace(steps=5, dt=0.25))["frameSteps"] == [0, 1, 2, 3, 4, 5]
    assert encode_episode(make_trace(steps=9, dt=0.01), Encoding())["frameSteps"] == [0, 5, 9]
    assert encode_episode(make_trace(steps=5, dt=0.25), Encoding(stride=2))["frameSteps"] == [0, 2, 4, 5]


def test_encode_episode_keeps_frames_and_every_step(make_trace):
    trace = make_trace(steps=9, humans=2, rays=8)
    data = encode_episode(trace, Encoding(stride=4, laser_rays=3))
    kept = [0, 4, 8, 9]
    assert data["frameSteps"] == kept and data["steps"] == 9
    assert len(data["robot"]) == 3 * len(kept) and len(data["robotVel"]) == 2 * len(kept)
    assert len(data["humanPos"]) == len(data["humanVel"]) == 2 * 2 * len(kept)
    assert data["robot"][3:6] == [1.1, 1, 0]  # state 4: x = 1 + 4 * 0.025, rounded to mm
    assert data["planIndex"] == [0, 0, 1, 1]
    assert [len(p) for p in data["plans"]] == [4, 6]
    # Per-step series stay complete.
    for key in ("action", "target", "reward", "force", "blame", "collisions", "wall"):
        assert len(data[key]) == 9, key
    assert data["action"] == trace.action.tolist()
    # Three evenly spaced rays of eight: first, middle, last.
    assert data["laser"]["angles"] == [-2, round(-2 + 4 * 4 / 7, 4), 2]
    assert len(data["laser"]["ranges"]) == 3 * len(kept)
    assert data["metrics"]["time_to_goal"] is None  # NaN is not JSON
    json.dumps(data, allow_nan=False)


def test_people_who_enter_or_leave_are_marked_absent(make_trace):
    # A recorded scene's people come and go: the file says who is there in each kept state, and
    # an absent person's slot values (NaN in the world) are written as 0.
    present = np.ones((10, 2), bool)
    present[:3, 1] = False  # human 1 enters at state 3
    present[7:, 0] = False  # human 0 leaves at state 7
    pos = make_trace(steps=9).human_pos.copy()
    pos[~present] = np.nan
    data = encode_episode(make_trace(steps=9, human_present=present, human_pos=pos), Encoding(stride=4))
    assert data["humanPresent"] == [1, 0, 1, 1, 0, 1, 0, 1]  # states 0, 4, 8, 9
    assert data["humanPos"][2:4] == [0, 0] and data["humanPos"][12:14] == [0, 0]
    json.dumps(data, allow_nan=False)
    assert "humanPresent" not in encode_episode(make_trace(steps=9))  # everyone, always: no key
    with pytest.raises(ValueError, match=r"human_present must have shape \(10, 2\), got \(10, 3\)"):
        make_trace(steps=9, human_present=np.ones((10, 3), bool))


def test_other_robots_are_written_where_there_are_some(make_trace, make_scene):
    others = np.zeros((10, 2, 3))
    others[:, 1, 0] = np.arange(10)
    trace = make_trace(steps=9, other_robots=others)
    data = encode_episode(trace, Encoding(stride=4))
    assert data["others"] == [0, 0, 0, 0, 0, 0, 0, 0, 0, 4, 0, 0, 0, 0, 0, 8, 0, 0, 0, 0, 0, 9, 0, 0]
    assert "others" not in encode_episode(make_trace(steps=9))
    assert make_trace(steps=9).other_robots.shape == (10, 0, 3)
    assert "other robots" in encode_replay(make_scene(), [make_trace(steps=9), trace])["legend"]
    assert "other robots" not in encode_replay(make_scene(), [make_trace(steps=9)])["legend"]
    with pytest.raises(ValueError, match=r"other_robots must have shape \(10, \*, 3\), got \(10, 2\)"):
        make_trace(steps=9, other_robots=np.zeros((10, 2)))


def test_laser_of_unscanned_frames_is_the_latest_scan(make_trace):
    ranges = np.arange(3)[:, None] + np.zeros((3, 8))
    trace = make_trace(steps=9, laser_steps=np.array([0, 5, 9]), laser_ranges=ranges)
    data = encode_episode(trace, Encoding(stride=2, laser_rays=8))
    per_frame = np.array(data["laser"]["ranges"]).reshape(-1, 8)[:, 0]
    # Kept states 0 2 4 6 8 9 -> scans of states 0 0 0 5 5 9.
    assert per_frame.tolist() == [0, 0, 0, 1, 1, 2]


def test_rounding(make_trace):
    trace = make_trace(steps=3, reward=np.array([0.123456789, -1e-9, 100.0]))
    data = encode_episode(trace, Encoding(stride=1, value_decimals=3, position_decimals=1))
    assert data["reward"] == [0.123, 0, 100]
    assert data["carrot"][:2] == [1.5, 1]
    text = json.dumps(encode_episode(make_trace(steps=400), Encoding(stride=1)))
    assert "0000000" not in text and "9999999" not in text  # no float noise left


def test_encode_replay(make_trace, make_scene):
    data = encode_replay(make_scene(), [make_trace(), make_trace(label="goalone")], view="map")
    assert data["format"] == REPLAY_FORMAT and data["view"] == "map"
    assert [e["label"] for e in data["episodes"]] == ["ref", "goalone"]
    assert data["scene"]["walls"][:4] == [0, 0, 6, 0] and data["scene"]["robotWidth"] == 0.43
    assert data["actions"]["names"] == ["GoAlone", "Halt", "Follow", "Pass"]
    # The scene names the task's actions; an action it does not name is refused, naming them.
    with pytest.raises(ValueError, match=r"took action 4, but the scene names 4 actions"):
        encode_replay(make_scene(), [make_trace(action=np.arange(len(make_trace().action)) % 5)])
    named = encode_replay(
        make_scene(action_names=("forward", "stop")),
        [make_trace(action=np.full(len(make_trace().action), -1))],
    )
    assert named["actions"]["names"] == ["forward", "stop"] and len(named["actions"]["colors"]) == 2
    with pytest.raises(ValueError, match="at least one episode"):
        encode_replay(make_scene(), [])
    with pytest.raises(ValueError, match="view must be 'follow' or 'map', got 'top'"):
        encode_replay(make_scene(), [make_trace()], view="top")


def test_the_viewer_reads_metric_labels_from_the_registry(make_trace, make_scene):
    data = encode_replay(make_scene(), [make_trace()])
    rows = data["metricRows"]
    assert [r[0] for r in rows] == list(VIEWER_METRICS)
    for name, heading, digits, kind in rows:
        m = metric(name)
        assert (heading, digits, kind) == (m.heading, m.digits, m.kind)
    assert ["time_to_goal", "time to goal, s", 2, "float"] in rows
    # The page's script has no list of its own: it shows the rows the data carries.
    script = resources.files("socialzoo.render").joinpath("viewer", "replay.js").read_text(encoding="utf-8")
    assert "DATA.metricRows" in script and '"time to goal' not in script
