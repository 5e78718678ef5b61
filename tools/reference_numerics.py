"""The numerics the recorded rollout digests are checked under: numpy's SIMD kernels no wider than
AVX2 and OpenBLAS's Haswell kernels, set in the environment before numpy is first imported.

numpy chooses its math kernels (exp, sin, arctan2, hypot, ...) by the CPU it runs on: with
AVX-512 some of them round a result differently in the last bit than the AVX2 ones do, and
OpenBLAS chooses its matrix kernels the same way. A seeded rollout is bit for bit the same on one
machine, every time; its digest is not the same on every machine. The golden digests
(tests/env/golden_rollouts.json and the digests kept in other tests) were recorded on a machine
without AVX-512, so tests/conftest.py and tools/rollout_digests.py run under these settings: a
digest then means the same on any x86-64 machine with AVX2, with or without AVX-512 (one with
AVX-512 differed in 36 of the 51 cases without them, in none with them).

This file imports nothing that imports numpy: it must run before numpy does.
"""

from __future__ import annotations

import os
import platform
from collections.abc import MutableMapping

# numpy's dispatch targets wider than AVX2: X86_V4 and AVX512_* (numpy 2.4 names; the older names
# for numpy 2.3 and before). numpy ignores a name it does not dispatch to.
NUMPY_DISABLED = (
    "X86_V4 AVX512_ICL AVX512_SPR AVX512F AVX512CD AVX512_KNL AVX512_KNM AVX512_SKX AVX512_CLX AVX512_CNL"
)
OPENBLAS_CORE = "Haswell"


def reference_settings() -> dict[str, str]:
    """The environment variables of the reference numerics on this machine (none off x86-64: the
    names are x86's, and another architecture's digests differ anyway)."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return {}
    return {"NPY_DISABLE_CPU_FEATURES": NUMPY_DISABLED, "OPENBLAS_CORETYPE": OPENBLAS_CORE}


def use_reference_numerics(environ: MutableMapping[str, str] = os.environ) -> bool:
    """Set the reference settings in `environ` where they are not set already (a setting of the
    user's own wins). Returns False if numpy is imported already: then they take no effect in this
    process (only in the processes it starts)."""
    import sys

    for name, value in reference_settings().items():
        environ.setdefault(name, value)
    return "numpy" not in sys.modules


def numpy_follows_reference() -> bool:
    """Whether this process's numpy runs without the dispatch targets the reference leaves out
    (imports numpy)."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:  # numpy 1.x
        from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__  # type: ignore[no-redef]

    if not reference_settings():
        return True
    disabled = set(NUMPY_DISABLED.split())
    return not any(__cpu_features__.get(name, False) for name in __cpu_dispatch__ if name in disabled)
