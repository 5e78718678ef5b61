"""`socialzoo humans report`: how each crowd model walks (speed, the fundamental diagram beside Weidmann's curve,
contacts, path length, time to goal), one figure per model and one table."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from socialzoo.cli import fail
from socialzoo.cli.arg_types import comma_list, out_dir, positive_int
from socialzoo.cli.dataclass_args import dataclass_from_namespace


def shipped_humans() -> str:
    """The path of the shipped learned humans' policy file.

    `socialzoo benchmark --humans` also reads "learned" alone as this file.
    """
    import socialzoo.agents

    return str(Path(socialzoo.agents.__file__).parent / "shipped" / "humans.safetensors")


def people_spec(spec: str) -> str:
    """A people spec; "learned" alone names the shipped learned humans."""
    return f"learned:{shipped_humans()}" if spec == "learned" else spec


def add_report(commands: Any) -> None:
    """Add `report` to the subcommands of `humans` (`commands`, their subparsers)."""
    report = commands.add_parser(
        "report",
        help="how each crowd model walks, one figure per model and one table",
        description="Walk each model's people on the map's validation scenarios without a robot and write "
        "DIR/report.md, report.csv (speed, local density, reach rate, time to goal, path length ratio, "
        "person-person and person-wall contacts per person-minute; learned models checked against the "
        "learned humans' targets: reach rate within 10% of the social force's, no more wall contacts), "
        "DIR/walk_<model>.png (speed histogram, speed against density beside Weidmann's 1993 curve, time "
        "to goal) and config.json.",
    )
    report.add_argument(
        "--humans",
        type=comma_list("people specs", people_spec),
        default=("sf", "orca", "groups"),
        help="comma-separated people specs: sf, orca, groups, learned (the shipped learned humans), "
        "learned:PATH, or mixes such as sf@0.5+orca@0.5 (default sf,orca,groups)",
    )
    report.add_argument("--map", default="gdc1", help="the map (its validation scenarios; default gdc1)")
    report.add_argument("--scenarios", type=positive_int, default=16, help="scenarios per model (default 16)")
    report.add_argument(
        "--seconds", type=float, default=60.0, help="how long the people walk, s (default 60)"
    )
    report.add_argument("--out", type=out_dir, required=True, help="output directory")
    report.add_argument("--no-figures", action="store_true", help="skip the figures (no matplotlib needed)")
    report.set_defaults(func=run_report)


def run_report(args: argparse.Namespace) -> int:
    """Run `socialzoo humans report`; returns the exit status."""
    from socialzoo.studies.human_report import HumanReportConfig, human_report

    try:
        config = dataclass_from_namespace(HumanReportConfig, args)
        _, files = human_report(config, args.out, figures=not args.no_figures)
    except (ValueError, FileNotFoundError) as err:
        return fail("humans report", err)
    print((args.out / "report.md").read_text())
    print(f"results in {args.out}: " + ", ".join(p.name for p in files))
    return 0
