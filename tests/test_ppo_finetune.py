"""tools/ppo_finetune.py: the PPO model starts as the policy file acts, its observation statistics
stay the file's, and the critic's warm-up leaves the actor as it was."""

from pathlib import Path

import numpy as np
import pytest

from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.config import EnvConfig

pytest.importorskip("stable_baselines3")
ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "socialzoo" / "agents" / "shipped" / "dagger.safetensors"


@pytest.fixture(scope="module")
def tool(load_tool):
    return load_tool("ppo_finetune")


def _probe(source):
    rng = np.random.default_rng(1)
    return rng.normal(source.normalizer.mean, np.sqrt(source.normalizer.var), (256, source.input_size))


def test_warmup_trains_the_critic_alone_then_ppo_moves_the_actor(tool):
    source = MlpPolicy.load(SHIPPED)
    config = EnvConfig().replace(max_steps=60)
    model = tool.ppo_from_policy(
        source, config, num_envs=4, n_steps=25, batch_size=50, n_epochs=1, learning_rate=1e-3
    )
    probe = _probe(source)
    start = tool.exported(model, source)
    assert np.allclose(start.scores(probe), source.scores(probe), atol=1e-4)
    critic = [p.detach().clone() for p in model.policy.mlp_extractor.value_net.parameters()]
    tool.finetune(model, warmup=100, steps=0)
    after_warmup = tool.exported(model, source)
    assert np.array_equal(after_warmup.scores(probe), start.scores(probe))  # the actor frozen
    assert any(
        not np.array_equal(a, b.detach())
        for a, b in zip(critic, model.policy.mlp_extractor.value_net.parameters(), strict=True)
    )
    np.testing.assert_array_equal(model.get_env().obs_rms.mean, source.normalizer.mean.astype(np.float64))
    tool.finetune(model, warmup=0, steps=100)
    assert not np.allclose(tool.exported(model, source).scores(probe), start.scores(probe))
    np.testing.assert_array_equal(model.get_env().obs_rms.var, source.normalizer.var.astype(np.float64))


def test_a_policy_without_a_normaliser_is_refused(tool):
    source = MlpPolicy.load(SHIPPED)
    bare = MlpPolicy(source.name, source.layers, source.activation, source.observation, None)
    with pytest.raises(ValueError, match="normaliser"):
        tool.ppo_from_policy(bare, EnvConfig())
