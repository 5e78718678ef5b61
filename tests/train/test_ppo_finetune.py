"""socialzoo train ppo-finetune: the PPO model starts as the policy file acts, its observation
statistics stay the file's, the critic's warm-up leaves the actor as it was, and a run on the
skeleton writes a policy of the source's name with its run record."""

import json
import tempfile
from pathlib import Path

import numpy as np
import pytest

from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.config import EnvConfig
from socialzoo.train import ppo_finetune

pytest.importorskip("stable_baselines3")

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "socialzoo" / "agents" / "shipped" / "dagger.safetensors"


def _probe(source):
    rng = np.random.default_rng(1)
    return rng.normal(source.normalizer.mean, np.sqrt(source.normalizer.var), (256, source.input_size))


def test_warmup_trains_the_critic_alone_then_ppo_moves_the_actor():
    source = MlpPolicy.load(SHIPPED)
    config = EnvConfig().replace(max_steps=60)
    model = ppo_finetune.ppo_from_policy(
        source, config, num_envs=4, n_steps=25, batch_size=50, n_epochs=1, learning_rate=1e-3
    )
    probe = _probe(source)
    start = ppo_finetune.exported(model, source)
    assert np.allclose(start.scores(probe), source.scores(probe), atol=1e-4)
    critic = [p.detach().clone() for p in model.policy.mlp_extractor.value_net.parameters()]
    ppo_finetune.finetune(model, warmup=100, steps=0)
    after_warmup = ppo_finetune.exported(model, source)
    assert np.array_equal(after_warmup.scores(probe), start.scores(probe))  # the actor frozen
    assert any(
        not np.array_equal(a, b.detach())
        for a, b in zip(critic, model.policy.mlp_extractor.value_net.parameters(), strict=True)
    )
    np.testing.assert_array_equal(model.get_env().obs_rms.mean, source.normalizer.mean.astype(np.float64))
    ppo_finetune.finetune(model, warmup=0, steps=100)
    assert not np.allclose(ppo_finetune.exported(model, source).scores(probe), start.scores(probe))
    np.testing.assert_array_equal(model.get_env().obs_rms.var, source.normalizer.var.astype(np.float64))


def test_init_takes_a_shipped_policy_by_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no file named "dagger" here
    assert ppo_finetune.Args(init="dagger").init == SHIPPED
    assert ppo_finetune.Args(init="DAgger").init == SHIPPED
    (tmp_path / "dagger").write_text("a file of that name is the file")
    assert ppo_finetune.Args(init="dagger").init == Path("dagger")
    assert ppo_finetune.Args(init="ref").init == Path("ref")  # an engineered policy has no file


def test_a_policy_without_a_normaliser_is_refused():
    source = MlpPolicy.load(SHIPPED)
    bare = MlpPolicy(source.name, source.layers, source.activation, source.observation, None)
    with pytest.raises(ValueError, match="normaliser"):
        ppo_finetune.ppo_from_policy(bare, EnvConfig())


def test_a_run_writes_a_policy_of_the_source_name_and_its_record(tmp_path):
    args = ppo_finetune.Args(init=SHIPPED, out=tmp_path / "ft", warmup=0, steps=1, w_blame=-2.0)
    path = ppo_finetune.train(args)
    assert path == tmp_path / "ft" / "ppo_finetune.safetensors"
    policy = MlpPolicy.load(path)
    assert policy.name == "dagger"
    assert policy.header["training"]["finetune"]["w_blame"] == -2.0
    record = json.loads((tmp_path / "ft" / "run.json").read_text())
    assert record["algo"] == "ppo-finetune" and record["finished"]
    assert record["results"]["env_steps"] == 1
    assert ppo_finetune.train(args) == path  # a finished run is not repeated


@pytest.mark.parametrize(("field", "value"), [("steps", -1), ("lr", 0.0), ("gamma", 1.5), ("threads", 0)])
def test_bad_arguments_name_the_field_and_value(field, value):
    with pytest.raises(ValueError, match=rf"{field}.*{value}"):
        ppo_finetune.Args(init=SHIPPED, **{field: value})


def test_the_run_shows_its_progress_in_env_steps():
    # A default run is 440,000 steps: it showed nothing until it ended.
    class Bar:
        n = 0

        def update(self, k):
            self.n += k

    source = MlpPolicy.load(SHIPPED)
    model = ppo_finetune.ppo_from_policy(
        source, EnvConfig().replace(max_steps=60), num_envs=4, n_steps=25, batch_size=50, n_epochs=1
    )
    bar = Bar()
    ppo_finetune.finetune(model, warmup=100, steps=100, bar=bar)
    assert bar.n == 200


def test_fine_tuning_leaves_no_empty_sb3_folder_in_the_temp_folder(tmp_path, monkeypatch):
    # SB3 gives a model built without a logger one of its own on the first learn(): an empty
    # folder SB3-<date> in the temp folder per model, which piled up in /tmp by the hundred.
    monkeypatch.delenv("SB3_LOGDIR", raising=False)
    temp = tmp_path / "temp"
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    source = MlpPolicy.load(SHIPPED)
    model = ppo_finetune.ppo_from_policy(
        source, EnvConfig().replace(max_steps=60), num_envs=4, n_steps=25, batch_size=50, n_epochs=1
    )
    ppo_finetune.finetune(model, warmup=100, steps=100)
    assert list(temp.glob("SB3-*")) == []


def test_a_policy_of_another_observation_layout_is_fine_tuned_on_its_own_observations(tmp_path):
    # Found fine-tuning a PPO trained with {"observation": {"num_human_slots": 10}} (47 numbers): the run
    # ended in a torch RuntimeError (107 against 47), since the fine-tuning env had the default layout.
    source = MlpPolicy.load(SHIPPED)
    mean, var = source.normalizer.mean[:47], source.normalizer.var[:47]
    first = (source.layers[0][0][:, :47], source.layers[0][1])
    small = MlpPolicy(
        "dagger",
        [first, *source.layers[1:]],
        source.activation,
        {"layout": "paper", "num_human_slots": 10},
        type(source.normalizer)(mean, var, source.normalizer.clip, source.normalizer.epsilon),
    )
    init = small.save(tmp_path / "small.safetensors", dict(source.header))
    path = ppo_finetune.train(
        ppo_finetune.Args(init=init, out=tmp_path / "ft", warmup=0, steps=1, progress=False)
    )
    tuned = MlpPolicy.load(path)
    assert tuned.observation == {"layout": "paper", "num_human_slots": 10} and tuned.input_size == 47
