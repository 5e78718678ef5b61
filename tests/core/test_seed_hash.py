"""socialzoo.core.seed_hash: numpy's SeedSequence state word, bit for bit, for batches of seeds."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.core.seed_hash import seed_states, words
from socialzoo.scenarios.start_state import _NOISE_STREAM


def _numpy(seed: int, tail: int) -> np.uint64:
    return np.random.SeedSequence([seed, tail]).generate_state(1, dtype=np.uint64)[0]


def test_seed_states_are_numpy_seed_sequences() -> None:
    rng = np.random.default_rng(0)
    edges = [0, 1, 2, 2**32 - 1, 2**32, 2**32 + 1, 2**40 + 5, 2**63 - 1, 2**63, 2**64 - 1]
    seeds = edges + list(range(300)) + [int(x) for x in rng.integers(0, 2**64, 3000, dtype=np.uint64)]
    seeds += [int(x) for x in rng.integers(0, 2**32, 1000)]
    for tail in (_NOISE_STREAM, 0, 7, 2**32 - 1, 2**32, 2**64 - 1):
        got = seed_states(seeds, tail)
        assert got.dtype == np.uint64
        assert got.tolist() == [int(_numpy(s, tail)) for s in seeds], f"tail {tail}"
    # An array of seeds of any integer type gives the same.
    assert seed_states(np.array([3, 2**40]), 9).tolist() == seed_states([3, 2**40], 9).tolist()


def test_seed_states_refuse_what_numpy_refuses() -> None:
    with pytest.raises(ValueError, match="seeds must lie in"):
        seed_states([-1, 3], 5)
    with pytest.raises(ValueError, match="more than 2"):
        seed_states([1], 2**64)
    assert words(0) == [0] and words(2**32 + 3) == [3, 1]
