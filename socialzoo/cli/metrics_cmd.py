"""`socialzoo metrics LOG.json [LOG2.json ...] [--out table.csv]`: Table I of the evaluation guidelines
(socialzoo.bench.guideline_metrics) for episode logs (socialzoo.bench.episode_log) of this simulator or any other."""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import out_file

# The columns of --out's CSV, in order: its help names them from here, so the two cannot drift apart.
CSV_COLUMNS = ("log", "label", "metric", "value", "unit")


def _non_negative(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text!r}")
    return value


def register(subparsers: Any) -> None:
    """Add `metrics`."""
    parser = subparsers.add_parser(
        "metrics",
        help=command_help("metrics"),
        description="Score episode logs (JSON in socialzoo's episode-log schema, "
        "socialzoo/bench/schemas/episode_log.schema.json; docs/guideline_metrics.md) with the metrics "
        "of Table I of the social-navigation evaluation guidelines (Francis et al., ACM THRI 2025): "
        "one table of metric, value and unit per log. Every log is checked first; a log that breaks "
        "the schema stops the command with its file and field, and nothing is written; so does an --out "
        "that names one of the logs.",
    )
    parser.add_argument("logs", nargs="+", type=Path, metavar="LOG.json", help="episode logs")
    parser.add_argument(
        "--out", type=out_file, help=f"also write every log's table to this CSV ({', '.join(CSV_COLUMNS)})"
    )
    parser.add_argument(
        "--personal-space", type=_non_negative, default=0.5, help="personal space, m (default 0.5)"
    )
    parser.add_argument(
        "--stall-speed", type=_non_negative, default=0.05, help="stalled below this speed, m/s (default 0.05)"
    )
    parser.add_argument(
        "--progress-time", type=_non_negative, default=10.0, help="failure-to-progress window, s (default 10)"
    )
    parser.add_argument(
        "--progress-distance",
        type=_non_negative,
        default=0.25,
        help="progress needed within the window, m (default 0.25)",
    )
    parser.set_defaults(func=run_metrics)


def _value(value: Any, digits: int) -> str:
    """A metric's value as text: yes/no for a flag, an integer, a float to `digits` decimals."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.{digits}f}"


def metric_rows(found: dict[str, Any]) -> list[tuple[str, str, str, str]]:
    """(name, label, value, unit) of each metric of a log, in registry order."""
    from socialzoo.core.metrics import metric

    rows = []
    for name, value in found.items():
        m = metric(name)
        rows.append((name, m.label, _value(value, m.digits), m.unit or "-"))
    return rows


def format_table(title: str, found: dict[str, Any]) -> str:
    """A log's metrics as a plain-text table under its title."""
    rows = [("metric", "", "value", "unit"), *metric_rows(found)]
    width = [max(len(r[i]) for r in rows) for i in (0, 2, 3)]
    lines = [title]
    for name, _, value, unit in rows:
        lines.append(f"  {name:<{width[0]}}  {value:>{width[1]}}  {unit}")
    return "\n".join(lines)


def _same_file(a: Path, b: Path) -> bool:
    """Whether paths a and b name one file (through links, ./ and ../ alike)."""
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them is not there: no file to lose
        return False


def run_metrics(args: argparse.Namespace) -> int:
    """Read and check every log, then print (and write) their tables; 2 on a bad log or option."""
    from socialzoo.bench.episode_log import EpisodeLogError, log_metrics, read_episode_log
    from socialzoo.bench.guideline_metrics import GuidelineParams

    try:
        params = GuidelineParams(
            personal_space=args.personal_space,
            stall_speed=args.stall_speed,
            progress_time=args.progress_time,
            progress_distance=args.progress_distance,
        )
    except ValueError as err:
        return fail("metrics", err)
    if args.out is not None and any(_same_file(args.out, log) for log in args.logs):
        return fail("metrics", f"--out {args.out} is one of the logs: the table would be written over it")
    scored = []
    try:
        for path in args.logs:  # every log is read and checked before anything is printed or written
            log = read_episode_log(path)
            scored.append((path, log, log_metrics(log, params, str(path))))
    except EpisodeLogError as err:
        return fail("metrics", f"invalid episode log: {err}")
    rows: list[dict[str, Any]] = []
    for path, log, found in scored:
        title = f"{path}" + (f" ({log['label']})" if log.get("label") else "")
        print(format_table(title, found))
        for name, _, _shown, unit in metric_rows(found):
            raw = found[name]
            rows.append(
                {
                    "log": str(path),
                    "label": log.get("label", ""),
                    "metric": name,
                    "value": repr(raw) if isinstance(raw, float) else str(int(raw)),
                    "unit": "" if unit == "-" else unit,
                }
            )
    if args.out is not None:
        from socialzoo.bench.tables import write_csv

        write_csv(rows, args.out, list(CSV_COLUMNS), lineterminator="\n")
        print(f"wrote {args.out}")
    return 0
