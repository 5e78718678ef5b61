"""The imitation trainers' networks: a TorchRL actor saved as an MlpPolicy file acts identically
once loaded; the normaliser matches the numpy one; the discriminator learns to tell Ref's
transitions from random ones."""

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("torchrl")

from tensordict import TensorDict  # noqa: E402
from torchrl.envs.utils import ExplorationType, set_exploration_type  # noqa: E402

from socialzoo.agents.demonstrations import load_demonstrations  # noqa: E402
from socialzoo.agents.mlp import MlpPolicy  # noqa: E402
from socialzoo.env.policy_file import current_env_version  # noqa: E402
from socialzoo.train.policy_net import (  # noqa: E402
    Discriminator,
    init_linear,
    make_actor,
    normalizer_stats,
    policy_network,
    to_mlp_policy,
)

OBSERVATION = {"layout": "paper", "num_human_slots": 25}


@pytest.mark.parametrize("activation", ["relu", "tanh"])
def test_torchrl_actor_and_loaded_policy_file_choose_the_same_actions(tmp_path, small_demos, activation):
    arrays, _ = load_demonstrations(small_demos)
    obs = arrays["obs"]
    generator = torch.Generator().manual_seed(1)
    net = policy_network(obs.shape[1], (32, 16), activation, normalizer_stats(obs), generator)
    init_linear(net, generator, last_gain=1.0)  # non-trivial logits (the default last layer is near 0)
    actor = make_actor(net)
    header = {"env_id": f"socialzoo/ActionSelection-v{current_env_version()}", "training": {"algo": "bc"}}
    path = to_mlp_policy("bc", net, OBSERVATION, activation).save(tmp_path / "bc.safetensors", header)
    loaded = MlpPolicy.load(path)
    # Demonstration observations, and wild ones that hit the normaliser's clip.
    rng = np.random.default_rng(0)
    probes = np.concatenate([obs, rng.normal(scale=50.0, size=(500, obs.shape[1]))]).astype(np.float32)
    with set_exploration_type(ExplorationType.DETERMINISTIC), torch.no_grad():
        td = actor(TensorDict(observation=torch.as_tensor(probes), batch_size=[len(probes)]))
    torch_actions = td["action"].to(torch.float32).argmax(-1).numpy()
    assert len(np.unique(torch_actions)) > 1
    np.testing.assert_array_equal(loaded.act(probes), torch_actions)
    np.testing.assert_allclose(loaded.scores(probes), td["logits"].numpy(), rtol=1e-4, atol=1e-4)


def test_normaliser_floors_the_variance_of_constant_entries():
    obs = np.zeros((10, 3), dtype=np.float32)
    obs[:, 0] = np.arange(10)
    mean, var = normalizer_stats(obs)
    assert mean[0] == 4.5 and var[0] == pytest.approx(8.25) and var[1] == var[2] > 0


@pytest.fixture
def one_torch_thread():
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.mark.usefixtures("one_torch_thread")
def test_discriminator_separates_ref_from_random_transitions(small_demos):
    from socialzoo.train.gail import discriminator_loss, discriminator_step

    arrays, _ = load_demonstrations(small_demos)
    obs = torch.as_tensor(arrays["obs"])
    expert_act = torch.nn.functional.one_hot(torch.as_tensor(arrays["action"]), 4).float()
    generator = torch.Generator().manual_seed(0)
    random_act = torch.nn.functional.one_hot(torch.randint(0, 4, (len(obs),), generator=generator), 4).float()
    half = len(obs) // 2
    disc = Discriminator(obs.shape[1], (64, 64), normalizer_stats(arrays["obs"][:half]), generator)
    loss = discriminator_loss(disc)
    optim = torch.optim.Adam(loss.parameters(), lr=1e-3)
    losses = []
    for _ in range(200):
        idx = torch.randint(0, half, (128,), generator=generator)
        losses.append(
            discriminator_step(loss, optim, (obs[idx], expert_act[idx]), (obs[idx], random_act[idx]))
        )
    assert np.mean(losses[-20:]) < np.mean(losses[:20])
    # Held-out steps: D is higher on Ref's action than on a random one, for most of them.
    with torch.no_grad():
        d_expert = disc(obs[half:], expert_act[half:])[:, 0]
        d_random = disc(obs[half:], random_act[half:])[:, 0]
    differs = (expert_act[half:] != random_act[half:]).any(-1)
    assert (d_expert[differs] > d_random[differs]).float().mean() > 0.8
    assert d_expert.mean() > 0.6 and d_random[differs].mean() < 0.4
