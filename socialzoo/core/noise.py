"""Counter-based random numbers: noise that is a pure function of (row key, step, index)."""

from __future__ import annotations

import numpy as np

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)


def splitmix64(x: np.ndarray) -> np.ndarray:
    """The splitmix64 finaliser applied elementwise to uint64 values."""
    with np.errstate(over="ignore"):
        z = x + _GOLDEN
        z = (z ^ (z >> np.uint64(30))) * _MIX1
        z = (z ^ (z >> np.uint64(27))) * _MIX2
        return z ^ (z >> np.uint64(31))


def uniform(key: np.ndarray, step: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Uniform numbers in (0, 1) of shape (B, *shape) for rows with keys (B,) at steps (B,)."""
    count = int(np.prod(shape))
    counter = np.arange(count, dtype=np.uint64).reshape(shape)
    row = splitmix64(key.astype(np.uint64) ^ splitmix64(step.astype(np.uint64)))
    with np.errstate(over="ignore"):
        bits = splitmix64(row.reshape((-1,) + (1,) * len(shape)) + counter * _GOLDEN)
    return ((bits >> np.uint64(11)).astype(np.float64) + 0.5) / float(1 << 53)


def normal(key: np.ndarray, step: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Standard normal numbers of shape (B, *shape) (Box-Muller on two counter streams)."""
    u = uniform(key, step, (2,) + shape)
    return np.sqrt(-2.0 * np.log(u[:, 0])) * np.cos(2.0 * np.pi * u[:, 1])
