"""`socialzoo study <name>`: single experiments of socialzoo.studies that have no other command
(`socialzoo study ref-tradeoff`: socialzoo.studies.ref_tradeoff)."""

from __future__ import annotations

import argparse
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import positive_int
from socialzoo.cli.dataclass_args import dataclass_from_namespace


def register(subparsers: Any) -> None:
    """Add `study` and its subcommands."""
    parser = subparsers.add_parser("study", help=command_help("study"), description=command_help("study"))
    studies = parser.add_subparsers(dest="study", required=True, metavar="STUDY")
    tradeoff = studies.add_parser(
        "ref-tradeoff",
        help="Ref's parameters against its success and blame, and learned policies beside them",
        description="Run Ref with every setting of corridor half-width, lookahead margin and heading "
        "tolerance (18 settings) on the first --trials validation scenarios of --map and print a "
        "Markdown table: success, blame, and whether another setting has at least its success with "
        "less blame. --learned adds each learned policy with its Halt score shifted by each of "
        "--halt-offsets (socialzoo.studies.ref_tradeoff).",
    )
    tradeoff.add_argument("--trials", type=positive_int, default=400, help="validation scenarios per setting")
    tradeoff.add_argument("--workers", type=positive_int, default=2, help="settings evaluated side by side")
    tradeoff.add_argument("--map", default="gdc1", help="map whose validation set is driven")
    tradeoff.add_argument(
        "--learned",
        nargs="*",
        default=[],
        metavar="NAME[:FILE]",
        help="learned MlpPolicy files to trace beside Ref (a name alone: its shipped file, e.g. dagger)",
    )
    tradeoff.add_argument(
        "--halt-offsets",
        type=_numbers,
        default=(-1.0, -0.5, 0.0, 0.5, 1.0),
        help="comma-separated Halt score offsets of each learned policy (a negative first one: "
        "--halt-offsets=-1,0,1; default -1,-0.5,0,0.5,1)",
    )
    tradeoff.set_defaults(func=run_ref_tradeoff_command)


def _numbers(text: str) -> tuple[float, ...]:
    """argparse type: comma-separated numbers (the error names the text)."""
    try:
        return tuple(float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def run_ref_tradeoff_command(args: argparse.Namespace) -> int:
    """Run `socialzoo study ref-tradeoff`; returns the exit status (2 for bad arguments)."""
    from socialzoo.studies.ref_tradeoff import RefTradeoffConfig, run_ref_tradeoff, tradeoff_table

    try:
        result = run_ref_tradeoff(dataclass_from_namespace(RefTradeoffConfig, args))
    except (ValueError, KeyError, FileNotFoundError) as err:
        return fail("study ref-tradeoff", err)
    print(tradeoff_table(result), end="")
    return 0
