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


def _absolute_paths(value):
    """Every word of the strings in a JSON value (and of a NAME=PATH spec) that is an absolute path."""
    if isinstance(value, dict):
        return [p for v in value.values() for p in _absolute_paths(v)]
    if isinstance(value, list):
        return [p for v in value for p in _absolute_paths(v)]
    if not isinstance(value, str):
        return []
    words = [part for word in value.split() for part in word.split("=")]
    return [w for w in words if len(w) > 1 and (w.startswith(("/", "~")) or w[1:3] == ":\\")]


def test_no_shipped_file_names_a_path_of_the_machine_that_made_it():
    """Issue 35: a shipped policy's records held the training machine's absolute paths (crowdnav's
    header "out": "/work/runs/crowdnav_s0" and its command, humans.selection.json's run and every
    checkpoint): paths are relative to the run folder (or the selection's), as the writers now make
    them."""
    from safetensors import safe_open

    found = {}
    for path in sorted(SHIPPED_DIR.iterdir()):
        if path.suffix == ".json":
            values = json.loads(path.read_text())
        elif path.suffix == ".safetensors":
            with safe_open(str(path), "np") as f:
                values = [json.loads(v) for v in (f.metadata() or {}).values()]
        else:
            continue
        if paths := _absolute_paths(values):
            found[path.name] = paths[:3]
    assert not found
