"""numpy's SeedSequence hash, compiled over a batch of seeds."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from socialzoo.core.jit import kernel

_MASK = 0xFFFFFFFF
_POOL = 4
_INIT_A, _MULT_A = 0x43B0D7E5, 0x931E8875
_INIT_B, _MULT_B = 0x8B51F9DD, 0x58F38DED
_MIX_L, _MIX_R = 0xCA01F9DD, 0x4973F715


def words(value: int) -> list[int]:
    """The 32-bit words numpy makes of a non-negative int, least significant first ([0] for 0)."""
    out = []
    while True:
        out.append(value & _MASK)
        value >>= 32
        if value == 0:
            return out


def seed_states(seeds: Sequence[int] | np.ndarray, tail: int) -> np.ndarray:
    """(N,) uint64: SeedSequence([seed, tail]).generate_state(1, dtype=np.uint64)[0] of each seed.

    Bit for bit numpy's (tests/core/test_seed_hash.py checks it against numpy over tens of
    thousands of seeds, the 32- and 64-bit edges included). A reset builds one SeedSequence per
    row for its noise key, about 20 microseconds each in Python, a large part of a recorded
    scene's reset; compiled, a batch of rows costs about one microsecond.

    The algorithm is numpy's (numpy/random/bit_generator.pyx, after Melissa O'Neill's
    seed_seq_fe): the entropy's 32-bit words hashed into a pool of four, the pool mixed, and the
    state words drawn from it. Here the entropy is the seed's words (one, or two above 2**32 - 1)
    followed by the tail's, at most four words in all (the pool's size), which is all a noise key
    needs.

    Raises:
        ValueError: a seed outside [0, 2**64) or a tail of more than two words.
    """
    tail_words = np.array(words(tail), dtype=np.int64)
    if len(tail_words) > _POOL - 2:
        raise ValueError(f"seed_states: the tail {tail} has more than {_POOL - 2} 32-bit words")
    if not (isinstance(seeds, np.ndarray) and seeds.dtype == np.uint64):
        values = [int(seed) for seed in seeds]
        bad = [seed for seed in values if not 0 <= seed < 2**64]
        if bad:
            raise ValueError(f"seed_states: seeds must lie in [0, 2**64), got {bad[0]}")
        seeds = np.array(values, dtype=np.uint64)
    out = np.empty(len(seeds), dtype=np.uint64)
    _seed_states(seeds, tail_words, out)
    return out


@kernel
def _seed_states(seeds, tail, out):  # type: ignore[no-untyped-def]
    """out[i] = the SeedSequence state word of entropy [low, high (if not 0), *tail], low and high
    the 32-bit words of seeds[i], in int64 arithmetic masked to 32 bits (products wrap; their low
    32 bits are the uint32 result). The words are split here, in uint64, where a reset's few seeds
    cost less than the numpy calls that split them."""
    entropy = np.zeros(_POOL, dtype=np.int64)
    pool = np.zeros(_POOL, dtype=np.int64)
    state = np.zeros(2, dtype=np.int64)
    for i in range(out.shape[0]):
        low = np.int64(seeds[i] & np.uint64(_MASK))
        high = np.int64(seeds[i] >> np.uint64(32))
        n = 0
        entropy[n] = low
        n += 1
        if high != 0:
            entropy[n] = high
            n += 1
        for w in range(tail.shape[0]):
            entropy[n] = tail[w]
            n += 1
        constant = _INIT_A
        for k in range(_POOL):  # hash the entropy (zeros past its end) into the pool
            value = ((entropy[k] if k < n else 0) ^ constant) & _MASK
            constant = (constant * _MULT_A) & _MASK
            value = (value * constant) & _MASK
            pool[k] = value ^ (value >> 16)
        for source in range(_POOL):  # mix every word into every other
            for target in range(_POOL):
                if source != target:
                    value = (pool[source] ^ constant) & _MASK
                    constant = (constant * _MULT_A) & _MASK
                    value = (value * constant) & _MASK
                    value ^= value >> 16
                    mixed = (_MIX_L * pool[target] - _MIX_R * value) & _MASK
                    pool[target] = mixed ^ (mixed >> 16)
        constant = _INIT_B
        for k in range(2):  # two 32-bit state words, the low one first
            value = (pool[k] ^ constant) & _MASK
            constant = (constant * _MULT_B) & _MASK
            value = (value * constant) & _MASK
            state[k] = value ^ (value >> 16)
        out[i] = np.uint64(state[0]) | (np.uint64(state[1]) << np.uint64(32))
