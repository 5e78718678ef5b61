"""Learned-policy files: save -> load gives identical actions; bad files are refused, never executed."""

import itertools
import json
import pickle

import numpy as np
import pytest

from socialzoo.agents.mlp import MlpPolicy, ObservationNormalizer
from socialzoo.env.policy_file import (
    PolicyFileError,
    current_env_version,
    read_policy_file,
    save_policy_file,
)

OBSERVATION = {"layout": "paper", "num_human_slots": 25}


def _policy(rng, normalize=True):
    sizes = [107, 16, 16, 4]
    weights = [(rng.normal(size=(o, i)), rng.normal(size=o)) for i, o in itertools.pairwise(sizes)]
    norm = (
        ObservationNormalizer(rng.normal(size=107), rng.uniform(0.5, 2, 107), 10.0, 1e-8)
        if normalize
        else None
    )
    return MlpPolicy("ppo", weights, "tanh", OBSERVATION, norm)


def _header():
    return {
        "env_id": f"socialzoo/ActionSelection-v{current_env_version()}",
        "training": {"algo": "ppo", "seed": 3, "steps": 10, "command": "socialzoo train ppo"},
    }


@pytest.mark.parametrize("normalize", [True, False])
def test_save_load_gives_identical_actions(tmp_path, normalize):
    rng = np.random.default_rng(0)
    policy = _policy(rng, normalize)
    path = policy.save(tmp_path / "p.safetensors", _header())
    loaded = MlpPolicy.load(path)
    obs = rng.normal(size=(64, 107)).astype(np.float32) * 3
    np.testing.assert_array_equal(loaded.act(obs), policy.act(obs))
    np.testing.assert_array_equal(loaded.scores(obs), policy.scores(obs))
    assert loaded.act(obs.reshape(8, 8, 107)).shape == (8, 8)
    assert loaded.config()["training"]["seed"] == 3 and len(loaded.config()["file_sha256"]) == 64


def test_act_matches_a_hand_computed_forward_pass():
    w1, b1 = np.array([[1.0, -1.0]]), np.array([0.5])
    w2, b2 = np.array([[2.0], [-2.0]]), np.array([0.0, 0.1])
    policy = MlpPolicy("bc", [(w1, b1), (w2, b2)], "relu", {"layout": "paper", "num_human_slots": 0})
    # x = (1, 0): hidden relu(1.5) = 1.5, scores (3.0, -2.9) -> 0; x = (0, 3): hidden 0, scores (0, 0.1) -> 1
    np.testing.assert_array_equal(policy.act(np.array([[1.0, 0.0], [0.0, 3.0]])), [0, 1])


def test_wrong_observation_width_is_refused_naming_the_layout(tmp_path):
    policy = _policy(np.random.default_rng(1))
    with pytest.raises(ValueError, match="'paper' layout of 107"):
        policy.act(np.zeros((2, 244), dtype=np.float32))


def test_a_file_of_another_env_version_is_refused(tmp_path):
    policy = _policy(np.random.default_rng(2))
    header = _header() | {"env_id": f"socialzoo/ActionSelection-v{current_env_version() + 7}"}
    path = policy.save(tmp_path / "old.safetensors", header)
    with pytest.raises(PolicyFileError, match="retrain"):
        MlpPolicy.load(path)
    tensors, _ = read_policy_file(path, check_env_version=False)
    assert "net.0.weight" in tensors


class _Explodes:
    def __reduce__(self):
        return (exec, ("import pathlib; pathlib.Path('PWNED').write_text('x')",))


def test_a_pickle_is_refused_without_running_it(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "evil.safetensors"
    path.write_bytes(pickle.dumps({"weights": _Explodes()}))
    with pytest.raises(PolicyFileError, match="not a safetensors policy file"):
        MlpPolicy.load(path)
    assert not (tmp_path / "PWNED").exists()


def test_headers_are_checked(tmp_path):
    with pytest.raises(ValueError, match="lacks"):
        save_policy_file(tmp_path / "x.safetensors", {"a": np.zeros(2)}, {"policy": "ppo"})
    from safetensors.numpy import save_file

    bare = tmp_path / "bare.safetensors"
    save_file({"a": np.zeros(2)}, str(bare))
    with pytest.raises(PolicyFileError, match="without a socialzoo policy header"):
        read_policy_file(bare)
    other = tmp_path / "other.safetensors"
    save_file({"a": np.zeros(2)}, str(other), metadata={"socialzoo": json.dumps({"format": "nope/9"})})
    with pytest.raises(PolicyFileError, match="format 'nope/9'"):
        read_policy_file(other)
    policy = _policy(np.random.default_rng(3), normalize=False)
    path = policy.save(tmp_path / "p.safetensors", _header())
    tensors, header = read_policy_file(path)
    header["network"]["sizes"][1] = 17
    save_policy_file(tmp_path / "bad.safetensors", tensors, header)
    with pytest.raises(PolicyFileError, match=r"net\.0\.weight has shape"):
        MlpPolicy.load(tmp_path / "bad.safetensors")


def test_a_file_whose_weights_hold_nan_or_inf_is_refused_naming_the_tensors(tmp_path):
    """A diverged run's network still acts (the argmax of NaN logits is action 0 for every
    observation), so the loader refuses it instead of letting it play."""
    from socialzoo.agents import make_policy
    from socialzoo.env.human_policy import LearnedHumanPolicy

    rng = np.random.default_rng(0)
    policy = _policy(rng)
    good = policy.save(tmp_path / "good.safetensors", _header())
    tensors, header = read_policy_file(good)
    for bad_value, name in ((np.nan, "nan"), (np.inf, "inf")):
        tensors = {**tensors, "net.1.weight": tensors["net.1.weight"].copy()}
        tensors["net.1.weight"][3, 5] = bad_value
        path = save_policy_file(tmp_path / f"{name}.safetensors", tensors, header)
        with pytest.raises(
            PolicyFileError, match=rf"{name}\.safetensors: tensors \['net.1.weight'\] hold non-finite"
        ):
            make_policy(f"ppo:{path}")
        with pytest.raises(PolicyFileError, match="non-finite"):
            LearnedHumanPolicy.load(path)
