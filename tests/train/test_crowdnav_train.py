"""`socialzoo train crowdnav`: a tiny run on the skeleton writes its policy, checkpoints, evaluations
and record; the policy loads in numpy and acts; arguments are checked."""

import json

import numpy as np
import pytest

pytest.importorskip("torch")
pytest.importorskip("stable_baselines3")

from socialzoo.agents import make_policy
from socialzoo.bench.crowd_eval import evaluate_crowd
from socialzoo.train.crowdnav import CrowdNavArgs, train

TINY = {
    "num_envs": 4,
    "n_steps": 16,
    "batch_size": 32,
    "n_epochs": 1,
    "embed": (8,),
    "value": (8,),
    "attention": (8,),
}


def test_a_tiny_run_keeps_its_best_validation_checkpoint(tmp_path):
    args = CrowdNavArgs(
        out=tmp_path / "run", total_steps=128, checkpoint_every=64, eval_trials=3, progress=False, **TINY
    )
    policy_file = train(args)
    record = json.loads((tmp_path / "run" / "run.json").read_text())
    results = record["results"]
    assert record["finished"] and results["env_steps"] == 128
    assert results["checkpoints"] == [
        "checkpoints/step_000000064.safetensors",
        "checkpoints/step_000000128.safetensors",
    ]
    assert results["kept_checkpoint"] == results["best_checkpoint"]["file"]
    assert (tmp_path / "run" / "evaluations.csv").read_text().count("\n") == 3
    policy = make_policy(f"crowdnav:{policy_file}", task="crowdnav")
    assert policy.header["training"]["seed"] == 0 and policy.action_kind == "discrete"
    result = evaluate_crowd(policy.act, args.task(), "val", cases=2)
    assert result.summary["episodes"] == 2
    # A finished run is not repeated.
    stamp = policy_file.stat().st_mtime_ns
    assert train(args) == policy_file and policy_file.stat().st_mtime_ns == stamp


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="multiple of the rollout"):
        CrowdNavArgs(total_steps=100, **TINY)
    with pytest.raises(ValueError, match="variant"):
        CrowdNavArgs(variant="Moon", **TINY)
    with pytest.raises(ValueError, match="collision_penalty"):
        CrowdNavArgs(collision_penalty=1.0, **TINY)
    with pytest.raises(ValueError, match="eval_trials"):
        CrowdNavArgs(eval_trials=101, **TINY)
    assert np.isclose(
        CrowdNavArgs(**TINY).task().reward.collision_penalty, -0.25
    )  # the task keeps CrowdNav's
