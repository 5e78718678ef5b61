"""SB3 models exported as policy files act as SB3 does: make_policy("ppo:FILE") gives the actions of
model.predict(deterministic=True) on VecNormalize-d observations."""

import numpy as np
import pytest
from stable_baselines3 import A2C, DQN, PPO
from stable_baselines3.common.vec_env import VecNormalize

from socialzoo.agents import make_policy
from socialzoo.env.policy_file import read_policy_file
from socialzoo.env.sb3_vec import SB3VecEnv
from socialzoo.train.sb3_common import env_id_of, quiet_logger
from socialzoo.train.sb3_export import ExportError, export_policy

ROOM = {"map": "open_room", "family": "circle_crossing", "max_steps": 200}


def _observations(venv, steps=60):
    """Observations the env really gives (random actions), plus scaled and shifted copies."""
    venv.seed(5)
    obs = [venv.reset()]
    rng = np.random.default_rng(0)
    for _ in range(steps):
        obs.append(venv.step(rng.integers(0, 4, venv.num_envs))[0])
    real = np.concatenate(obs)
    wild = real * rng.uniform(0.5, 2.0, real.shape).astype(np.float32) + rng.normal(size=real.shape).astype(
        np.float32
    )
    return np.concatenate([real, wild])


def _save(model, name, norm, tmp_path, config):
    policy, output = export_policy(model, name, {"layout": "paper", "num_human_slots": 25}, norm)
    header = {"env_id": env_id_of(config), "network": {"output": output}, "training": {"seed": 1}}
    return policy.save(tmp_path / f"{name}.safetensors", header)


@pytest.mark.parametrize("algo", ["ppo", "dqn"])
def test_exported_policy_acts_as_sb3_predict_on_normalised_observations(tmp_path, algo):
    venv = SB3VecEnv(8, **ROOM)
    norm = VecNormalize(venv, gamma=0.99)
    if algo == "ppo":
        model = PPO("MlpPolicy", norm, n_steps=25, batch_size=50, n_epochs=2, seed=1, device="cpu")
    else:
        model = DQN("MlpPolicy", norm, learning_starts=50, train_freq=1, seed=1, device="cpu")
    model.set_logger(quiet_logger())  # SB3's own logger leaves an empty /tmp/SB3-<date> folder
    model.learn(400)
    assert norm.obs_rms.count > 400  # statistics were collected, so normalising changes the input
    path = _save(model, algo, norm, tmp_path, venv.config)
    policy = make_policy(f"{algo}:{path}")
    obs = _observations(SB3VecEnv(4, **ROOM))
    norm.training = False
    expected, _ = model.predict(norm.normalize_obs(obs), deterministic=True)
    np.testing.assert_array_equal(policy.act(obs), expected)
    # Without the statistics the actions would differ: the test can tell.
    assert not np.array_equal(model.predict(obs, deterministic=True)[0], expected)
    _, header = read_policy_file(path)
    assert header["normalization"]["clip"] == norm.clip_obs
    assert header["network"]["output"] == ("logits" if algo == "ppo" else "q_values")


def test_export_without_normalisation_and_custom_layers(tmp_path):
    venv = SB3VecEnv(4, **ROOM)
    model = PPO("MlpPolicy", venv, n_steps=8, batch_size=32, policy_kwargs={"net_arch": [16, 8, 8]}, seed=2)
    model.set_logger(quiet_logger())
    model.learn(32)
    policy = make_policy(f"ppo:{_save(model, 'ppo', None, tmp_path, venv.config)}")
    obs = _observations(venv, steps=10)
    np.testing.assert_array_equal(policy.act(obs), model.predict(obs, deterministic=True)[0])
    assert [w.shape[0] for w, _ in policy.layers] == [16, 8, 8, 4] and policy.normalizer is None


def test_other_models_are_refused():
    model = A2C("MlpPolicy", SB3VecEnv(2, **ROOM), n_steps=4, seed=0)
    with pytest.raises(ExportError, match="PPO or DQN only"):
        export_policy(model, "a2c", {})
