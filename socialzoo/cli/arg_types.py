"""Argument types shared by the subcommands."""

from __future__ import annotations

import argparse


def _int_at_least(text: str, low: int, what: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
    if value < low:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer of at least 1 (the error names the value)."""
    return _int_at_least(text, 1, "a positive integer")


def count(text: str) -> int:
    """argparse type: an integer of at least 0 (the error names the value)."""
    return _int_at_least(text, 0, "an integer >= 0")


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
