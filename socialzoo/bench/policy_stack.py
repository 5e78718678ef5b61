"""Many learned policies of one network shape acting in one batch as stacked weights, so a step costs one
gathered product per layer instead of one small product per policy."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.policy_file import mlp_forward


@contextlib.contextmanager
def single_blas_thread() -> Iterator[None]:
    """Limit numpy's BLAS to one thread inside the block (threadpoolctl).

    The evaluation runs with one BLAS thread: its products are small, and OpenBLAS's own threads, on
    a machine whose cores are already busy with the evaluation's worker processes, cost more in
    waiting than they save (measured: 64 x 256 by 256 x 256 took 27 ms with the default threads
    beside other work, 1.2 ms with one).
    """
    with threadpool_limits(limits=1, user_api="blas"):
        yield


def stack_key(policy: Any) -> tuple[Any, ...] | None:
    """What policies must share to be stacked (network shape, activation, normalisation), or None
    for a policy that cannot be (not an MlpPolicy)."""
    if type(policy) is not MlpPolicy:
        return None
    norm = policy.normalizer
    return (
        policy.activation,
        tuple(w.shape for w, _ in policy.layers),
        None if norm is None else (norm.clip, norm.epsilon),
    )


class MlpStack:
    """Greedy actions of several MlpPolicy of the same `stack_key` at once.

    E.g. the checkpoints of a training run (the RL curves evaluate 43 of them side by side). A stack
    gives exactly the actions its policies give one by one (tests check it on recorded
    observations): the normalisation is the same float64 arithmetic, and each row's products are the
    same float32 dot products, taken row by row (np.matmul over a stack of 1-row matrices).

    Args:
        policies: the policies (index i in `act`'s `which` is policies[i]).
    """

    def __init__(self, policies: Sequence[MlpPolicy]) -> None:
        keys = {stack_key(p) for p in policies}
        if len(keys) != 1 or None in keys:
            raise ValueError(f"MlpStack: policies of one network shape and normalisation needed, got {keys}")
        first = policies[0]
        self.activation = first.activation
        self.weights = [np.stack([p.layers[i][0].T for p in policies]) for i in range(len(first.layers))]
        self.biases = [np.stack([p.layers[i][1] for p in policies]) for i in range(len(first.layers))]
        norm = first.normalizer
        self.normalized = norm is not None
        if norm is not None:
            self.mean = np.stack([p.normalizer.mean for p in policies])  # type: ignore[union-attr]
            self.scale = np.stack([np.sqrt(p.normalizer.var + norm.epsilon) for p in policies])  # type: ignore[union-attr]
            self.clip = norm.clip
        self.input_size = first.input_size

    def act(self, obs: np.ndarray, which: np.ndarray) -> np.ndarray:
        """(n,) int64 greedy actions of rows `obs` (n, D), row j taken by policy which[j]."""
        x = np.asarray(obs, dtype=np.float32)
        if self.normalized:
            x = np.clip((x - self.mean[which]) / self.scale[which], -self.clip, self.clip).astype(np.float32)
        # Row j as a 1-row matrix times its policy's weights (n, in, out).
        layers = [(w[which], b[which][:, None, :]) for w, b in zip(self.weights, self.biases, strict=True)]
        h = mlp_forward(x[:, None, :], layers, self.activation)
        return np.argmax(h[:, 0, :], axis=1).astype(np.int64)
