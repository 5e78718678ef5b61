"""Compiled kernels: numba's `njit` with the options every socialzoo kernel shares."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

import numba
import numpy as np

F = TypeVar("F", bound=Callable[..., Any])


def kernel(fn: F) -> F:
    """Compile `fn` in nopython mode with socialzoo's shared options.

    - cache=True: compiled code is written next to the module (or to NUMBA_CACHE_DIR), so only the
      first import on a machine pays the compile time.
    - error_model="numpy": division follows IEEE (inf, nan) like numpy instead of raising, which
      also lets numba skip the zero checks.
    - fastmath stays off: results must not depend on the compiler's reassociation.
    """
    # The dispatcher is called exactly like fn: callers keep fn's signature.
    return cast(F, numba.njit(cache=True, nogil=True, error_model="numpy")(fn))


@kernel
def _block_sum(values, start, count):  # type: ignore[no-untyped-def]
    """numpy's sum of a run of at most 128 values: eight running sums, paired, then the rest in turn."""
    if count < 8:
        total = 0.0
        for i in range(count):
            total += values[start + i]
        return total
    r0, r1, r2, r3 = values[start], values[start + 1], values[start + 2], values[start + 3]
    r4, r5, r6, r7 = values[start + 4], values[start + 5], values[start + 6], values[start + 7]
    i = 8
    while i < count - count % 8:
        r0 += values[start + i]
        r1 += values[start + i + 1]
        r2 += values[start + i + 2]
        r3 += values[start + i + 3]
        r4 += values[start + i + 4]
        r5 += values[start + i + 5]
        r6 += values[start + i + 6]
        r7 += values[start + i + 7]
        i += 8
    total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < count:
        total += values[start + i]
        i += 1
    return total


@kernel
def numpy_sum(values, start, count):  # type: ignore[no-untyped-def]
    """The sum of values[start : start + count] (float64) added in numpy's own order (its pairwise
    summation: runs of up to 128 summed by _block_sum, longer runs split at half, rounded down to a
    multiple of 8, and the halves' sums added), so a kernel that replaces `array.sum()` returns the
    same bits. The halving walks an explicit stack: numba's cached code cannot call itself."""
    if count <= 128:
        return _block_sum(values, start, count)
    # Depth-first over the halving tree: each run's start, count and how many halves are summed.
    starts, counts = np.empty(64, dtype=np.int64), np.empty(64, dtype=np.int64)
    done = np.zeros(64, dtype=np.int64)
    sums = np.empty(64)
    top, held = 0, 0
    starts[0], counts[0] = start, count
    while top >= 0:
        s, c = starts[top], counts[top]
        if c <= 128:
            sums[held] = _block_sum(values, s, c)
            held += 1
            top -= 1
            continue
        half = c // 2
        half -= half % 8
        if done[top] == 2:  # both halves summed: the two last sums are its halves'
            held -= 1
            sums[held - 1] = sums[held - 1] + sums[held]
            top -= 1
            continue
        first = done[top] == 0
        done[top] += 1
        top += 1
        starts[top] = s if first else s + half
        counts[top] = half if first else c - half
        done[top] = 0
    return sums[0]
