"""Where two torch trainings of one seed part: the same BC training under several CPU kernel paths.

    python tools/kernel_paths.py --demos DEMOS.npz --out DIR [--steps 155400] [--every 10]
        [--trials 500] [--paths as-is,again,aten-default,mkl-compatible,threads-2] [--csv FILE]
        [--trainer-args "--epochs 1 --min-updates 10"]

Issue 38 saw the torch-trained rows (BC, GAIL, DQN) move when the protocol was re-run on another
machine of the same kind, while one machine trains one seed to the same weights twice. The likely
cause is the CPU code path of torch's kernels, which torch and MKL pick at run time from the CPU's
instruction sets. This tool makes those choices on one machine: it trains BC (`socialzoo train bc`,
one seed, checkpoints every --every updates) once per kernel path, each in its own process with the
path's environment (torch reads ATEN_CPU_CAPABILITY and MKL reads MKL_CBWR when they load), then
reports, against the first path, the first checkpoint whose weights differ, the largest weight
difference at the end, and each final policy's success on the first --trials gdc1-test scenarios
(`socialzoo benchmark`). Finished trainings and stored trials are reused on a rerun. --csv writes
the table as a reproduction results file (results/reproduction/results/kernel_paths.csv), which
REPRODUCTION.md's "What a re-run may differ by" shows.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from safetensors.numpy import load_file

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


def train(
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
    print(f"{name}: {' '.join(f'{k}={v}' for k, v in env_vars.items())} {' '.join(command[3:])}", flush=True)
    subprocess.run(command, check=True, env={**os.environ, **env_vars})
    return policy


def _weights(path: Path) -> dict[str, np.ndarray]:
    return load_file(str(path))


def compare(base: Path, other: Path) -> tuple[str, float]:
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


def evaluate(policies: dict[str, Path], trials: int, out: Path) -> dict[str, float]:
    """Each final policy's success (%) on the first `trials` gdc1-test scenarios."""
    from socialzoo.reproduce.results import read_csv

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
    rows = {str(r["policy"]): r for r in read_csv(out / "benchmark" / "summary.csv")}
    return {name: 100 * float(rows[f"bc:{p}"]["success_rate"]) for name, p in policies.items()}


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--demos", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--steps", type=int, default=155_400)
    parser.add_argument("--every", type=int, default=10, help="checkpoint every this many updates")
    parser.add_argument("--trials", type=int, default=500, help="gdc1-test scenarios per policy (0: none)")
    parser.add_argument("--paths", default=",".join(KERNEL_PATHS))
    parser.add_argument("--csv", type=Path, help="also write the table here")
    parser.add_argument(
        "--trainer-args",
        default="",
        help='more `socialzoo train bc` arguments, e.g. "--epochs 1 --min-updates 10"',
    )
    args = parser.parse_args()
    names = [n for n in args.paths.split(",") if n]
    unknown = [n for n in names if n not in KERNEL_PATHS]
    if unknown:
        parser.error(f"unknown kernel path(s) {unknown}; known: {list(KERNEL_PATHS)}")
    more = tuple(args.trainer_args.split())
    policies = {name: train(name, args.demos, args.steps, args.every, args.out, more) for name in names}
    success = evaluate(policies, args.trials, args.out) if args.trials else {}
    base = args.out / names[0]
    rows = []
    for name, policy in policies.items():
        first, largest = compare(base, policy.parent)
        env_vars, extra = KERNEL_PATHS[name]
        record = json.loads((policy.parent / "run.json").read_text())
        rows.append(
            {
                "kernel_path": name,
                "settings": " ".join([*(f"{k}={v}" for k, v in env_vars.items()), *extra]),
                "demonstration_steps": args.steps,
                "updates": record["results"]["updates"],
                "checkpoint_every": args.every,
                "first_differing_update": first,
                "largest_weight_difference": largest,
                "trials": args.trials,
                "success_pct": success.get(name, float("nan")),
            }
        )
    print(f"\nBC, {args.steps} demonstration steps, seed 0; against {names[0]}:\n")
    print(
        "| kernel path | settings | updates | first checkpoint that differs (updates) | largest weight "
        f"difference | gdc1-test success % ({args.trials}) |"
    )
    print("|---|---|---:|---|---:|---:|")
    for r in rows:
        print(
            f"| {r['kernel_path']} | {r['settings']} | {r['updates']} | {r['first_differing_update']} | "
            f"{r['largest_weight_difference']:.3g} | {r['success_pct']:.1f} |"
        )
    if args.csv:  # appended to the rows of other runs (other sizes) already there
        from socialzoo.bench.tables import write_csv
        from socialzoo.reproduce.results import read_csv

        old = read_csv(args.csv) if args.csv.is_file() else []
        old = [r for r in old if int(r["demonstration_steps"]) != args.steps]
        write_csv([*old, *rows], args.csv)


if __name__ == "__main__":
    main()
