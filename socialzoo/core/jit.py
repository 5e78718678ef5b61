"""Compiled kernels: numba's `njit` with the options every socialzoo kernel shares."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

import numba

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
