"""Trainer arguments on the command line: one option per dataclass field, typed, with defaults."""

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import pytest

from socialzoo.cli.dataclass_args import add_dataclass_arguments, attribute_docs, dataclass_from_namespace


@dataclass(frozen=True, kw_only=True)
class Args:
    """Arguments of a toy trainer.

    Attributes:
        steps: environment steps to train for.
        lr: learning rate, spread over
            two lines.
        out: output folder.
        algo: which variant.
        sizes: hidden layer sizes.
        progress: show a progress bar.
        repeats: scenario repeats, or None for the default.
        env: EnvConfig overrides.
    """

    steps: int = 100
    lr: float = 3e-4
    out: Path = Path("runs/x")
    algo: Literal["a", "b"] = "a"
    sizes: tuple[int, ...] = (64, 64)
    progress: bool = True
    repeats: int | None = None
    env: dict = None  # type: ignore[assignment]


def _parse(argv):
    parser = argparse.ArgumentParser()
    add_dataclass_arguments(parser, Args)
    return dataclass_from_namespace(Args, parser.parse_args(argv))


def test_defaults_round_trip():
    assert _parse([]) == Args()


def test_every_type_parses():
    args = _parse(
        [
            "--steps",
            "7",
            "--lr",
            "0.1",
            "--out",
            "o",
            "--algo",
            "b",
            "--sizes",
            "8",
            "4",
            "--no-progress",
            "--repeats",
            "20",
            "--env",
            '{"max_steps": 10}',
        ]
    )
    assert args == Args(
        steps=7,
        lr=0.1,
        out=Path("o"),
        algo="b",
        sizes=(8, 4),
        progress=False,
        repeats=20,
        env={"max_steps": 10},
    )
    assert _parse(["--repeats", "none"]).repeats is None


@pytest.mark.parametrize("argv", [["--steps", "x"], ["--algo", "c"], ["--env", "[1]"], ["--env", "{"]])
def test_bad_values_are_usage_errors(argv):
    with pytest.raises(SystemExit):
        _parse(argv)


def test_help_comes_from_the_docstring():
    docs = attribute_docs(Args)
    assert docs["lr"] == "learning rate, spread over two lines."
    assert set(docs) == {"steps", "lr", "out", "algo", "sizes", "progress", "repeats", "env"}
