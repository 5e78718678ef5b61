"""The attention-over-people network: permutation-invariant, masked, and the numpy policy computes
what the torch network computes."""

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from socialzoo.agents.crowd_policy import CrowdAttentionPolicy  # noqa: E402
from socialzoo.train.crowd_attention import CrowdAttention, attention_state  # noqa: E402

SLOTS = 4


def _obs(rng, n, present):
    obs = rng.normal(size=(n, 6 + 8 * SLOTS)).astype(np.float32)
    mask = np.arange(SLOTS)[None, :] < np.asarray(present)[:, None]
    obs[:, 6 + 7 * SLOTS :] = mask
    obs[:, 6 : 6 + 7 * SLOTS].reshape(n, SLOTS, 7)[~mask] = 0.0
    return obs


def _net():
    torch.manual_seed(0)
    return CrowdAttention(SLOTS, embed=(16, 12), value=(10, 8), attention=(9,))


def test_the_crowd_feature_ignores_empty_slots_and_the_order_of_people():
    net, rng = _net(), np.random.default_rng(1)
    obs = _obs(rng, 3, [4, 2, 0])
    out = net(torch.as_tensor(obs)).detach().numpy()
    shuffled = obs.copy()
    people = shuffled[0, 6 : 6 + 7 * SLOTS].reshape(SLOTS, 7)
    shuffled[0, 6 : 6 + 7 * SLOTS] = people[[2, 0, 3, 1]].ravel()
    np.testing.assert_allclose(
        net(torch.as_tensor(shuffled)).detach().numpy()[0], out[0], rtol=1e-5, atol=1e-6
    )
    changed = obs.copy()
    changed[1, 6 + 7 * 3 : 6 + 7 * 4] = 99.0  # an empty slot's numbers do not matter
    np.testing.assert_allclose(net(torch.as_tensor(changed)).detach().numpy()[1], out[1], rtol=1e-6)
    np.testing.assert_array_equal(out[2, 6:], 0.0)  # nobody present: no crowd feature
    assert np.all(np.isfinite(out))


@pytest.mark.parametrize("action", ["discrete", "continuous"])
def test_the_numpy_policy_computes_the_torch_network(action):
    net, rng = _net(), np.random.default_rng(2)
    head = torch.nn.Sequential(torch.nn.Linear(6 + 8, 7), torch.nn.Tanh())
    out = torch.nn.Linear(7, 81 if action == "discrete" else 2)
    tensors = attention_state(net)
    tensors.update({f"policy.{k}": v.detach().numpy() for k, v in head.state_dict().items()})
    tensors.update({f"action.{k}": v.detach().numpy() for k, v in out.state_dict().items()})
    header = {"network": {"action": action, "activation": "tanh"}, "observation": {"slots": SLOTS}}
    policy = CrowdAttentionPolicy(tensors, header)
    obs = _obs(rng, 5, [4, 3, 1, 0, 2])
    expected = out(head(net(torch.as_tensor(obs)))).detach().numpy()
    np.testing.assert_allclose(policy.action_output(obs), expected, rtol=1e-5, atol=1e-5)
    actions = policy.act(obs)
    if action == "discrete":
        np.testing.assert_array_equal(actions, expected.argmax(-1))
    else:
        np.testing.assert_allclose(actions, np.clip(expected, -1, 1), rtol=1e-5, atol=1e-5)
    with pytest.raises(ValueError, match="observations must be"):
        policy.act(obs[:, :-1])
