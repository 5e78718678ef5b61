"""The native TorchRL env: specs, the PettingZooWrapper's transitions, batches, partial resets, mixes."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torchrl.envs.libs.pettingzoo import PettingZooWrapper
from torchrl.envs.utils import check_env_specs

from socialzoo.env.parallel import parallel_env
from socialzoo.env.torchrl_env import SocialNavTorchEnv

SMALL = {"map": "open_room", "max_steps": 40, "scenario": {"min_humans": 1, "max_humans": 5}}


def make(batch_size: int = 1, seed: int = 0, **kwargs) -> SocialNavTorchEnv:
    return SocialNavTorchEnv(batch_size=batch_size, seed=seed, **{**SMALL, **kwargs})


def wrapper(**kwargs) -> PettingZooWrapper:
    env = parallel_env(episode_info=False, **{**SMALL, **kwargs})
    return PettingZooWrapper(env=env, use_mask=True, return_state=True, done_on_any=False)


class GoAloneEveryone:
    """A robot policy for the env's robot_policy: always GoAlone, and records what it was given."""

    def __init__(self) -> None:
        self.calls = 0

    def act(self, obs, task):
        self.calls += 1
        assert task.observations() is obs
        return np.zeros(obs.shape[:-1], dtype=np.int64)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"num_robots": 2, "num_learned_humans": 3},
        {"num_robots": 1, "num_learned_humans": 2, "robot_action": "velocity"},
        {"num_robots": 1, "num_learned_humans": 0},
    ],
)
def test_native_check_env_specs(kwargs):
    env = make(batch_size=3, **kwargs)
    check_env_specs(env, seed=0)
    assert list(env.group_map) == ["robot", "human"][: 1 + bool(kwargs["num_learned_humans"])]


def test_wrapper_check_env_specs_same_layout():
    native = make(num_robots=2, num_learned_humans=3)
    wrapped = wrapper(num_robots=2, num_learned_humans=3)
    check_env_specs(wrapped, seed=0)
    assert native.group_map == wrapped.group_map
    for spec in ("full_action_spec", "full_reward_spec", "full_done_spec"):
        mine, theirs = getattr(native, spec), getattr(wrapped, spec)
        assert set(mine.keys(True, True)) == set(theirs.keys(True, True)), spec
        for key in mine.keys(True, True):
            assert mine[key].shape[1:] == theirs[key].shape and mine[key].dtype == theirs[key].dtype, key
    common = set(native.observation_spec.keys(True, True)) & set(wrapped.observation_spec.keys(True, True))
    assert {("robot", "observation"), ("human", "observation"), ("human", "mask"), "state"} <= common


@pytest.mark.parametrize("robot_action", ["subpolicy", "velocity"])
def test_same_transitions_as_the_petting_zoo_wrapper(robot_action):
    """Seed for seed, step for step, across episode ends and resets: every entry the wrapper has.

    The differences by design: ("human", "mask") is also False for empty human slots, and "state"
    is float32 here, float64 in the ParallelEnv (the same numbers once rounded).
    """
    kwargs = {"num_robots": 2, "num_learned_humans": 3, "robot_action": robot_action}
    native, wrapped = make(seed=5, **kwargs), wrapper(**kwargs)
    rng = np.random.default_rng(1)
    td_n, td_w = native.reset(), wrapped.reset(seed=5)
    ends = 0
    for step in range(130):
        if robot_action == "subpolicy":
            robot = torch.as_tensor(rng.integers(0, 4, 2))
        else:
            robot = torch.as_tensor(rng.uniform(-1, 1, (2, 2)), dtype=torch.float32)
        human = torch.as_tensor(rng.uniform(-1, 1, (3, 2)), dtype=torch.float32)
        td_w["robot", "action"], td_w["human", "action"] = robot, human
        td_n["robot", "action"], td_n["human", "action"] = robot[None], human[None]
        out_w, td_w = wrapped.step_and_maybe_reset(td_w)
        out_n, td_n = native.step_and_maybe_reset(td_n)
        present = out_w["next", "human", "info", "present"].bool()
        for key in out_w.keys(True, True):
            theirs, mine = out_w[key], out_n[key][0]
            if key[-1] == "mask" and "human" in key:
                before = key[:-1] + ("info", "present")
                theirs = theirs & out_w[before].bool()
            if key in ("state", ("next", "state")):
                theirs = theirs.float()
            assert torch.equal(theirs, mine), (step, key)
        assert present.shape == (3,)
        ends += int(out_n["next", "done"].item())
    assert ends >= 2  # the 40-step limit ended episodes, and both reset the same way


def test_rows_of_a_batch_are_independent_and_row_zero_is_the_single_env():
    single, batch = make(num_learned_humans=2), make(batch_size=3, num_learned_humans=2)
    rng = np.random.default_rng(0)
    td_s, td_b = single.reset(), batch.reset()
    for _ in range(60):
        robot = torch.as_tensor(rng.integers(0, 4, (3, 1)))
        human = torch.as_tensor(rng.uniform(-1, 1, (3, 2, 2)), dtype=torch.float32)
        td_b["robot", "action"], td_b["human", "action"] = robot, human
        td_s["robot", "action"], td_s["human", "action"] = robot[:1], human[:1]
        out_b, td_b = batch.step_and_maybe_reset(td_b)
        out_s, td_s = single.step_and_maybe_reset(td_s)
        assert (out_b[:1] == out_s).all()
    # Other rows play other scenarios of their own streams.
    assert not torch.equal(out_b["next", "state"][0], out_b["next", "state"][1])


def test_partial_reset_restarts_only_the_done_rows():
    env = make(batch_size=2, num_learned_humans=2)
    td = env.reset()
    td = env.rand_action(td)
    out = env.step(td)
    state = out["next", "state"].clone()
    marker = torch.tensor([[True], [False]])
    again = env.reset(out["next"].clone().set("_reset", marker))
    assert not torch.equal(again["state"][0], state[0])
    assert torch.equal(again["state"][1], state[1])
    assert int(env.core.state.step_count[0]) == 0 and int(env.core.state.step_count[1]) == 1


def test_mixed_learned_and_scripted_humans_step_and_masks_follow_the_slots():
    env = make(batch_size=4, num_learned_humans=3, scenario={"min_humans": 1, "max_humans": 8}, max_steps=60)
    td = env.reset()
    present = env.core.state.human_mask.copy()
    assert torch.equal(td["human", "mask"], torch.as_tensor(present[:, :3]))
    assert present[:, 3:].any()  # some humans are scripted
    # Learned humans stand still (zero desired velocity); scripted ones walk their routes.
    start = env.core.state.human_pos.copy()

    def halt_and_stand(td):
        td["human", "action"] = torch.zeros(4, 3, 2)
        td["robot", "action"] = torch.ones(4, 1, dtype=torch.int64)
        return td

    td = env.rollout(50, policy=halt_and_stand, tensordict=td, auto_reset=False)
    moved = np.linalg.norm(env.core.state.human_pos - start, axis=-1)
    learned, scripted = moved[:, :3][present[:, :3]], moved[:, 3:][present[:, 3:]]
    assert learned.mean() < 0.2 < 0.5 < scripted.mean(), (learned, scripted)
    # Empty slots: zero observations and rewards throughout.
    empty = ~torch.as_tensor(present[:, :3])
    steps = td.transpose(0, 1)  # rollouts are (B, T)
    assert not steps["next", "human", "observation"][:, empty].any()
    assert not steps["next", "human", "reward"][:, empty].any()


def test_robot_policy_drives_the_robots_inside_the_env():
    policy = GoAloneEveryone()
    env = make(batch_size=2, num_learned_humans=2, robot_policy=policy)
    assert ("robot", "action") not in env.full_action_spec.keys(True, True)
    check_env_specs(env, seed=0)
    driven = env.rollout(20, tensordict=env.reset())
    manual = make(batch_size=2, num_learned_humans=2)
    manual.set_seed(0)
    td = manual.reset()
    env.set_seed(0)
    td_p = env.reset()
    for t in range(20):
        action = manual.rand_action(td)["human", "action"]
        td["robot", "action"] = torch.zeros(2, 1, dtype=torch.int64)
        td["human", "action"] = action
        td_p["human", "action"] = action
        out_m, td = manual.step_and_maybe_reset(td)
        out_p, td_p = env.step_and_maybe_reset(td_p)
        assert torch.equal(out_m["next", "robot", "observation"], out_p["next", "robot", "observation"]), t
    assert policy.calls > 20 and driven.shape == (2, 20)


def test_a_rollout_records_the_actions_its_policy_gave_across_resets():
    """On the CPU the env reads the action tensors as numpy views: the rows it resets must not
    rewrite them (on a GPU the copy hid this; tools/gpu_torchrl_check.py compares both)."""
    env = make(batch_size=2, max_steps=3)
    given = torch.tensor([[3], [2]])

    def constant(td):
        td["robot", "action"] = given.clone()
        return td

    td = env.rollout(7, policy=constant, break_when_any_done=False)
    assert (td["robot", "action"] == given[:, None]).all()  # rollouts are (B, T, R)


def test_robots_that_left_are_masked_and_report_done():
    env = make(num_robots=2, num_learned_humans=1, robot_action="velocity", max_steps=200)
    td = env.reset()

    def full_ahead(td):
        td["robot", "action"] = torch.tensor([[[1.0, 0.0], [0.0, 0.0]]])
        td["human", "action"] = torch.zeros(1, 1, 2)
        return td

    td = env.rollout(200, policy=full_ahead, tensordict=td, auto_reset=False)[0]
    mask = td["next", "robot", "mask"]
    gone = torch.nonzero(~mask[:, 0])
    assert len(gone), "robot_0 never left (wall or goal expected driving straight at full speed)"
    first = int(gone[0])
    assert td["next", "robot", "done"][first, 0, 0].item()
    after = td["next", "robot"][first + 1 :, 0]
    assert after["done"].all() and after["terminated"].all() and after["truncated"].all()
    assert not after["observation"].any() and not after["reward"].any()


def test_bad_arguments_and_actions_raise():
    with pytest.raises(ValueError, match="batch_size"):
        SocialNavTorchEnv(batch_size=0, **SMALL)
    with pytest.raises(ValueError, match="robot_policy"):
        make(robot_policy=object())
    with pytest.raises(ValueError, match="num_learned_humans"):
        make(num_learned_humans=9)
    # A task whose robot observation is a dict (CrowdNav's "dict"): named, not a TypeError in the specs.
    with pytest.raises(ValueError, match="SocialNavTorchEnv: the task's observation must be one Box"):
        SocialNavTorchEnv(task="crowdnav", observation="dict")
    with pytest.raises(ValueError, match=r"SocialNavTorchEnv.set_seed: seed must be an int >= 0"):
        make().set_seed(-1)
    env = make(num_learned_humans=1)
    td = env.rand_action(env.reset())
    td["human", "action"] = torch.full((1, 1, 2), 1.5)
    with pytest.raises(ValueError, match="human action"):
        env.step(td)


def test_a_bad_robot_action_is_named_by_its_row_and_robot():
    """A NaN robot action in row 1, robot 1 of three rows of two robots: the message named
    "robot 3" (the CrowdNav task's flat index over rows and robots); it names row 1's robot 1, and
    nothing changes."""
    env = SocialNavTorchEnv(batch_size=3, task="crowdnav", num_robots=2, observation="flat", seed=0)
    td = env.reset()
    before = env.task.core.state.robot_pose.copy()
    action = torch.zeros(3, 2, 2)
    action[1, 1, 0] = float("nan")
    td["robot", "action"] = action
    with pytest.raises(ValueError, match=r"CrowdNav: velocity action \[nan, 0.0\] of row 1's robot 1 "):
        env.step(td)
    np.testing.assert_array_equal(env.task.core.state.robot_pose, before)
