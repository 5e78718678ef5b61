"""CrowdNavConfig.observed_people: the CrowdNav observation of the K people nearest the robot, so
that a policy trained with K people plays a scene of another number of person slots."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from socialzoo.agents import PolicyTaskError, make_policy
from socialzoo.env.crowd_observation import nearest_people
from socialzoo.env.tasks.crowdnav import CrowdNavTask


def test_nearest_people_lists_present_people_nearest_first_then_empty_slots() -> None:
    robot = np.array([[0.0, 0.0]])
    people = np.array([[[3.0, 0.0], [1.0, 0.0], [0.5, 0.0], [2.0, 0.0]]])
    mask = np.array([[True, True, False, True]])
    slots, present = nearest_people(robot, people, mask, 3)
    assert slots.tolist() == [[1, 3, 0]] and present.tolist() == [[True, True, True]]
    slots, present = nearest_people(robot, people, mask, 6)
    assert slots.tolist() == [[1, 3, 0, 0, 0, 0]]
    assert present.tolist() == [[True, True, True, False, False, False]]


def _rows(task: CrowdNavTask) -> tuple[np.ndarray, np.ndarray]:
    obs = task.observation
    assert obs is not None
    return obs.humans.copy(), obs.mask.copy()


@pytest.mark.parametrize("signals", [False, True])
def test_the_nearest_people_are_the_same_people_sorted_by_distance(signals: bool) -> None:
    kwargs = {"variant": "20", "signals": signals}
    full, nearest = (
        CrowdNavTask(batch_size=3, **kwargs),
        CrowdNavTask(batch_size=3, observed_people=20, **kwargs),
    )
    for task in (full, nearest):
        task.seed(5)
        task.reset(np.arange(3), {})
    rng = np.random.default_rng(0)
    for _ in range(6):
        action = rng.uniform(-1, 1, (3, 1, 2)).astype(np.float32)
        for task in (full, nearest):
            task.step(action)
        (a, a_mask), (b, b_mask) = _rows(full), _rows(nearest)
        for row in range(3):
            assert sorted(map(tuple, a[row][a_mask[row]])) == sorted(map(tuple, b[row][b_mask[row]]))
            distance = b[row][b_mask[row], 5]
            assert np.all(np.diff(distance) >= 0)
            # the present people first, the empty slots after them
            assert not np.any(np.diff(b_mask[row].astype(int)) > 0)


def test_fewer_or_more_observed_people_than_slots() -> None:
    task = CrowdNavTask(batch_size=2, observed_people=3)  # CrowdNav's 5 people
    assert task.observation_space.shape == (6 + 8 * 3,)
    task.seed(0)
    task.reset(np.arange(2), {})
    humans, mask = _rows(task)
    assert mask.all() and humans.shape == (2, 3, 7)
    state = task.core.state
    ranges = state.human_pos - state.robot_pose[:, 0, None, :2]
    nearest3 = np.sort(np.hypot(ranges[..., 0], ranges[..., 1]), axis=1)[:, :3]
    assert np.allclose(humans[..., 5], nearest3, atol=1e-5)
    wide = CrowdNavTask(batch_size=2, observed_people=8)
    wide.seed(0)
    wide.reset(np.arange(2), {})
    humans, mask = _rows(wide)
    assert mask.sum(1).tolist() == [5, 5] and not humans[:, 5:].any()


def test_observed_people_must_be_a_positive_count() -> None:
    with pytest.raises(ValueError, match="observed_people"):
        CrowdNavTask(observed_people=0)


def test_the_shipped_attention_policy_acts_alike_on_its_people_in_any_order() -> None:
    policy = make_policy("crowdnav", task="crowdnav")
    for observed in (None, 5):
        env = gym.make("socialzoo/CrowdNav-v1", action="discrete", observed_people=observed)
        obs, _ = env.reset(seed=3)
        actions = []
        for _ in range(40):
            action = int(policy.act(obs[None])[0])
            actions.append(action)
            obs, _, term, trunc, _ = env.step(action)
            if term or trunc:
                obs, _ = env.reset()
        if observed is None:
            expected = actions
    assert actions == expected


def test_a_crowdnav_learner_plays_a_scene_of_more_slots_through_its_nearest_people() -> None:
    from socialzoo.data.tracks import Recording, Track
    from socialzoo.scenarios.catalogue import FAMILIES, register_family
    from socialzoo.scenarios.recorded import RecordedScene

    # 60 people crossing a 16 m square at 1 m/s, entering over 120 s: about 8 at once.
    rng = np.random.default_rng(0)
    tracks = []
    for person in range(60):
        a, b = rng.uniform(-8, 8, 2), rng.uniform(-8, 8, 2)
        frames = int(np.hypot(*(b - a)) / 0.4) + 2
        tracks.append(Track(person, int(rng.integers(0, 300)), np.linspace(a, b, frames)))
    tracks.sort(key=lambda t: (t.first_frame, t.person))
    recording = Recording(
        name="crowd",
        dt=0.4,
        num_frames=max(t.last_frame for t in tracks) + 1,
        tracks=tuple(tracks),
        source="test",
    )
    name = "recorded_test_observed_people"
    if name not in FAMILIES:
        register_family(RecordedScene(recording, name=name))
    kwargs = {"family": name, "robot_visible": True, "action": "discrete"}
    every_slot = CrowdNavTask(**kwargs)
    assert every_slot.num_human_slots > 5
    with pytest.raises(PolicyTaskError, match="46 numbers"):
        make_policy("crowdnav", task=every_slot)
    task = CrowdNavTask(batch_size=2, observed_people=5, **kwargs)
    policy = make_policy("crowdnav", task=task)
    task.seed(0)
    task.reset(np.arange(2), {})
    for _ in range(10):
        obs = task.observations()[:, 0]
        task.step(policy.act(obs)[:, None])
