"""The reference code's quirks (SPEC section 11) as switches: each one on a hand-made step where it
changes the value, the preset and its ids, and the default ids untouched."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import socialzoo  # noqa: F401  (registers the ids)
from socialzoo.agents.mlp import MlpPolicy, ObservationNormalizer, evaluation_file, without_normalisation
from socialzoo.core.state import WorldState
from socialzoo.env.config import EnvConfig
from socialzoo.env.observation import SOCIALGYM1_NUM_SLOTS, ObservationConfig, build_observation
from socialzoo.env.outcome import robot_outcome
from socialzoo.env.quirks import REFERENCE_QUIRKS, ReferenceQuirks
from socialzoo.env.registration import BENCHMARK_IDS, REFERENCE_IDS
from socialzoo.env.reward import compute_reward, progress
from socialzoo.env.world import StepEvents


def world(robot_xy, goal_xy, human_xy=(0.8, 0.0)):
    """One world, one robot heading +x at 1 m/s, one human."""
    return WorldState(
        robot_pose=np.array([[[*robot_xy, 0.0]]]),
        robot_vel=np.array([[[1.0, 0.0]]]),
        robot_goal=np.array([[[*goal_xy, 0.0]]]),
        human_pos=np.array([[human_xy]], dtype=float),
        human_vel=np.zeros((1, 1, 2)),
        human_pref_speed=np.ones((1, 1)),
        human_mask=np.ones((1, 1), bool),
        human_route=np.zeros((1, 1, 1, 2)),
        human_route_len=np.ones((1, 1), np.intp),
        human_waypoint=np.zeros((1, 1), np.intp),
        human_direction=np.ones((1, 1), np.intp),
        step_count=np.array([10]),
        noise_key=np.zeros(1, np.uint64),
    )


def outcome(quirks, before, after, contact=False, **reward):
    cfg = EnvConfig(map="open_room", quirks=quirks).replace(reward=dict(reward))
    events = StepEvents(
        robot_wall=np.array([[False]]),
        robot_human=np.array([[[contact]]]),
        human_blocked=np.zeros((1, 1), bool),
    )
    no = np.zeros((1, 1), bool)
    return robot_outcome(before, after, events, np.ones((1, 1), bool), np.array([[-1]]), no, no, cfg)


def test_defaults_off_and_the_preset_all_on():
    assert not ReferenceQuirks().any
    assert EnvConfig().quirks == ReferenceQuirks()
    assert all(getattr(REFERENCE_QUIRKS, name) for name in ReferenceQuirks.names())
    with pytest.raises(ValueError, match=r"ReferenceQuirks\.goal_distance_x_only"):
        ReferenceQuirks(goal_distance_x_only=1)  # type: ignore[arg-type]
    cfg = EnvConfig.from_dict({"quirks": {"human_theta_index": True}})
    assert cfg.quirks.human_theta_index and not cfg.quirks.goal_distance_x_only
    assert EnvConfig.from_dict(cfg.to_dict()) == cfg


def test_named_sets_and_which_change_training():
    assert ReferenceQuirks.named("all") == REFERENCE_QUIRKS
    alone = ReferenceQuirks.named("reward_distance_plus_bonus")
    assert alone.reward_distance_plus_bonus and sum(getattr(alone, n) for n in ReferenceQuirks.names()) == 1
    assert alone.trains and REFERENCE_QUIRKS.trains
    # PPO's evaluation quirk changes no env a learner trains in.
    assert not ReferenceQuirks.named("ppo_eval_without_normalisation").trains
    with pytest.raises(ValueError, match="unknown reference quirk 'bonus'"):
        ReferenceQuirks.named("bonus")


def test_goal_distance_x_only():
    # The robot moves 0.1 m along y straight towards a goal 3 m away along y.
    before, after = world((0.0, 0.0), (0.0, 3.0)), world((0.0, 0.1), (0.0, 3.0))
    start, end, goal = np.array([[0.0, 0.0]]), np.array([[0.0, 0.1]]), np.array([[0.0, 3.0]])
    assert progress(start, end, goal)[0] == pytest.approx(0.1)
    assert progress(start, end, goal, x_only=True)[0] == 0.0
    ours = outcome(ReferenceQuirks(), before, after)
    theirs = outcome(ReferenceQuirks(goal_distance_x_only=True), before, after)
    assert ours.progress[0, 0] == pytest.approx(0.1)
    assert theirs.progress[0, 0] == 0.0
    assert ours.reward[0, 0] - theirs.reward[0, 0] == pytest.approx(5.0 * 0.1)


def test_collision_penalty_dropped():
    before, after = world((0.0, 0.0), (4.0, 0.0)), world((0.025, 0.0), (4.0, 0.0))
    # The default weight is 0, so the switch is exact only with a weight: it drops the term.
    ours = outcome(ReferenceQuirks(), before, after, contact=True, w_collision=-2.0)
    theirs = outcome(
        ReferenceQuirks(collision_penalty_dropped=True), before, after, contact=True, w_collision=-2.0
    )
    assert ours.human_collisions[0, 0] == theirs.human_collisions[0, 0] == 1
    assert theirs.reward[0, 0] - ours.reward[0, 0] == pytest.approx(2.0)
    default = outcome(ReferenceQuirks(), before, after, contact=True)
    assert default.reward[0, 0] == theirs.reward[0, 0]


def test_reward_distance_plus_bonus():
    d_g, blame, force = np.array([0.025, -0.01]), np.array([0.7, 0.2]), np.array([0.9, 0.4])
    success, contacts = np.array([True, False]), np.array([1, 0])
    cfg = EnvConfig().reward
    ours, _ = compute_reward(d_g, blame, force, success, contacts, cfg)
    theirs, terms = compute_reward(
        d_g, blame, force, success, contacts, cfg, ReferenceQuirks(reward_distance_plus_bonus=True)
    )
    np.testing.assert_allclose(theirs, [5.0 * 0.025 + 100.0, 10.0 * -0.01])
    np.testing.assert_allclose(ours - theirs, [-0.1 * 0.7 - 0.01 * 0.9, -0.1 * 0.2 - 0.01 * 0.4])
    assert terms["blame"].tolist() == terms["force"].tolist() == terms["collision"].tolist() == [0.0, 0.0]
    total = terms["progress"] + terms["blame"] + terms["force"] + terms["success"] + terms["collision"]
    np.testing.assert_array_equal(total, theirs)
    # Through the env's outcome: a human 0.8 m ahead costs force and blame, except with the quirk.
    before, after = world((0.0, 0.0), (4.0, 0.0)), world((0.025, 0.0), (4.0, 0.0))
    a = outcome(ReferenceQuirks(), before, after)
    b = outcome(ReferenceQuirks(reward_distance_plus_bonus=True), before, after)
    assert a.blame[0, 0] > 0 and a.force[0, 0] > 0
    assert b.reward[0, 0] == pytest.approx(5.0 * 0.025)
    assert a.reward[0, 0] < b.reward[0, 0]


def test_human_theta_index():
    # Two people, the second nearer: slot 0 holds person 1, slot 1 person 0.
    args = (
        ObservationConfig(layout="socialgym1"),
        np.array([[0.0, 0.0, 0.0]]),
        np.array([[0.0, 0.0]]),
        np.array([[2.0, 0.0]]),
        np.array([[2.0, 0.0]]),
        np.array([0]),
        np.array([[[3.0, 0.0], [1.0, 1.0]]]),
        np.zeros((1, 2, 2)),
        np.array([[True, True]]),
    )
    ours = build_observation(*args)
    theirs = build_observation(*args, theta_index=True)
    assert ours[0, 2] == ours[0, 5] == 0.0
    assert (theirs[0, 2], theirs[0, 5]) == (1.0, 0.0)
    np.testing.assert_array_equal(np.delete(ours, [2, 5], axis=1), np.delete(theirs, [2, 5], axis=1))
    # An occluded person keeps an all-zero slot.
    hidden = build_observation(*args[:-1], np.array([[False, True]]), theta_index=True)
    assert hidden[0, 2] == 1.0 and not hidden[0, 3 : 3 * SOCIALGYM1_NUM_SLOTS].any()


def test_human_theta_index_in_the_env():
    env = gym.make(
        "socialzoo/ActionSelectionReference-v2", observation={"layout": "socialgym1"}, max_steps=20
    ).unwrapped
    n = SOCIALGYM1_NUM_SLOTS
    for seed in range(20):  # the first scenario whose robot sees two people or more
        obs, _ = env.reset(seed=seed)
        filled = (obs[0 : 3 * n : 3] != 0) | (obs[1 : 3 * n : 3] != 0)
        if filled.sum() >= 2:
            break
    assert filled.sum() == min(int(env.task.core.see().sum()), n) >= 2
    theta = obs[2 : 3 * n : 3]
    # Every filled slot's theta is a distinct person index; at most one person has index 0.
    indices = theta[filled]
    assert len(set(indices.tolist())) == len(indices) and (indices == 0).sum() <= 1 and indices.max() > 0
    assert not theta[~filled].any()


def test_ppo_eval_without_normalisation(tmp_path):
    # A one-layer network: scores = obs; normalised, the second entry wins; raw, the first.
    weights = [(np.eye(2, dtype=np.float32), np.zeros(2, dtype=np.float32))]
    norm = ObservationNormalizer(np.array([10.0, 0.0]), np.array([100.0, 1.0]), 10.0, 1e-8)
    policy = MlpPolicy("ppo", weights, "tanh", {"layout": "paper"}, norm)
    file = policy.save(tmp_path / "ppo.safetensors", {"env_id": next(iter(BENCHMARK_IDS)), "training": {}})
    obs = np.array([[5.0, 1.0]], dtype=np.float32)
    assert MlpPolicy.load(file).act(obs).tolist() == [1]
    raw = MlpPolicy.load(without_normalisation(file, tmp_path / "raw.safetensors"))
    assert raw.normalizer is None and raw.header["evaluated_without_normalisation"]
    assert raw.act(obs).tolist() == [0]
    # The switch: only PPO, only with the quirk on.
    on = ReferenceQuirks(ppo_eval_without_normalisation=True)
    assert evaluation_file("ppo", file, ReferenceQuirks(), tmp_path / "q") == file
    assert evaluation_file("dqn", file, on, tmp_path / "q") == file
    stripped = evaluation_file("ppo", file, on, tmp_path / "q")
    assert stripped != file and MlpPolicy.load(stripped).act(obs).tolist() == [0]


def test_reference_ids():
    assert set(REFERENCE_IDS) == {
        "socialzoo/ActionSelectionReference-v2",
        "socialzoo/ActionSelectionTransferReference-v2",
    }
    for env_id in REFERENCE_IDS:
        assert env_id in gym.registry
        assert gym.registry[env_id].kwargs["quirks"] == dataclasses.asdict(REFERENCE_QUIRKS)
    for env_id in BENCHMARK_IDS:
        assert "quirks" not in gym.registry[env_id].kwargs


def test_reference_id_same_world_other_reward():
    """The quirks change rewards only: the same seed and actions give the same observations."""
    ours = gym.make("socialzoo/ActionSelection-v2", max_steps=400)
    theirs = gym.make("socialzoo/ActionSelectionReference-v2", max_steps=400)
    a, _ = ours.reset(seed=11)
    b, _ = theirs.reset(seed=11)
    np.testing.assert_array_equal(a, b)
    rewards = []
    for _ in range(120):  # GoAlone: the robot starts moving after about 50 steps
        a, ra, *_ = ours.step(0)
        b, rb, *_ = theirs.step(0)
        np.testing.assert_array_equal(a, b)
        rewards.append((ra, rb))
    assert any(ra != rb for ra, rb in rewards)
