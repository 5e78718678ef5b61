"""GAIL end to end on a tiny budget: the run folder, checkpoints every checkpoint_every env steps,
a loadable policy; the reward forms; argument checks."""

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from socialzoo.agents.mlp import MlpPolicy  # noqa: E402
from socialzoo.train.gail import Args, gail_reward, train  # noqa: E402


def test_a_short_gail_run_writes_policy_checkpoints_and_record(small_demos, tmp_path):
    args = Args(
        demos=small_demos, steps=1000, total_steps=400, num_envs=4, rollout_len=50, max_episode_steps=60,
        hidden=(16, 16), disc_hidden=(16, 16), minibatch=100, out=tmp_path / "gail", checkpoint_every=200,
        progress=False, seed=3,
    )  # fmt: skip
    path = train(args)
    assert path == tmp_path / "gail" / "gail.safetensors"
    record = json.loads((tmp_path / "gail" / "run.json").read_text())
    assert record["algo"] == "gail" and record["seed"] == 3 and record["finished"]
    assert record["args"]["scenario_repeats"] == 20 and record["results"]["env_steps"] == 400
    checkpoints = sorted(p.name for p in (tmp_path / "gail" / "checkpoints").iterdir())
    assert checkpoints == ["step_000000200.safetensors", "step_000000400.safetensors"]
    assert list((tmp_path / "gail" / "tensorboard").glob("events.out.tfevents.*"))
    policy = MlpPolicy.load(path)
    assert policy.header["training"]["env_steps"] == 400 and policy.header["training"]["seed"] == 3
    obs = np.zeros((3, policy.input_size), dtype=np.float32)
    assert policy.act(obs).shape == (3,)


def test_checkpoints_are_evaluated_in_episodes_of_the_training_time_limit(small_demos, tmp_path, monkeypatch):
    """max_episode_steps is the time limit of the validation episodes too, not the benchmark's 3200."""
    import socialzoo.bench.runner as runner

    limits = []
    monkeypatch.setattr(
        runner,
        "run_chunk",
        lambda trials, spec: limits.extend(c.max_steps for c in spec.env_configs.values()) or [],
    )
    args = Args(
        demos=small_demos, steps=1000, total_steps=200, num_envs=4, rollout_len=50, max_episode_steps=60,
        hidden=(16, 16), disc_hidden=(16, 16), minibatch=100, out=tmp_path / "gail", checkpoint_every=200,
        progress=False, eval_trials=2,
    )  # fmt: skip
    train(args)
    assert limits == [60]


def test_reward_forms():
    logits = torch.tensor([-50.0, 0.0, 2.0])
    d = torch.sigmoid(logits)
    np.testing.assert_allclose(gail_reward(logits, "logit"), [-10.0, 0.0, 2.0])
    np.testing.assert_allclose(gail_reward(logits, "positive")[1:], -torch.log(1 - d[1:]), rtol=1e-5)
    np.testing.assert_allclose(gail_reward(logits, "negative")[1:], torch.log(d[1:]), rtol=1e-5)
    assert gail_reward(logits, "negative")[0] == -10.0


def test_bad_arguments_name_the_field():
    with pytest.raises(ValueError, match=r"gail Args\.gamma must be in \[0\.0, 1\.0\], got 1\.5"):
        Args(gamma=1.5)
    with pytest.raises(ValueError, match=r"gail Args\.num_envs"):
        Args(num_envs=0)
    with pytest.raises(ValueError, match=r"gail Args\.reward"):
        Args(reward="other")
    # A minibatch larger than an iteration's transitions was cut to them, recorded as asked.
    with pytest.raises(
        ValueError, match=r"gail Args\.minibatch \(201\) must be at most .* num_envs \* rollout_len \(200\)"
    ):
        Args(num_envs=4, rollout_len=50, minibatch=201)
    # 300 steps in iterations of 4 x 50 trained 400 (the collector gathers whole iterations).
    with pytest.raises(
        ValueError,
        match=r"gail Args\.total_steps \(300\) must be a multiple of an iteration's transitions, .* \(200\)",
    ):
        Args(total_steps=300, num_envs=4, rollout_len=50, minibatch=100)
    assert Args(total_steps=400, num_envs=4, rollout_len=50, minibatch=100).total_steps == 400
