"""Argument types shared by the subcommands."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any


def at_least(low: int, what: str = "") -> Callable[[str], int]:
    """argparse type: an integer of at least `low` (the error names the value and says `what`,
    by default "an integer >= low")."""
    what = what or f"an integer >= {low}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return value

    return parse


positive_int = at_least(1, "a positive integer")
count = at_least(0)


def given(args: argparse.Namespace, *names: str) -> dict[str, Any]:
    """The options among `names` that the command line set (not None), by name (for --max-steps:
    the env overrides)."""
    return {name: getattr(args, name) for name in names if getattr(args, name) is not None}


def split_commas(text: str) -> tuple[str, ...]:
    """The items of comma-separated text, stripped, empty ones left out."""
    return tuple(item.strip() for item in text.split(",") if item.strip())


def comma_list(what: str, convert: Callable[[str], str] = str) -> Callable[[str], tuple[str, ...]]:
    """argparse type: comma-separated items (split_commas), each passed through `convert`; an error
    ("expected comma-separated WHAT") names text without any."""

    def parse(text: str) -> tuple[str, ...]:
        items = tuple(convert(item) for item in split_commas(text))
        if not items:
            raise argparse.ArgumentTypeError(f"expected comma-separated {what}, got {text!r}")
        return items

    return parse


def add_backend_arguments(parser: argparse.ArgumentParser, what: str) -> None:
    """--backend, --address, --workers and --batch-size of the evaluation runner (`what` runs there)."""
    parser.add_argument("--backend", choices=("local", "ray"), default="local", help=f"where {what} run")
    parser.add_argument("--address", default=None, help="Ray cluster address (with --backend ray)")
    parser.add_argument(
        "--workers",
        type=positive_int,
        default=None,
        help="local processes (default 2), or Ray chunks (default: one per cluster CPU)",
    )
    parser.add_argument(
        "--batch-size", type=positive_int, default=64, help="env rows stepped together per worker"
    )
