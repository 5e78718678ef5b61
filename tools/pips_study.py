"""PIPS beyond the paper: success against demonstration steps, with and without windowing.

    python tools/pips_study.py --demos DEMOS.npz [--root runs/pips_study] [--out results/pips_study]
        [--steps 500,1000,3500,10000] [--windows 20,0] [--trials 200] [--seed 0] [--workers 1]

Synthesises one program per (steps, window) with the project's trainer (socialzoo.train.pips,
seed recorded in each pips.train.json) from DEMOS (`socialzoo demos`, training scenarios), then
evaluates each on the first TRIALS scenarios of the gdc1 validation set (gdc1-val) and writes
pips_study.{csv,md,png} into --out. Both halves resume: finished cells are not synthesised again
and stored trials are read back. --skip-training evaluates the programs already under --root;
--skip-evaluation only synthesises.
"""

from __future__ import annotations

import argparse
import logging
import time
from pathlib import Path

from socialzoo.studies.pips_study import (
    STUDY_STEPS,
    STUDY_TRIALS,
    STUDY_WINDOWS,
    find_study_programs,
    run_pips_study,
)
from socialzoo.studies.pips_study_training import PipsStudyConfig, train_pips_study


def _ints(text: str) -> tuple[int, ...]:
    return tuple(int(v) for v in text.split(",") if v)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--demos", type=Path, required=True)
    parser.add_argument("--root", type=Path, default=Path("runs/pips_study"))
    parser.add_argument("--out", type=Path, default=Path("results/pips_study"))
    parser.add_argument("--steps", type=_ints, default=STUDY_STEPS)
    parser.add_argument("--windows", type=_ints, default=STUDY_WINDOWS)
    parser.add_argument("--trials", type=int, default=STUDY_TRIALS)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--batch-size", type=int, default=100)
    parser.add_argument("--skip-training", action="store_true")
    parser.add_argument("--skip-evaluation", action="store_true")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    start = time.perf_counter()
    if args.skip_training:
        programs = {
            k: p
            for k, p in find_study_programs(args.root).items()
            if k[0] in args.steps and k[1] in args.windows
        }
    else:
        config = PipsStudyConfig(
            demos=args.demos, root=args.root, steps=args.steps, windows=args.windows, seed=args.seed
        )
        programs = train_pips_study(config)
    print(f"synthesis done after {time.perf_counter() - start:.0f} s", flush=True)
    if args.skip_evaluation:
        return
    result = run_pips_study(
        programs,
        args.out,
        trials=args.trials,
        workers=args.workers,
        batch_size=args.batch_size,
        progress=not args.no_progress,
    )
    print((args.out / "pips_study.md").read_text())
    print(
        f"{result.computed} trials run, {result.reused} read back; {time.perf_counter() - start:.0f} s in all",
        flush=True,
    )


if __name__ == "__main__":
    main()
