"""Stacked learned policies give exactly the actions of the policies one by one."""

import itertools

import numpy as np
import pytest

from socialzoo.agents.mlp import MlpPolicy, ObservationNormalizer
from socialzoo.bench.policy_stack import MlpStack, single_blas_thread, stack_key


def policy(seed, sizes=(107, 64, 64, 4), activation="tanh", normalized=True):
    rng = np.random.default_rng(seed)
    layers = [
        (rng.normal(size=(o, i)) / np.sqrt(i), rng.normal(size=o)) for i, o in itertools.pairwise(sizes)
    ]
    norm = ObservationNormalizer(rng.normal(size=sizes[0]), rng.uniform(0.1, 4, sizes[0]), 10.0, 1e-8)
    return MlpPolicy("ppo", layers, activation, {"layout": "paper"}, norm if normalized else None)


@pytest.mark.parametrize("activation,normalized", [("tanh", True), ("relu", False)])
def test_stack_acts_as_each_policy(activation, normalized):
    policies = [policy(k, activation=activation, normalized=normalized) for k in range(5)]
    rng = np.random.default_rng(9)
    obs = (3 * rng.normal(size=(4000, 107))).astype(np.float32)
    which = rng.integers(0, 5, size=4000)
    stacked = MlpStack(policies).act(obs, which)
    for k, p in enumerate(policies):
        rows = which == k
        assert np.array_equal(stacked[rows], p.act(obs[rows]))  # as the runner calls it: its rows
    assert np.array_equal(
        stacked[:50], [policies[w].act(obs[i : i + 1])[0] for i, w in enumerate(which[:50])]
    )


def test_only_policies_of_one_shape_stack():
    assert stack_key(policy(0)) == stack_key(policy(1)) != stack_key(policy(2, sizes=(107, 32, 4)))
    assert stack_key(policy(0)) != stack_key(policy(0, normalized=False))
    assert stack_key(object()) is None
    with pytest.raises(ValueError, match="one network shape"):
        MlpStack([policy(0), policy(1, sizes=(107, 32, 4))])


def test_single_blas_thread_limits_blas_inside_only():
    threadpoolctl = pytest.importorskip("threadpoolctl")
    before = [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]
    with single_blas_thread():
        assert all(i["num_threads"] == 1 for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas")
    assert [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"] == before
