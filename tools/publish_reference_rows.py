"""Put a later `socialzoo reproduce --reference` run's rows into the published reproduction.

    socialzoo reproduce --out DIR --seeds 5 --seed-trials 500 --only demos --reference goal_distance_x_only
    python tools/publish_reference_rows.py --from DIR

DIR's results/ (collected by the run) must share the published run's settings hash. Its
reference.csv (every quirk set the work folder holds), its reference trainings' records and its
reference part's timing replace the published ones (socialzoo.reproduce.rerun_rows.replace_reference_rows);
the tables, figures and REPRODUCTION.md are then drawn again from results/reproduction/. --root is
the repository (default: the current folder).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from socialzoo.reproduce.publish import PUBLISHED_DIR, redraw_published
from socialzoo.reproduce.rerun_rows import replace_reference_rows
from socialzoo.reproduce.results import RESULTS_DIR


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--from", dest="source", type=Path, required=True, help="the reference run's --out DIR"
    )
    parser.add_argument("--root", type=Path, default=Path("."))
    args = parser.parse_args()
    for path in replace_reference_rows(args.root / PUBLISHED_DIR, args.source / RESULTS_DIR):
        print("rewrote", path)
    print("wrote", redraw_published(args.root))


if __name__ == "__main__":
    main()
