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
    with pytest.raises(ValueError, match=r"CrowdNavArgs.learning_rate must be in \(0.0, 1.0\], got 0.0"):
        CrowdNavArgs(learning_rate=0.0, **TINY)
    with pytest.raises(
        ValueError, match=r"CrowdNavArgs.batch_size \(65\) must be at most the rollout.*\(64\)"
    ):
        CrowdNavArgs(**{**TINY, "batch_size": 65}, total_steps=64, checkpoint_every=64)
    with pytest.raises(ValueError, match=r"CrowdNavArgs.batch_size must be an int >= 2, got 1"):
        CrowdNavArgs(**{**TINY, "batch_size": 1})
    assert np.isclose(
        CrowdNavArgs(**TINY).task().reward.collision_penalty, -0.25
    )  # the task keeps CrowdNav's


def test_a_tiny_run_on_two_suite_families_acts_on_the_suite_ids_observations(tmp_path):
    import gymnasium as gym

    from socialzoo.env.policy_file import read_policy_file
    from socialzoo.train.crowdnav import SUITE_ID

    args = CrowdNavArgs(
        out=tmp_path / "run",
        families="a,narrow_doorway",
        total_steps=64,
        checkpoint_every=64,
        eval_trials=2,
        progress=False,
        **{**TINY, "n_steps": 8},
    )
    assert args.family_names() == ("frontal_approach", "narrow_doorway") and args.rows() == [2, 2]
    policy_file = train(args)
    record = json.loads((tmp_path / "run" / "run.json").read_text())
    assert record["results"]["families"] == ["frontal_approach", "narrow_doorway"]
    assert record["results"]["env_id"] == SUITE_ID and record["args"]["families"] == "a,narrow_doorway"
    _, header = read_policy_file(policy_file, check_env_version=False)
    assert header["env_id"] == SUITE_ID and header["observation"]["signals"] is True
    assert header["training"]["families"] == ["frontal_approach", "narrow_doorway"]
    for family in args.family_names():
        env = gym.make(SUITE_ID, family=family, action="discrete")
        policy = make_policy(
            f"crowdnav:{policy_file}", task="crowdnav", observation_space=env.observation_space
        )
        obs, _ = env.reset(seed=0)
        for _ in range(3):
            action = policy.act(obs[None])
            assert action.shape == (1,) and 0 <= action[0] < 81
            obs, *_ = env.step(int(action[0]))
        env.close()


def test_families_are_resolved_split_and_checked():
    from socialzoo.scenarios.suite import SUITE_NAMES
    from socialzoo.train.crowdnav import validation_cases

    suite = CrowdNavArgs(families="suite", num_envs=64, **{k: v for k, v in TINY.items() if k != "num_envs"})
    assert suite.family_names() == SUITE_NAMES and suite.env_id == "socialzoo/CrowdNavSuite-v2"
    assert sum(suite.rows()) == 64 and set(suite.rows()) == {2, 3} and suite.rows()[0] == 3
    counts = [cases for _, cases in validation_cases(suite)]
    assert sum(counts) == 100 and set(counts) == {4}
    task = suite.task("blind_corner")
    assert task.family == "blind_corner" and task.signals and task.max_humans == 20 and task.time_limit == 60
    few = CrowdNavArgs(families="a, b ,c", eval_trials=2, **TINY)
    assert [t.family for t, _ in validation_cases(few)] == ["frontal_approach", "pedestrian_obstruction"]
    with pytest.raises(ValueError, match=r"num_envs \(4\) must be at least the number of families \(25\)"):
        CrowdNavArgs(families="suite", **TINY)
    with pytest.raises(ValueError, match="unknown family 'moon'"):
        CrowdNavArgs(families="a,moon", **TINY)
    with pytest.raises(ValueError, match="twice"):
        CrowdNavArgs(families="a,frontal_approach", **TINY)
    with pytest.raises(ValueError, match="leave variant empty"):
        CrowdNavArgs(families="a", variant="Walls", **TINY)
    with pytest.raises(ValueError, match="decided by the families"):
        CrowdNavArgs(families="a", env_overrides={"map": "gdc1"}, **TINY)
