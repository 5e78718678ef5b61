"""The attention-over-people network: permutation-invariant, masked, and the numpy policy computes
what the torch network computes."""

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from socialzoo.agents.crowd_policy import CrowdAttentionPolicy  # noqa: E402
from socialzoo.env.policy_file import PolicyFileError  # noqa: E402
from socialzoo.train.crowd_attention import CrowdAttention  # noqa: E402

SLOTS = 4


def _obs(rng, n, present, signals=False):
    r, p = (9, 8) if signals else (6, 7)
    obs = rng.normal(size=(n, r + (p + 1) * SLOTS)).astype(np.float32)
    mask = np.arange(SLOTS)[None, :] < np.asarray(present)[:, None]
    obs[:, r + p * SLOTS :] = mask
    obs[:, r : r + p * SLOTS].reshape(n, SLOTS, p)[~mask] = 0.0
    if signals:  # gestures 0, 1, 2 in the present slots
        obs[:, r : r + p * SLOTS].reshape(n, SLOTS, p)[..., -1] = rng.integers(0, 3, (n, SLOTS)) * mask
    return obs


def _net(signals=False):
    torch.manual_seed(0)
    return CrowdAttention(SLOTS, embed=(16, 12), value=(10, 8), attention=(9,), signals=signals)


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


@pytest.mark.parametrize("signals", [False, True])
@pytest.mark.parametrize("action", ["discrete", "continuous"])
def test_the_numpy_policy_computes_the_torch_network(action, signals):
    net, rng = _net(signals), np.random.default_rng(2)
    robot_dim = 9 if signals else 6
    head = torch.nn.Sequential(torch.nn.Linear(robot_dim + 8, 7), torch.nn.Tanh())
    out = torch.nn.Linear(7, 81 if action == "discrete" else 2)
    tensors = {f"attention.{k}": v.detach().numpy() for k, v in net.state_dict().items()}
    tensors.update({f"policy.{k}": v.detach().numpy() for k, v in head.state_dict().items()})
    tensors.update({f"action.{k}": v.detach().numpy() for k, v in out.state_dict().items()})
    observation = {"slots": SLOTS, **({"signals": True} if signals else {})}  # no key: the old layout
    header = {"network": {"action": action, "activation": "tanh"}, "observation": observation}
    policy = CrowdAttentionPolicy(tensors, header)
    obs = _obs(rng, 5, [4, 3, 1, 0, 2], signals)
    assert policy.observation_size == net.observation_size == obs.shape[1]
    expected = out(head(net(torch.as_tensor(obs)))).detach().numpy()
    np.testing.assert_allclose(policy.action_output(obs), expected, rtol=1e-5, atol=1e-5)
    actions = policy.act(obs)
    if action == "discrete":
        np.testing.assert_array_equal(actions, expected.argmax(-1))
    else:
        np.testing.assert_allclose(actions, np.clip(expected, -1, 1), rtol=1e-5, atol=1e-5)
    with pytest.raises(ValueError, match="observations must be"):
        policy.act(obs[:, :-1])
    assert policy.task_overrides == {"action": action, **({"signals": True} if signals else {})}


def test_the_signal_features_reach_the_network_and_a_layout_mismatch_is_refused():
    net, rng = _net(signals=True), np.random.default_rng(3)
    obs = _obs(rng, 2, [3, 3], signals=True)
    changed = obs.copy()
    changed[0, 9 + 8 * 1 + 7] = 2.0 - changed[0, 9 + 8 * 1 + 7]  # slot 1's gesture
    changed[1, 6:9] += 1.0  # the nearest door
    before, after = net(torch.as_tensor(obs)).detach().numpy(), net(torch.as_tensor(changed)).detach().numpy()
    # Both reach the pooled crowd feature (the door through every person's pair with the robot).
    assert not np.allclose(before[0, 9:], after[0, 9:]) and not np.allclose(before[1, 9:], after[1, 9:])
    tensors = {f"attention.{k}": v.detach().numpy() for k, v in net.state_dict().items()}
    tensors.update(
        {"action.weight": np.zeros((81, 9 + 8), np.float32), "action.bias": np.zeros(81, np.float32)}
    )
    header = {"network": {"action": "discrete", "activation": "tanh"}, "observation": {"slots": SLOTS}}
    with pytest.raises(PolicyFileError, match=r"not 13.*without signals"):
        CrowdAttentionPolicy(tensors, header)
    with pytest.raises(PolicyFileError, match="signals must be true or false"):
        CrowdAttentionPolicy(tensors, {**header, "observation": {"slots": SLOTS, "signals": "yes"}})
