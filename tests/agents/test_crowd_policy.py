"""The learned CrowdNav policies that ship: crowdnav (CrowdNav's joint state) acts as it always has,
and suite_crowdnav (trained on the scenario suite, with signals) loads and acts on the suite id's
observations, its run record beside it."""

import json

import gymnasium as gym
import numpy as np
import pytest

from socialzoo.agents import SHIPPED_DIR, make_policy
from socialzoo.env.policy_file import PolicyFileError, read_policy_file, save_policy_file
from socialzoo.env.registration import CROWD_SUITE_ID

# The suite id the shipped suite policy was trained on: v1, before the escorts held all the way
# (v2 changed the success rule and the escorted persons' speeds, not what a policy observes).
TRAINED_ON = "socialzoo/CrowdNavSuite-v1"


def test_the_shipped_crowdnav_policy_reads_the_old_layout_and_acts_as_before():
    policy = make_policy("crowdnav", task="crowdnav")
    assert "signals" not in policy.header["observation"] and not policy.signals
    assert policy.observation_size == 6 + 8 * 5 and policy.task_overrides == {"action": "discrete"}
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(256, 46)).astype(np.float32)
    obs[:, 6 + 7 * 5 :] = rng.random((256, 5)) > 0.4
    # The actions of the file before the network learned the signal layout.
    expected = [10, 5, 5, 5, 50, 5, 5, 50, 50, 5, 5, 50, 50, 24, 5, 5, 30, 24, 75, 5]
    assert policy.act(obs)[:20].tolist() == expected


def test_the_shipped_suite_policy_acts_on_the_suite_ids_observations_with_its_run_record():
    path = SHIPPED_DIR / "suite_crowdnav.safetensors"
    assert path.stat().st_size < 2**20
    _, header = read_policy_file(path, check_env_version=False)
    assert header["env_id"] == TRAINED_ON and header["observation"]["signals"] is True
    record = json.loads((SHIPPED_DIR / "suite_crowdnav.run.json").read_text())
    command = record["command"]
    assert (
        command.startswith("socialzoo train crowdnav ")
        and "--families suite" in command
        and "--seed" in command
    )
    assert record["finished"] and record["seed"] == header["training"]["seed"]
    assert (
        record["results"]["families"] == header["training"]["families"]
        and len(header["training"]["families"]) == 25
    )
    assert record["results"]["env_id"] == TRAINED_ON
    # The file is the kept checkpoint, chosen on the families' validation cases.
    assert (
        record["results"]["kept_checkpoint"]
        == f"checkpoints/step_{header['training']['steps']:09d}.safetensors"
    )
    for family in ("frontal_approach", "narrow_doorway"):
        env = gym.make(CROWD_SUITE_ID, family=family, action="discrete")
        policy = make_policy("suite_crowdnav", task="crowdnav", observation_space=env.observation_space)
        assert policy.task_overrides == {"action": "discrete", "signals": True}
        obs, _ = env.reset(seed=0)
        for _ in range(3):
            action = policy.act(obs[None])
            assert action.shape == (1,) and 0 <= action[0] < 81
            obs, *_ = env.step(int(action[0]))
        env.close()


def test_a_suite_policy_of_the_current_suite_id_loads_and_one_of_an_unknown_version_is_refused(tmp_path):
    """The suite id has a version of its own, one ahead of the CrowdNav task's: a file trained on it
    now (socialzoo/CrowdNavSuite-v2) loads (it was refused: v2 is not the task's v1)."""
    from socialzoo.agents.crowd_policy import CrowdAttentionPolicy

    tensors, header = read_policy_file(SHIPPED_DIR / "suite_crowdnav.safetensors", check_env_version=False)
    current = save_policy_file(
        tmp_path / "current.safetensors", tensors, {**header, "env_id": CROWD_SUITE_ID}
    )
    assert CrowdAttentionPolicy.load(current).header["env_id"] == CROWD_SUITE_ID
    other = save_policy_file(
        tmp_path / "other.safetensors", tensors, {**header, "env_id": "socialzoo/CrowdNavSuite-v9"}
    )
    with pytest.raises(PolicyFileError, match="CrowdNavSuite-v9"):
        CrowdAttentionPolicy.load(other)


def test_a_policy_trained_in_the_world_frame_is_evaluated_in_it(tmp_path):
    """A learner trained with action_frame="world" (CrowdNav's ActionXY) acts in the world frame in
    `socialzoo crowdnav eval` as it does in training, not turned into the default goal frame."""
    from socialzoo.agents.crowd_policy import CrowdAttentionPolicy
    from socialzoo.bench.crowd_eval import evaluate_crowd
    from socialzoo.bench.task_benchmark import run_task_benchmark
    from socialzoo.env.crowd_config import CrowdNavConfig

    tensors, header = read_policy_file(SHIPPED_DIR / "crowdnav.safetensors", check_env_version=False)
    header["training"]["task"]["action_frame"] = "world"
    path = CrowdAttentionPolicy(tensors, header).save(tmp_path / "world.safetensors", tensors)
    policy = CrowdAttentionPolicy.load(path)
    assert policy.task_overrides == {"action": "discrete", "action_frame": "world"}
    rows, _ = run_task_benchmark(
        "socialzoo/CrowdNav-v1", [f"crowdnav:{path}"], tmp_path / "out", cases=4, figures=False
    )
    config = CrowdNavConfig(action="discrete", action_frame="world")
    direct = evaluate_crowd(lambda obs, task: policy.act(obs), config, "test", 4).episodes
    expected = float(np.mean([e["path_length"] for e in direct]))
    goal_frame = evaluate_crowd(
        lambda obs, task: policy.act(obs), config.replace(action_frame="goal"), "test", 4
    )
    assert rows[0]["path_length_mean"] == pytest.approx(expected)
    assert expected != pytest.approx(float(np.mean([e["path_length"] for e in goal_frame.episodes])))


def test_a_policy_trained_with_other_kinematics_is_refused_by_name(tmp_path):
    """A unicycle learner played on a holonomic task (81 actions either way) ran without a word."""
    from socialzoo.agents import PolicyTaskError, make_policy
    from socialzoo.agents.crowd_policy import CrowdAttentionPolicy
    from socialzoo.bench.task_benchmark import TaskId, run_task_benchmark

    tensors, header = read_policy_file(SHIPPED_DIR / "crowdnav.safetensors", check_env_version=False)
    header["training"]["task"]["robot"]["kinematics"] = "unicycle"
    path = CrowdAttentionPolicy(tensors, header).save(tmp_path / "unicycle.safetensors", tensors)
    holonomic = TaskId.of("socialzoo/CrowdNav-v1").make(1)
    with pytest.raises(
        PolicyTaskError, match=r"trained with a unicycle robot .* this task's robot is holonomic"
    ):
        make_policy(f"crowdnav:{path}", task=holonomic)
    with pytest.raises(PolicyTaskError, match="unicycle"):
        run_task_benchmark("socialzoo/CrowdNav-v1", [f"crowdnav:{path}"], tmp_path / "out", cases=1)
    unicycle = TaskId.of("socialzoo/CrowdNav-v1").make(1, robot={"kinematics": "unicycle"})
    assert make_policy(f"crowdnav:{path}", task=unicycle).check_config(unicycle.config) is None
    make_policy("crowdnav", task=holonomic)  # the shipped learner, trained holonomic
