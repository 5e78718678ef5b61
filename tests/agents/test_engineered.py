"""GoAlone and Ref: Ref's decisions on hand-built scenes, its observation parsing, the registry."""

import json

import numpy as np
import pytest

from socialzoo.agents import POLICIES, make_policy, register_policy
from socialzoo.agents.engineered import (
    GoAlone,
    Ref,
    RefConfig,
    ref_actions,
    ref_inputs_from_core,
    ref_inputs_from_paper_obs,
)
from socialzoo.nav.subpolicies import FOLLOW, GO_ALONE, HALT

TARGET = np.array([[1.5, 0.0]])  # carrot 1.5 m straight ahead


def decide(humans, target=TARGET, seen=None, cfg=None):
    """Ref's action for one robot; humans: list of (x, y, vx, vy) in the robot frame."""
    h = np.array(humans, dtype=float).reshape(1, -1, 4)
    seen = np.ones(h.shape[:2], bool) if seen is None else np.array([seen])
    return int(ref_actions(h[..., :2], h[..., 2:], seen, np.asarray(target, float), cfg)[0])


def test_clear_corridor_goes_alone():
    assert decide([]) == GO_ALONE
    # Beside the corridor, or ahead but beyond |target| + 0.9 = 2.4 m.
    assert decide([(1.0, 1.0, 0.0, 0.0), (1.0, -0.8, 0.0, 0.0), (2.6, 0.0, -1.0, 0.0)]) == GO_ALONE


def test_human_walking_ahead_towards_the_target_is_followed():
    assert decide([(1.2, 0.1, 1.0, 0.0)]) == FOLLOW
    # Within 0.8 rad of the target direction.
    assert decide([(1.2, 0.1, np.cos(0.7), np.sin(0.7))]) == FOLLOW
    # The direction to the local target, not the robot's heading, is the reference.
    assert decide([(1.0, 0.3, 0.0, 1.0)], target=[[0.0, 1.5]]) == FOLLOW
    assert decide([(1.0, 0.3, 0.0, 1.0)]) == HALT


def test_crossing_or_oncoming_or_standing_human_halts():
    assert decide([(1.0, 0.2, 0.0, 1.0)]) == HALT  # crossing, 1.57 rad off
    assert decide([(1.0, 0.0, -1.0, 0.0)]) == HALT  # oncoming
    assert decide([(1.0, 0.0, 0.05, 0.0)]) == HALT  # (almost) standing: no walking direction
    assert decide([(1.2, 0.1, np.cos(0.9), np.sin(0.9))]) == HALT  # just outside 0.8 rad


def test_human_behind_or_unseen_is_ignored():
    assert decide([(-0.5, 0.0, 1.0, 0.0)]) == GO_ALONE
    assert decide([(-1.0, 0.1, 0.0, 1.0)]) == GO_ALONE
    assert decide([(1.0, 0.0, 0.0, 1.0)], seen=[False]) == GO_ALONE


def test_nearest_blocking_human_decides():
    walker_far, crosser_near = (2.0, 0.0, 1.0, 0.0), (1.0, 0.0, 0.0, 1.0)
    assert decide([walker_far, crosser_near]) == HALT
    walker_near, crosser_far = (1.0, 0.0, 1.0, 0.0), (2.0, 0.0, 0.0, 1.0)
    assert decide([crosser_far, walker_near]) == FOLLOW
    # A non-blocking human nearer than the blocker (outside the corridor) does not count.
    assert decide([(0.5, 1.0, 0.0, 1.0), walker_far]) == FOLLOW


def test_front_sector_and_corridor_are_configurable():
    human = (0.4, 0.6, 0.0, 1.0)  # bearing 56 degrees, inside the 0.62 m corridor
    assert decide([human]) == HALT
    assert decide([human], cfg=RefConfig(sector_deg=45.0)) == GO_ALONE
    assert decide([human], cfg=RefConfig(corridor_half_width=0.5)) == GO_ALONE


def test_batch_of_scenes_in_one_call():
    scenes = [[(1.0, 0.0, 1.0, 0.0)], [(1.0, 0.0, 0.0, 1.0)], [(-1.0, 0.0, 1.0, 0.0)]]
    h = np.array(scenes, float)
    out = ref_actions(h[..., :2], h[..., 2:], np.ones((3, 1), bool), np.repeat(TARGET, 3, axis=0))
    assert out.tolist() == [FOLLOW, HALT, GO_ALONE]
    assert out.dtype == np.int64


def paper_obs(humans, target=(1.5, 0.0), v=0.0, slots=4):
    obs = np.zeros(7 + 4 * slots, np.float32)
    obs[2:4] = target
    obs[4] = v
    for i, (x, y, vx, vy) in enumerate(humans):
        obs[7 + 4 * i : 11 + 4 * i] = (x, y, vx - v, vy)  # slots hold velocities relative to the robot
    return obs


def test_ref_acts_on_paper_observations():
    obs = np.stack(
        [
            paper_obs([]),
            paper_obs([(1.2, 0.1, 1.0, 0.0)], v=1.2),  # walking ahead while the robot drives at 1.2 m/s
            paper_obs([(1.0, 0.2, 0.0, 1.0)], v=0.5),
            paper_obs([(-1.0, 0.0, 1.0, 0.0)]),
        ]
    )
    ref = Ref()
    assert ref.act(obs).tolist() == [GO_ALONE, FOLLOW, HALT, GO_ALONE]
    assert ref.act(obs.reshape(2, 2, -1)).shape == (2, 2)
    _, vel, seen, target = ref_inputs_from_paper_obs(obs)
    assert seen.sum(1).tolist() == [0, 1, 1, 1]
    np.testing.assert_allclose(vel[1, 0], [1.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(target[0], [1.5, 0.0])
    with pytest.raises(ValueError, match="7 \\+ 4K"):
        ref.act(np.zeros((2, 10), np.float32))
    with pytest.raises(ValueError, match="shape"):
        ref.act(np.zeros(11, np.float32))


def test_goalone_and_registry():
    assert GoAlone().act(np.zeros((5, 1, 11))).tolist() == [[0]] * 5
    assert set(POLICIES) >= {"goalone", "ref"}
    assert isinstance(make_policy("GoAlone"), GoAlone)
    ref = make_policy("ref", heading_tolerance=0.5)
    assert ref.config()["heading_tolerance"] == 0.5
    json.dumps(ref.config())
    with pytest.raises(ValueError, match=r"unknown policy 'nope'.*goalone.*ref"):
        make_policy("nope")
    with pytest.raises(ValueError, match="already registered"):
        register_policy("ref", "somewhere:Else")
    with pytest.raises(ValueError, match=r"RefConfig\.corridor_half_width"):
        RefConfig(corridor_half_width=-1.0)
    with pytest.raises(ValueError, match=r"RefConfig\.sector_deg"):
        RefConfig(sector_deg=120.0)


def test_observation_and_world_state_give_the_same_decisions(rooms_map_path):
    """On a real env, Ref from the paper observation equals Ref from the core's world state."""
    from socialzoo.env.config import EnvConfig
    from socialzoo.env.tasks.action_selection import ActionSelectionTask
    from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario

    path = rooms_map_path
    scenarios = ScenarioConfig(min_humans=4, max_humans=8)
    task = ActionSelectionTask(EnvConfig(map=str(path), max_steps=200, scenario=scenarios), 6)
    task.reset_rows(np.arange(6), [generate_scenario(task.map, seed, scenarios) for seed in range(6)])
    ref = Ref()
    chosen = []
    for _ in range(200):
        from_obs = ref.act(task.obs)
        from_state = ref_actions(*ref_inputs_from_core(task.core), ref.cfg).reshape(from_obs.shape)
        np.testing.assert_array_equal(from_obs, from_state)
        chosen += from_obs.ravel().tolist()
        task.step(from_obs)
    assert {GO_ALONE, HALT, FOLLOW} <= set(chosen)
