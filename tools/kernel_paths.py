"""Where two torch trainings of one seed part: the same BC training under several CPU kernel paths
(socialzoo.studies.kernel_paths).

    python tools/kernel_paths.py --demos DEMOS.npz --out DIR [--steps 155400] [--every 10]
        [--trials 500] [--paths as-is,again,aten-default,mkl-compatible,threads-2] [--csv FILE]
        [--trainer-args "--epochs 1 --min-updates 10"]

Prints the table; --csv also writes it as a reproduction results file
(results/reproduction/results/kernel_paths.csv, rows of other --steps kept), which REPRODUCTION.md's
"What a re-run may differ by" shows.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from socialzoo.studies.kernel_paths import KERNEL_PATHS, kernel_path_rows


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
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    names = [n for n in args.paths.split(",") if n]
    try:
        rows = kernel_path_rows(
            args.demos,
            args.out,
            names,
            steps=args.steps,
            every=args.every,
            trials=args.trials,
            trainer_args=tuple(args.trainer_args.split()),
        )
    except ValueError as err:
        parser.error(str(err))
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
