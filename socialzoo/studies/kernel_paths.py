"""Where two torch trainings of one seed part: one BC training under several CPU kernel paths."""

from __future__ import annotations

import json
import logging
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

logger = logging.getLogger(__name__)

# name: (environment variables, extra trainer arguments). "again" repeats "as-is": one machine,
# one path, the same weights (tests/train/test_determinism.py checks it on a small run).
KERNEL_PATHS: dict[str, tuple[dict[str, str], tuple[str, ...]]] = {
    "as-is": ({}, ()),
    "again": ({}, ()),
    # ATen's scalar kernels instead of its AVX2 ones (activations, Adam's element-wise updates).
    "aten-default": ({"ATEN_CPU_CAPABILITY": "default"}, ()),
    # MKL's reproducible SSE2 code path for its GEMMs (the Linear layers).
    "mkl-compatible": ({"MKL_CBWR": "COMPATIBLE"}, ()),
    # MKL's AVX2 path named explicitly: on an AVX2 CPU the same as as-is, unless MKL chose another.
    "mkl-avx2": ({"MKL_CBWR": "AVX2"}, ()),
    # Two torch threads split the GEMMs' sums.
    "threads-2": ({}, ("--threads", "2")),
}


def train_under_path(
    name: str, demos: Path, steps: int, every: int, out: Path, trainer_args: tuple[str, ...] = ()
) -> Path:
    """One BC training under kernel path `name` into out/<name>/ (skipped when finished)."""
    env_vars, extra = KERNEL_PATHS[name]
    folder = out / name
    policy = folder / "bc.safetensors"
    if policy.is_file():
        return policy
    command = [
        sys.executable,
        "-m",
        "socialzoo",
        "train",
        "bc",
        "--demos",
        str(demos),
        "--steps",
        str(steps),
        "--seed",
        "0",
        "--out",
        str(folder),
        "--checkpoint-every",
        str(every),
        "--no-progress",
        *trainer_args,
        *extra,
    ]
    logger.info("%s: %s %s", name, " ".join(f"{k}={v}" for k, v in env_vars.items()), " ".join(command[3:]))
    subprocess.run(command, check=True, env={**os.environ, **env_vars})
    return policy


def _weights(path: Path) -> dict[str, np.ndarray]:
    from safetensors.numpy import load_file

    return load_file(str(path))


def compare_weights(base: Path, other: Path) -> tuple[str, float]:
    """(the first checkpoint of `other` whose weights differ from `base`'s, or "none"; the largest
    absolute weight difference of the final policies)."""
    first = "none"
    for checkpoint in sorted((base / "checkpoints").glob("step_*.safetensors")):
        a, b = _weights(checkpoint), _weights(other / "checkpoints" / checkpoint.name)
        if any(not np.array_equal(a[k], b[k]) for k in a):
            first = str(int(checkpoint.stem.split("_")[1]))
            break
    a, b = _weights(base / "bc.safetensors"), _weights(other / "bc.safetensors")
    return first, max(float(np.max(np.abs(a[k] - b[k]))) for k in a)


def evaluate_success(policies: dict[str, Path], trials: int, out: Path) -> dict[str, float]:
    """Each final policy's success (%) on the first `trials` gdc1-test scenarios."""
    from socialzoo.bench.tables import read_summary_csv

    specs = ",".join(f"bc:{p}" for p in policies.values())
    subprocess.run(
        [
            sys.executable,
            "-m",
            "socialzoo",
            "benchmark",
            "--policies",
            specs,
            "--maps",
            "gdc1",
            "--trials",
            str(trials),
            "--out",
            str(out / "benchmark"),
            "--no-progress",
        ],
        check=True,
    )
    rows = {str(r["policy"]): r for r in read_summary_csv(out / "benchmark" / "summary.csv")}
    return {name: 100 * float(rows[f"bc:{p}"]["success_rate"]) for name, p in policies.items()}


def kernel_path_rows(
    demos: Path,
    out: Path,
    names: Sequence[str],
    *,
    steps: int = 155_400,
    every: int = 10,
    trials: int = 500,
    trainer_args: tuple[str, ...] = (),
) -> list[dict[str, Any]]:
    """One row per kernel path: its settings, the training's updates, the first checkpoint whose
    weights differ from the first path's ("none": none does), the largest final weight difference,
    and the final policy's success (%) on the first `trials` gdc1-test scenarios (NaN for 0).

    Why: issue 38 saw the torch-trained rows (BC, GAIL, DQN) move when the protocol was re-run on another
    machine of the same kind, while one machine trains one seed to the same weights twice. The likely cause is
    the CPU code path of torch's kernels, which torch and MKL pick at run time from the CPU's instruction
    sets. This makes those choices on one machine: it trains BC (`socialzoo train bc`, one seed) once per
    kernel path, each in its own process with the path's environment (torch reads ATEN_CPU_CAPABILITY and MKL
    reads MKL_CBWR when they load), and compares each against the first path (`socialzoo benchmark` for the
    success). Finished trainings and stored trials are reused. tools/kernel_paths.py is its command line.

    Raises:
        ValueError: an unknown kernel path (the known ones are named).
    """
    unknown = [n for n in names if n not in KERNEL_PATHS]
    if unknown:
        raise ValueError(f"unknown kernel path(s) {unknown}; known: {list(KERNEL_PATHS)}")
    policies = {name: train_under_path(name, demos, steps, every, out, trainer_args) for name in names}
    success = evaluate_success(policies, trials, out) if trials else {}
    base = out / names[0]
    rows = []
    for name, policy in policies.items():
        first, largest = compare_weights(base, policy.parent)
        env_vars, extra = KERNEL_PATHS[name]
        record = json.loads((policy.parent / "run.json").read_text())
        rows.append(
            {
                "kernel_path": name,
                "settings": " ".join([*(f"{k}={v}" for k, v in env_vars.items()), *extra]),
                "demonstration_steps": steps,
                "updates": record["results"]["updates"],
                "checkpoint_every": every,
                "first_differing_update": first,
                "largest_weight_difference": largest,
                "trials": trials,
                "success_pct": success.get(name, float("nan")),
            }
        )
    return rows
