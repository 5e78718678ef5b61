"""How the training part of `socialzoo reproduce --seeds K` scales with its workers: the same
trainings (PPO and DQN, several seeds, as socialzoo.reproduce.parts trains them) one after the
other, side by side in local processes, and as Ray tasks on a local Ray with `--workers` CPUs.

Every mode trains the same runs into its own fresh folder (nothing is reused between modes); the
figure is the wall time of `socialzoo.reproduce.backend.run_tasks` and its speed-up over one after
the other. Each training uses one torch thread, as in reproduce. Run on an otherwise idle machine:
other jobs take the second core away from the side-by-side modes.

Run: python benchmarks/training_scaling.py [--steps 12000] [--seeds 2] [--workers 2] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

from _common import positive_int

MODES = {"serial": ("local", 1), "local": ("local", None), "ray": ("ray", None)}


def trainings(root: Path, steps: int, seeds: int) -> list[tuple[str, object]]:
    """PPO and DQN of seeds 0..seeds-1, `steps` env steps each, one checkpoint, no evaluations."""
    from socialzoo.train import trainer_args

    def args(algo: str, seed: int) -> object:
        out = root / f"{algo}-s{seed}"
        return trainer_args(algo)(
            out=out, seed=seed, total_steps=steps, checkpoint_every=steps, progress=False
        )

    return [(algo, args(algo, seed)) for seed in range(seeds) for algo in ("ppo", "dqn")]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--steps", type=positive_int, default=12_000, help="env steps per training")
    p.add_argument("--seeds", type=positive_int, default=2, help="seeds per learner (PPO and DQN)")
    p.add_argument(
        "--workers", type=positive_int, default=2, help="processes / Ray CPUs of the parallel modes"
    )
    p.add_argument(
        "--modes",
        default="serial,local,ray",
        help=f"comma-separated, of {','.join(MODES)} (run in that order)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object per line")
    args = p.parse_args()
    modes = args.modes.split(",")
    unknown = sorted(set(modes) - set(MODES))
    if unknown:
        p.error(f"unknown modes {unknown}; known: {', '.join(MODES)}")
    # In MODES' order, serial first: every later mode's speed-up is over it (given after it, it had none).
    modes = [mode for mode in MODES if mode in modes]
    os.environ.setdefault("SOCIALZOO_PROGRESS", "off")

    from socialzoo.reproduce.backend import run_tasks
    from socialzoo.reproduce.parts import train_task

    baseline = None
    for mode in modes:
        backend, workers = MODES[mode]
        workers = workers or args.workers
        with tempfile.TemporaryDirectory(prefix=f"scaling-{mode}-") as tmp:
            items = trainings(Path(tmp), args.steps, args.seeds)
            start = time.perf_counter()
            run_tasks(train_task, items, backend=backend, workers=workers)
            seconds = time.perf_counter() - start
        baseline = baseline or (seconds if mode == "serial" else None)
        figure = {
            "mode": mode,
            "backend": backend,
            "workers": workers,
            "trainings": len(items),
            "steps_each": args.steps,
            "wall_s": round(seconds, 1),
            "speedup_over_serial": round(baseline / seconds, 2) if baseline else None,
        }
        if args.json:
            print(json.dumps(figure))
        else:
            speedup = f"{figure['speedup_over_serial']:.2f}x" if baseline else "-"
            print(
                f"{mode:<7} {backend:<6} workers={workers}  {len(items)} trainings x {args.steps:,} steps  "
                f"{seconds:8.1f} s  speed-up {speedup}"
            )
        sys.stdout.flush()


if __name__ == "__main__":
    main()
