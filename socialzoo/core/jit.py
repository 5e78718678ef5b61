"""Compiled kernels: numba's `njit` with the options every socialzoo kernel shares.

A kernel replaces a chain of small numpy calls whose per-call overhead dominated a step (at B = 1
a step was ~150 numpy calls) or whose (B, pairs) temporaries dominated memory traffic (at B = 256).
Kernels loop over the batch inside compiled code and take plain arrays, so the batched-array
world is unchanged around them; benchmarks/ shows what each one bought (see DEVELOPERS.md).

- cache=True: compiled code is written next to the module (or to NUMBA_CACHE_DIR), so only the
  first import on a machine pays the compile time.
- error_model="numpy": division follows IEEE (inf, nan) like numpy instead of raising, which
  also lets numba skip the zero checks.
- fastmath stays off: results must not depend on the compiler's reassociation.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

import numba

F = TypeVar("F", bound=Callable[..., Any])


def kernel(fn: F) -> F:
    """Compile `fn` in nopython mode with socialzoo's shared options."""
    # The dispatcher is called exactly like fn: callers keep fn's signature.
    return cast(F, numba.njit(cache=True, nogil=True, error_model="numpy")(fn))
