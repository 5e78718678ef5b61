"""Throughput of two versions of socialzoo side by side: a benchmark script run in each tree in turn
for several rounds, and the ratio new / old of every figure per round and overall (min, median, max).

The machine's speed varies from day to day and with other load, so only figures measured in the same
run, interleaved, compare. OLD and NEW are folders (a checkout) or git revisions (checked out in a
temporary worktree, removed at the end). Each tree runs with its own PYTHONPATH and its own
NUMBA_CACHE_DIR, and one untimed run first compiles its kernels. The script is the NEW tree's copy
unless --scripts says otherwise (`own`: each tree its own copy, `old`: the old copy in both, or a
folder); it must print one JSON object per line with --json, as every script in benchmarks/ does.
On a machine that other jobs load, --cpu times by CPU time: the script runs with time.perf_counter
replaced by time.process_time (and BLAS on one thread), so the time other jobs take is not counted.

Run: python benchmarks/compare_commits.py 912376b . env_throughput.py [--rounds 3] [-- --seconds 2]
(options after -- go to the script)
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _common import positive_int

REPO = Path(__file__).resolve().parent.parent
KEY_NUMBERS = ("batch", "people", "envs")  # integer fields that name a case rather than measure it
# Runs a script (the first argument) with the wall clock replaced by the process's CPU time.
CPU_CLOCK = (
    "import runpy, sys, time; time.perf_counter = time.process_time; sys.argv = sys.argv[1:]; "
    "runpy.run_path(sys.argv[0], run_name='__main__')"
)


def tree(spec: str, scratch: Path, side: str) -> Path:
    """The folder of `spec`: an existing folder as it is, else a git revision checked out under `scratch`
    in a folder named by its `side` (old and new may be one revision: a run that measures the noise)."""
    if Path(spec).is_dir():
        return Path(spec).resolve()
    folder = scratch / f"tree-{side}"
    added = subprocess.run(
        ["git", "-C", str(REPO), "worktree", "add", "--detach", str(folder), spec],
        capture_output=True,
        text=True,
    )
    if added.returncode:
        sys.exit(f"{spec!r} is neither a folder nor a revision of {REPO}: {added.stderr.strip()}")
    return folder


def run(folder: Path, script: Path, args: list[str], cache: Path, metric: str, cpu: bool) -> dict[str, float]:
    """One run of `script` with `folder` on the path: {figure key: its `metric`}."""
    env = dict(os.environ, PYTHONPATH=str(folder), NUMBA_CACHE_DIR=str(cache))
    command = [sys.executable, str(script), "--json", *args]
    if cpu:
        env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
        command[1:1] = ["-c", CPU_CLOCK]
    out = subprocess.run(
        command,
        env=env,
        cwd=script.parent,
        capture_output=True,
        text=True,
    )
    if out.returncode:
        sys.exit(f"{script} failed in {folder}:\n{out.stderr}")
    figures = {}
    for line in out.stdout.splitlines():
        if not line.startswith("{"):
            continue
        fig = json.loads(line)
        if metric not in fig:
            sys.exit(
                f"{script.name} prints no {metric!r} (its fields: {', '.join(fig)}): choose one with --metric"
            )
        if fig[metric] is None:  # not measured in this run (harness_throughput's body when N <= B)
            continue
        key = " ".join(
            str(v) for k, v in fig.items() if isinstance(v, str) or (k in KEY_NUMBERS and isinstance(v, int))
        )
        figures[key] = float(fig[metric])
    return figures


def number(value: float) -> str:
    """A figure to print: rates whole, small figures (seconds, MiB) with 4 significant digits."""
    return f"{value:,.0f}" if abs(value) >= 100 else f"{value:.4g}"


def spread(values: list[float]) -> str:
    return f"{statistics.median(values):.3f} ({min(values):.3f}-{max(values):.3f})"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("old", help="folder or git revision of the baseline")
    p.add_argument("new", help="folder or git revision measured against it")
    p.add_argument("script", help="a script of benchmarks/ (name or path)")
    p.add_argument("--rounds", type=positive_int, default=3)
    p.add_argument(
        "--scripts", default="new", help="whose copy of the script: new, old, own (each its own) or a folder"
    )
    p.add_argument(
        "--metric", default="env_steps_per_s", help="the JSON field compared (default env_steps_per_s)"
    )
    p.add_argument(
        "--cpu", action="store_true", help="time by CPU time, BLAS on one thread (on a loaded machine)"
    )
    p.add_argument("--no-warmup", action="store_true", help="skip the untimed compiling run")
    p.add_argument("--cache", type=Path, help="folder of the numba caches (default: a temporary one)")
    argv = sys.argv[1:]
    split = argv.index("--") if "--" in argv else len(argv)
    args, script_args = p.parse_args(argv[:split]), argv[split + 1 :]  # after --: the script's options
    with tempfile.TemporaryDirectory(prefix="compare-") as tmp:
        scratch, trees = Path(tmp), {}
        try:
            for side, spec in (("old", args.old), ("new", args.new)):
                trees[side] = tree(spec, scratch, side)
            cache_root = args.cache or scratch
            caches = {side: cache_root / f"numba-{side}" for side in trees}
            name = Path(args.script).name
            folders = {side: trees[side] / "benchmarks" for side in trees}
            if args.scripts in ("new", "old"):
                folders = dict.fromkeys(trees, folders[args.scripts])
            elif args.scripts != "own":
                folders = dict.fromkeys(trees, Path(args.scripts).resolve())
            scripts = {side: folders[side] / name for side in trees}
            print(
                f"old {trees['old']}\nnew {trees['new']}\nscript {name} {' '.join(script_args)}\n"
                f"figure {args.metric} (old, new) and new/old",
                flush=True,
            )
            if not args.no_warmup:
                for side in trees:
                    run(trees[side], scripts[side], script_args, caches[side], args.metric, args.cpu)
            ratios: dict[str, list[float]] = {}
            for r in range(args.rounds):
                # Alternate which goes first, so that a drift in the machine's speed hits both alike.
                order = ("old", "new") if r % 2 == 0 else ("new", "old")
                rates = {
                    side: run(trees[side], scripts[side], script_args, caches[side], args.metric, args.cpu)
                    for side in order
                }
                for key, old in rates["old"].items():
                    if key in rates["new"] and old > 0:
                        ratio = rates["new"][key] / old
                        ratios.setdefault(key, []).append(ratio)
                        print(
                            f"round {r + 1}  {key:<52} old {number(old):>12}  new {number(rates['new'][key]):>12}  "
                            f"new/old {ratio:.3f}",
                            flush=True,
                        )
            print(f"\nnew/old over {args.rounds} rounds: median (min-max)")
            for key, values in ratios.items():
                print(f"  {key:<52} {spread(values)}")
        finally:
            for folder in trees.values():
                if folder.is_relative_to(scratch):
                    subprocess.run(
                        ["git", "-C", str(REPO), "worktree", "remove", "--force", str(folder)],
                        check=False,
                        capture_output=True,
                    )


if __name__ == "__main__":
    main()
