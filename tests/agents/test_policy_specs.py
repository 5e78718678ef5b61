"""Policies are named "ref", "ppo" (the shipped file) or "ppo:PATH" (a file)."""

import numpy as np
import pytest

import socialzoo.agents as agents
from socialzoo.agents import check_policy_spec, make_policy, split_policy_spec
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.policy_file import current_env_version


def _save(path):
    rng = np.random.default_rng(0)
    policy = MlpPolicy(
        "ppo", [(rng.normal(size=(4, 107)), np.zeros(4))], "tanh", {"layout": "paper", "num_human_slots": 25}
    )
    header = {"env_id": f"socialzoo/ActionSelection-v{current_env_version()}", "training": {"seed": 0}}
    return policy.save(path, header)


def test_split():
    assert split_policy_spec("PPO:runs/A.safetensors") == ("ppo", "runs/A.safetensors")
    assert split_policy_spec("ref") == ("ref", None)
    with pytest.raises(ValueError, match=r"unknown policy 'nope'; known policies: .*ref"):
        split_policy_spec("nope")
    with pytest.raises(ValueError, match="no file after"):
        split_policy_spec("ppo:")


def test_learned_policies_load_from_a_path_or_the_shipped_file(tmp_path, monkeypatch):
    file = _save(tmp_path / "mine.safetensors")
    loaded = make_policy(f"ppo:{file}")
    assert isinstance(loaded, MlpPolicy) and loaded.path == file
    monkeypatch.setattr(agents, "SHIPPED_DIR", tmp_path / "shipped")
    with pytest.raises(ValueError, match=r"no shipped 'ppo' policy.*ppo:PATH"):
        check_policy_spec("ppo")
    _save(tmp_path / "shipped" / "ppo.safetensors")
    assert make_policy("ppo").path == tmp_path / "shipped" / "ppo.safetensors"


def test_bad_specs_are_refused_before_anything_runs(tmp_path):
    with pytest.raises(ValueError, match="no such file"):
        check_policy_spec(f"ppo:{tmp_path / 'missing.safetensors'}")
    # A folder was "no such file", though it is there: the user looks for a typo instead.
    with pytest.raises(ValueError, match=r"policy 'ppo:.*': '.*' is a folder, not a file"):
        check_policy_spec(f"ppo:{tmp_path}")
    with pytest.raises(ValueError, match="not loaded from a file"):
        check_policy_spec(f"ref:{tmp_path}")
    from socialzoo.bench.experiment import BenchmarkConfig

    with pytest.raises(ValueError, match=r"BenchmarkConfig\.policies: policy 'ppo:"):
        BenchmarkConfig(policies=(f"ppo:{tmp_path / 'missing.safetensors'}",))


@pytest.mark.parametrize("how", ["spec", "keyword"])
def test_make_policy_refuses_a_file_for_an_engineered_policy(tmp_path, how):
    # socialzoo demo --policy-path FILE (ref by default) and replay --policy ref=FILE got a
    # TypeError from RefConfig (a traceback from demo) instead of check_policy_spec's message.
    args = ("ref:" + str(tmp_path),) if how == "spec" else ("ref",)
    kwargs = {} if how == "spec" else {"path": tmp_path}
    with pytest.raises(ValueError, match="policy 'ref' is not loaded from a file"):
        make_policy(*args, **kwargs)


def test_a_learned_policy_without_a_shipped_file_names_the_command_that_trains_it():
    """mappo files come from `socialzoo train cotrain` (there is no `socialzoo train mappo`)."""
    from socialzoo.train import TRAINERS

    with pytest.raises(ValueError, match=r"`socialzoo train cotrain --out DIR`\) and name it 'mappo:PATH'"):
        check_policy_spec("mappo")
    for key, command in agents.POLICY_TRAINERS.items():
        assert key in agents.POLICIES and command.split()[0] in TRAINERS
