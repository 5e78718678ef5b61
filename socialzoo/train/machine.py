"""The machine facts that decide torch-trained numbers, for every run record: the CPU (model and the instruction-set
flags that pick torch's and the BLAS's kernels), torch and its BLAS/oneDNN build, thread counts, numpy, Python."""

from __future__ import annotations

import os
import platform
import re
import sys
from typing import Any

# The CPU flags that choose the kernel paths of MKL, oneDNN and OpenBLAS (the rest of
# /proc/cpuinfo's flags do not change floating-point results).
KERNEL_FLAGS: tuple[str, ...] = (
    "sse4_2",
    "avx",
    "avx2",
    "fma",
    "f16c",
    "avx512f",
    "avx512dq",
    "avx512bw",
    "avx512vl",
    "avx512_vnni",
    "avx512_bf16",
    "amx_bf16",
    "amx_tile",
    "asimd",
    "sve",
)
# Environment variables that set thread counts or pin a BLAS code path.
THREAD_VARIABLES: tuple[str, ...] = (
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "NUMBA_NUM_THREADS",
    "MKL_CBWR",
    "MKL_ENABLE_INSTRUCTIONS",
    "ONEDNN_MAX_CPU_ISA",
    "DNNL_MAX_CPU_ISA",
    "ATEN_CPU_CAPABILITY",
)


def cpu_facts(cpuinfo: str | None = None) -> dict[str, Any]:
    """The CPU: model name, vendor, logical CPUs and the kernel-choosing flags it has.

    Args:
        cpuinfo: the text of /proc/cpuinfo (None: read it; absent on macOS and Windows, where
            platform's processor name stands in).
    """
    if cpuinfo is None:
        try:
            with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
                cpuinfo = f.read()
        except OSError:
            cpuinfo = ""
    fields: dict[str, str] = {}
    for line in cpuinfo.splitlines():
        key, sep, value = line.partition(":")
        if not sep:
            if fields:
                break  # the first processor's block is enough
            continue
        fields.setdefault(key.strip(), value.strip())
    flags = set((fields.get("flags") or fields.get("Features") or "").split())
    return {
        "model": fields.get("model name")
        or fields.get("Model")
        or platform.processor()
        or platform.machine(),
        "vendor": fields.get("vendor_id", ""),
        "machine": platform.machine(),
        "logical_cpus": os.cpu_count(),
        "kernel_flags": [f for f in KERNEL_FLAGS if f in flags],
    }


def torch_facts() -> dict[str, Any] | None:
    """torch's version, its build (BLAS, LAPACK, oneDNN, OpenMP, the CPU capability its kernels
    dispatch to) and thread counts; None when torch is not installed."""
    try:
        import torch
    except ImportError:
        return None
    config = torch.__config__.show()
    build: dict[str, str] = {}
    for key, pattern in (
        ("cpu_capability", r"CPU capability usage:\s*(\S+)"),
        ("blas", r"BLAS_INFO=([^,\s]+)"),
        ("lapack", r"LAPACK_INFO=([^,\s]+)"),
        ("mkl", r"Intel\(R\) (?:oneAPI )?Math Kernel Library Version ([^\n]+)"),
        ("onednn", r"Intel\(R\) MKL-DNN (v[^\s(]+)|oneDNN (v[^\s(]+)"),
        ("openmp", r"OpenMP (\d+)"),
        ("compiler", r"- (GCC [\d.]+|clang [\d.]+|MSVC [\d.]+)"),
    ):
        match = re.search(pattern, config)
        if match:
            build[key] = next(g for g in match.groups() if g).strip()
    return {
        "version": torch.__version__,
        "build": build,
        "mkldnn_available": bool(torch.backends.mkldnn.is_available()),
        "mkl_available": bool(torch.backends.mkl.is_available()),
        "threads": torch.get_num_threads(),
        "interop_threads": torch.get_num_interop_threads(),
        "deterministic_algorithms": bool(torch.are_deterministic_algorithms_enabled()),
    }


def numpy_facts() -> dict[str, Any]:
    """numpy's version and the BLAS/LAPACK it was built with (numpy.show_config as a dict)."""
    import numpy as np

    facts: dict[str, Any] = {"version": np.__version__}
    try:
        shown: Any = np.show_config(mode="dicts")  # numpy >= 1.26
    except TypeError:
        return facts
    config: dict[str, Any] = shown if isinstance(shown, dict) else {}
    deps: dict[str, Any] = config.get("Build Dependencies") or {}
    for key in ("blas", "lapack"):
        dep: dict[str, Any] = deps.get(key) or {}
        if dep:
            facts[key] = {k: dep.get(k) for k in ("name", "version", "openblas configuration") if dep.get(k)}
    simd: dict[str, Any] = config.get("SIMD Extensions") or {}
    if simd:
        facts["simd_found"] = list(simd.get("found", []))
    return facts


def machine_facts() -> dict[str, Any]:
    """Everything above, plain JSON: "cpu", "platform", "python", "torch" (None without torch),
    "numpy", "env" (the THREAD_VARIABLES that are set).

    Why: two trainings of one seed on one machine give the same weights (tests/train/test_determinism.py); on
    another CPU or library build, the same code may run other kernels (AVX-512 against AVX2 paths of
    MKL/oneDNN/OpenBLAS sum in another order) and the floating-point sums part after a few updates. These
    facts are what a reader needs to tell whether a re-run ran the same kernels.
    """
    return {
        "cpu": cpu_facts(),
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "torch": torch_facts(),
        "numpy": numpy_facts(),
        "env": {name: os.environ[name] for name in THREAD_VARIABLES if name in os.environ},
    }
