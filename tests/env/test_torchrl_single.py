"""The TorchRL adapter: TorchRL's spec check, the same transitions as the Gymnasium VectorEnv,
partial resets that touch only the rows asked for."""

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("torchrl")

from torchrl.envs.utils import check_env_specs, step_mdp  # noqa: E402

from socialzoo.env.torchrl_single import ActionSelectionTorchEnv, CrowdNavTorchEnv  # noqa: E402
from socialzoo.env.vector import ActionSelectionVectorEnv  # noqa: E402


def _one_hot(actions):
    return torch.nn.functional.one_hot(torch.as_tensor(actions), 4).bool()


def test_torchrl_spec_check_passes():
    env = ActionSelectionTorchEnv(2, max_steps=20)
    env.set_seed(3)
    check_env_specs(env)


def test_torchrl_gym_env_builds_a_registered_id():
    """TorchRL's GymEnv passes frameskip to gymnasium.make and drops it on Python's TypeError for an
    unknown keyword; the ids raised a ValueError, so GymEnv("socialzoo/...") failed."""
    from torchrl.envs import GymEnv

    env = GymEnv("socialzoo/CrowdNav-v1")
    check_env_specs(env, seed=0)
    assert env.rollout(5)["next", "observation"].shape == (5, 46)


def test_rows_match_the_vector_env_including_episode_ends():
    b, seed = 3, 7
    env = ActionSelectionTorchEnv(b, max_steps=25)
    env.set_seed(seed)
    td = env.reset()
    venv = ActionSelectionVectorEnv(b, max_steps=25)
    obs, _ = venv.reset(seed=seed)
    np.testing.assert_array_equal(td["observation"].numpy(), obs)
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(60):
        actions = rng.integers(0, 4, b)
        td["action"] = _one_hot(actions)
        td = env.step(td)
        obs, reward, terminated, truncated, info = venv.step(actions)
        nxt = td["next"]
        ended = terminated | truncated
        # TorchRL keeps an episode's true last observation; the VectorEnv reports it in final_obs.
        last = np.where(ended[:, None], info["final_obs"], obs) if ended.any() else obs
        np.testing.assert_array_equal(nxt["observation"].numpy(), last)
        np.testing.assert_allclose(nxt["reward"].numpy()[:, 0], reward, rtol=1e-6, atol=1e-7)
        np.testing.assert_array_equal(nxt["terminated"].numpy()[:, 0], terminated)
        np.testing.assert_array_equal(nxt["truncated"].numpy()[:, 0], truncated)
        np.testing.assert_array_equal(nxt["done"].numpy()[:, 0], ended)
        ends += int(ended.sum())
        td = env.maybe_reset(step_mdp(td))
        np.testing.assert_array_equal(td["observation"].numpy(), obs)
    assert ends >= b  # every row went through at least one truncation


def test_partial_reset_touches_only_the_masked_rows():
    env = ActionSelectionTorchEnv(3, categorical_action_encoding=True)
    env.set_seed(1)
    td = env.reset()
    for _ in range(5):
        td["action"] = torch.zeros(3, dtype=torch.int64)
        td = step_mdp(env.step(td))
    before = td["observation"].clone()
    seeds = [s.seed for s in env.core.scenarios]
    td["_reset"] = torch.tensor([[False], [True], [False]])
    out = env.reset(td)
    np.testing.assert_array_equal(out["observation"][[0, 2]].numpy(), before[[0, 2]].numpy())
    assert not torch.equal(out["observation"][1], before[1])
    assert [s.seed for s in env.core.scenarios][::2] == seeds[::2]
    assert env.core.state.step_count[1] == 0 and env.core.state.step_count[0] == 5


def test_a_partial_reset_after_set_seed_touches_only_the_masked_rows_too():
    """set_seed mid-run, then a reset of some rows (TorchRL's "_reset"): TorchRL keeps the other
    rows' data, so the env must keep their episodes. It restarted every row after set_seed, so
    those rows' observations in the tensordict were the old episode's while the env played a new
    one (SocialNavTorchEnv already kept them)."""
    env = CrowdNavTorchEnv(2)
    env.set_seed(1)
    td = env.reset()
    for _ in range(3):
        td["action"] = torch.zeros(2, 2)
        td = step_mdp(env.step(td))
    env.set_seed(2)
    td["_reset"] = torch.tensor([[True], [False]])
    out = env.reset(td)
    fresh = CrowdNavTorchEnv(2)
    fresh.set_seed(2)
    assert torch.equal(out["observation"][0], fresh.reset()["observation"][0])  # row 0 on seed 2's stream
    assert torch.equal(out["observation"][1], td["observation"][1])  # row 1 as TorchRL kept it ...
    np.testing.assert_array_equal(
        env.task.observations()[1, 0], td["observation"][1].numpy()
    )  # ... and so the env
    assert env.core.state.step_count[1] == 3 and env.core.state.step_count[0] == 0


def test_scenarios_repeat_as_configured():
    from tensordict import TensorDict

    env = ActionSelectionTorchEnv(1, scenario={"repeats": 2})
    env.set_seed(0)
    env.reset()
    seeds = [env.core.scenarios[0].seed]
    for _ in range(2):
        env.reset(TensorDict({"_reset": torch.tensor([[True]])}, batch_size=[1]))
        seeds.append(env.core.scenarios[0].seed)
    assert seeds[0] == seeds[1] != seeds[2]


def test_configs_it_cannot_serve_are_refused():
    with pytest.raises(ValueError, match="num_robots=2"):
        ActionSelectionTorchEnv(1, num_robots=2)
    with pytest.raises(ValueError, match="num_envs"):
        ActionSelectionTorchEnv(0)
    with pytest.raises(ValueError, match="one Box"):
        CrowdNavTorchEnv(1, observation="dict")
    with pytest.raises(ValueError, match=r"CrowdNavTorchEnv.set_seed: seed must be an int >= 0"):
        CrowdNavTorchEnv(1).set_seed(1.5)


def test_velocity_actions_are_a_bounded_box_that_passes_the_spec_check():
    from torchrl.envs.utils import check_env_specs

    env = ActionSelectionTorchEnv(2, robot_action="velocity", max_steps=10)
    assert tuple(env.action_spec.shape) == (2, 2)
    check_env_specs(env, seed=0)


def test_bad_actions_are_refused_naming_the_adapter():
    # Found probing the adapter with bad actions: an all-zero or NaN one-hot played action 0, a
    # (B, 2) one-hot action 0 or 1 (argmax), index 1.5 played 1 and NaN said "action
    # -9223372036854775808", and a wrong shape was torch's "shape '[3]' is invalid".
    from tensordict import TensorDict

    env = ActionSelectionTorchEnv(3, max_steps=20)
    env.set_seed(0)
    env.reset()
    bad_one_hots = {
        "not one-hot": torch.zeros(3, 4),
        "not one-hot.*nan": torch.full((3, 4), float("nan")),
        r"shape \(3, 4\), got \(3, 2\)": torch.eye(2)[[0, 1, 0]],
        r"shape \(3, 4\), got \(3,\)": torch.tensor([0, 1, 2]),
    }
    for match, action in bad_one_hots.items():
        with pytest.raises(ValueError, match=f"ActionSelectionTorchEnv: .*{match}"):
            env.step(TensorDict({"action": action}, batch_size=[3]))
    env.step(TensorDict({"action": _one_hot([0, 1, 3])}, batch_size=[3]))
    indices = ActionSelectionTorchEnv(3, categorical_action_encoding=True, max_steps=20)
    indices.reset()
    for action in ([0.0, 1.0, 1.5], [0.0, 1.0, float("nan")], [[0, 0]] * 3, [True, False, True]):
        with pytest.raises(ValueError, match="ActionSelectionTorchEnv: actions must be"):
            indices.step(TensorDict({"action": torch.tensor(action)}, batch_size=[3]))
    indices.step(TensorDict({"action": torch.tensor([[0], [1], [3]])}, batch_size=[3]))  # (B, 1) indices
    velocity = ActionSelectionTorchEnv(3, robot_action="velocity", max_steps=20)
    velocity.reset()
    with pytest.raises(ValueError, match=r"ActionSelectionTorchEnv: actions must have shape \(3, 2\)"):
        velocity.step(TensorDict({"action": torch.zeros(3, 3)}, batch_size=[3]))


def test_a_reset_mask_of_another_shape_is_refused_by_name():
    # Found probing partial resets: a (B, 2) "_reset" was torch's "shape '[3]' is invalid for input
    # of size 6" (TaskTorchEnv) or TorchRL's mask IndexError after the rows were reset (SocialNavTorchEnv).
    from tensordict import TensorDict

    from socialzoo.env.torchrl_env import SocialNavTorchEnv

    for env in (ActionSelectionTorchEnv(3, max_steps=20), SocialNavTorchEnv(batch_size=3, max_steps=20)):
        env.rollout(2, break_when_any_done=False)
        steps = env.core.state.step_count.copy()
        assert (steps == 2).all()
        mask = TensorDict({"_reset": torch.ones(3, 2, dtype=torch.bool)}, batch_size=[3])
        with pytest.raises(ValueError, match=rf"{type(env).__name__}: '_reset' must be \(3, 1\) flags"):
            env.reset(mask)
        np.testing.assert_array_equal(env.core.state.step_count, steps)
        env.reset(TensorDict({"_reset": torch.tensor([True, False, False])}, batch_size=[3]))
