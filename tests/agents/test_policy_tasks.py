"""make_policy resolves a policy for the task it is asked about and refuses, with a named error, a
policy of another task or a learned policy whose observations are not the size of the task's."""

from __future__ import annotations

import subprocess
import sys

import pytest

from socialzoo.agents import POLICIES, PolicyTaskError, make_policy, policy_task, register_policy
from socialzoo.env.crowd_config import CrowdNavConfig
from socialzoo.env.crowd_observation import observation_space
from socialzoo.env.tasks.action_selection import ActionSelectionTask
from socialzoo.env.tasks.crowdnav import CrowdNavTask


def test_every_shipped_policy_names_a_known_task():
    from socialzoo.env.tasks import TASKS

    shipped = [name for name, target in POLICIES.items() if target.startswith("socialzoo.")]
    assert {policy_task(name) for name in shipped} <= set(TASKS)


def test_a_policy_of_another_task_is_refused_naming_both_tasks():
    with pytest.raises(PolicyTaskError, match=r"'orca' acts in task 'crowdnav', not 'action_selection'"):
        make_policy("orca")
    with pytest.raises(PolicyTaskError, match=r"policies of 'crowdnav': crowdnav, orca, social_force"):
        make_policy("ref", task="crowdnav")
    assert make_policy("orca", task="crowdnav").act is not None


def test_a_learned_policy_of_another_observation_size_is_refused():
    wide = observation_space(CrowdNavConfig.variant("20"))
    with pytest.raises(PolicyTaskError, match=r"46 numbers \(trained on socialzoo/CrowdNav-v1\).* have 166"):
        make_policy("crowdnav", task="crowdnav", observation_space=wide)
    assert make_policy("crowdnav", task=CrowdNavTask()).observation_size == 46
    assert make_policy("ppo", task=ActionSelectionTask(map="open_room")).input_size == 107
    with pytest.raises(PolicyTaskError, match="244"):
        make_policy("ppo", task=ActionSelectionTask(map="open_room", observation={"layout": "socialgym1"}))


def test_a_registered_policy_keeps_its_task():
    register_policy("orca_again", "socialzoo.agents.crowd_engineered:CrowdOrcaRobot", task="crowdnav")
    try:
        assert policy_task("orca_again") == "crowdnav"
        with pytest.raises(ValueError, match="already registered"):
            register_policy("orca_again", "socialzoo.agents.crowd_engineered:CrowdOrcaRobot")
    finally:
        POLICIES.pop("orca_again")
        from socialzoo.agents import POLICY_TASKS

        POLICY_TASKS.pop("orca_again")


def test_the_crowdnav_replay_of_a_policy_on_another_variant_fails_with_the_named_error(tmp_path):
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "socialzoo",
            "crowdnav",
            "replay",
            "--policies",
            "crowdnav",
            "--variant",
            "20",
            "--out",
            str(tmp_path / "page.html"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 2
    assert "reads observations of 46 numbers" in done.stderr and "166" in done.stderr


def test_a_policy_file_of_another_task_is_refused_as_such_not_as_outdated(tmp_path):
    """A file recording a current id of a task with versions of its own (socialzoo/CrowdNav-v1) is
    not a benchmark policy of an old version: the robot and people loaders say whose it is."""
    import numpy as np

    from socialzoo.env.human_policy import LearnedHumanPolicy
    from socialzoo.env.policy_file import PolicyFileError, save_policy_file

    network = {"kind": "mlp", "activation": "tanh", "output": "logits", "sizes": [3, 2]}
    tensors = {"net.0.weight": np.zeros((2, 3), np.float32), "net.0.bias": np.zeros(2, np.float32)}
    path = save_policy_file(
        tmp_path / "crowd.safetensors",
        tensors,
        {
            "policy": "crowdnav",
            "network": network,
            "observation": {},
            "env_id": "socialzoo/CrowdNav-v1",
            "training": {},
        },
    )
    for spec in (f"ppo:{path}", f"bc:{path}"):
        with pytest.raises(
            PolicyFileError, match=r"CrowdNav-v1, a 'crowdnav' task env.*policy of the 'crowdnav' task"
        ) as err:
            make_policy(spec)
        assert "retrain" not in str(err.value)
    with pytest.raises(PolicyFileError, match=r"a 'crowdnav' task env"):
        LearnedHumanPolicy.load(path)
    # An outdated benchmark file still gets the advice to retrain.
    old = save_policy_file(
        tmp_path / "old.safetensors",
        tensors,
        {
            "policy": "ppo",
            "network": network,
            "observation": {},
            "env_id": "socialzoo/ActionSelection-v1",
            "training": {},
        },
    )
    with pytest.raises(PolicyFileError, match=r"retrain it"):
        make_policy(f"ppo:{old}")


def test_a_task_benchmark_refuses_a_policy_of_another_task_before_any_policy_plays(tmp_path):
    """The refused policy comes second: the first must not have played (nor stored a trial) by then."""
    from socialzoo.bench.task_benchmark import run_task_benchmark

    lines = []
    with pytest.raises(PolicyTaskError, match=r"'goalone' acts in task 'action_selection', not 'crowdnav'"):
        run_task_benchmark(
            "socialzoo/CrowdNav-v1", ["orca", "goalone"], tmp_path / "one", cases=2, say=lines.append
        )
    assert lines == [] and not (tmp_path / "one").exists()


def test_the_benchmark_of_several_ids_refuses_before_the_first_id_plays(tmp_path, capsys):
    from socialzoo.cli import main

    ids = "socialzoo/CrowdNav-v1,socialzoo/ActionSelection-v2"
    code = main(
        ["benchmark", "--maps", ids, "--policies", "orca", "--trials", "2", "--out", str(tmp_path / "two")]
    )
    assert code == 2
    assert "'orca' acts in task 'crowdnav', not 'action_selection'" in capsys.readouterr().err
    assert not (tmp_path / "two").exists()
