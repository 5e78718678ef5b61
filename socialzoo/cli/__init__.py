"""The `socialzoo` command: one entry point, one module per group of subcommands.

Each entry of COMMANDS names a module with a `register(subparsers)` function that adds its
subcommands; every subcommand sets `func(args) -> int` (the exit status).
"""

from __future__ import annotations

import argparse
import importlib
import logging
from collections.abc import Sequence

from socialzoo import __version__

# Modules that register subcommands, in the order `socialzoo --help` lists them.
COMMANDS: tuple[str, ...] = (
    "socialzoo.cli.benchmark_cmd",  # benchmark, demos
    "socialzoo.cli.demo_cmd",  # demo
    "socialzoo.cli.humans_cmd",  # compare-humans
    "socialzoo.cli.map_cmd",  # map list|show|import|validate
    "socialzoo.cli.replay_cmd",  # replay
    "socialzoo.cli.reproduce_cmd",  # reproduce
    "socialzoo.cli.steps_cmd",  # steps-to-ref
    "socialzoo.cli.train_cmd",  # train <trainer>
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every registered subcommand."""
    parser = argparse.ArgumentParser(
        prog="socialzoo",
        description="socialzoo: social-navigation simulator, benchmark and baselines.",
    )
    parser.add_argument("--version", action="version", version=f"socialzoo {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS:
        importlib.import_module(module).register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (2 for a usage or input error)."""
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO, format="%(levelname)s %(name)s: %(message)s"
    )
    return int(args.func(args))
