"""The shipped PPO and DQN policies: small, loadable, made by `socialzoo train` with the seed recorded."""

import json

import numpy as np
import pytest

from socialzoo.agents import SHIPPED_DIR, make_policy
from socialzoo.env.policy_file import read_policy_file


@pytest.mark.parametrize("name", ["ppo", "dqn"])
def test_shipped_policy_loads_acts_and_has_its_run_record(name):
    path = SHIPPED_DIR / f"{name}.safetensors"
    assert path.stat().st_size < 2**20
    policy = make_policy(name)
    obs = np.random.default_rng(0).normal(size=(16, policy.input_size)).astype(np.float32)
    actions = policy.act(obs)
    assert actions.shape == (16,) and ((actions >= 0) & (actions < 4)).all()
    _, header = read_policy_file(path)
    record = json.loads((SHIPPED_DIR / f"{name}.run.json").read_text())
    assert record["command"].startswith(f"socialzoo train {name} ") and "--seed" in record["command"]
    assert record["finished"] and record["results"]["wall_seconds"] > 0
    assert record["seed"] == header["training"]["seed"]
    # The header holds the arguments as given, the record its paths relative to the run folder.
    assert record["args"] == {**header["training"]["args"], "out": "."}
    assert header["training"]["steps"] == record["args"]["total_steps"] and record["args"]["map"] == "gdc1"
    assert header["normalization"] is not None  # both train on VecNormalize-d observations
