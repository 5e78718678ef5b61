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
