"""Start-up time of the `socialzoo` command: wall time of `socialzoo --help` and other help pages,
each a fresh process (best and median of --repeats runs), beside `python -c "import socialzoo"`.

Run: python benchmarks/cli_startup.py [--repeats 7] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time

COMMANDS: tuple[tuple[str, list[str]], ...] = (
    ("python -c 'import socialzoo'", [sys.executable, "-c", "import socialzoo"]),
    ("socialzoo --help", [sys.executable, "-m", "socialzoo", "--help"]),
    ("socialzoo map check --help", [sys.executable, "-m", "socialzoo", "map", "check", "--help"]),
    ("socialzoo benchmark --help", [sys.executable, "-m", "socialzoo", "benchmark", "--help"]),
    ("socialzoo train --help", [sys.executable, "-m", "socialzoo", "train", "--help"]),
    ("socialzoo train ppo --help", [sys.executable, "-m", "socialzoo", "train", "ppo", "--help"]),
)


def wall_times(command: list[str], repeats: int) -> list[float]:
    """Wall time of `repeats` runs of `command`, s (one untimed run first warms the file cache)."""
    subprocess.run(command, check=True, capture_output=True)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return times


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=7, help="timed runs per command")
    p.add_argument("--json", action="store_true", help="print one JSON object per line")
    args = p.parse_args()
    if args.repeats < 1:
        p.error(f"--repeats must be at least 1, got {args.repeats}")
    for name, command in COMMANDS:
        times = wall_times(command, args.repeats)
        figure = {
            "command": name,
            "best_s": round(min(times), 3),
            "median_s": round(statistics.median(times), 3),
        }
        print(
            json.dumps(figure)
            if args.json
            else f"{name:34s} best {figure['best_s']:.3f} s  median {figure['median_s']:.3f} s"
        )


if __name__ == "__main__":
    main()
