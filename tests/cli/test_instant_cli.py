"""The command starts at once: `socialzoo --help` lists every subcommand from the table alone, and
a subcommand's help imports no heavy library (torch, ray, matplotlib, Stable-Baselines3).

Times are measured by benchmarks/cli_startup.py, never here; this checks what gets imported.
"""

import argparse
import subprocess
import sys

import pytest

from socialzoo.cli import COMMANDS, build_parser, main

HEAVY = ("torch", "ray", "matplotlib", "stable_baselines3", "torchrl", "tensordict")


def imported_modules(*words: str) -> set[str]:
    """Top-level names of the modules `python -X importtime -m socialzoo WORDS` imports."""
    run = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "socialzoo", *words],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    names = set()
    for line in run.stderr.splitlines():
        if line.startswith("import time:") and "|" in line:
            names.add(line.rsplit("|", 1)[1].strip().split(".")[0])
    assert "socialzoo" in names  # the report was read
    return names


@pytest.mark.parametrize(
    "words",
    [
        ("--help",),
        ("map", "check", "--help"),
        ("benchmark", "--help"),
        ("train", "--help"),
        ("replay", "--help"),
        ("humans", "compare", "--help"),
    ],
    ids=" ".join,
)
def test_help_imports_no_heavy_library(words):
    assert imported_modules(*words) & set(HEAVY) == set()


def test_top_level_help_imports_no_compiled_world():
    # The table is enough to list the subcommands: not even the numba kernels load.
    assert {"numba", "scipy"} & imported_modules("--help") == set()


def test_every_subcommand_is_listed_and_registered_by_its_module(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--help"])
    assert exit_info.value.code == 0
    listing = capsys.readouterr().out
    for name, (_, help_line) in COMMANDS.items():
        assert name in listing and help_line[:30] in " ".join(listing.split())
    # Registered in full, each module adds exactly the subcommands the table gives it.
    full = build_parser()
    subparsers = next(a for a in full._actions if a.dest == "command")
    assert list(subparsers.choices) == list(COMMANDS)


def test_a_subcommand_registers_its_options_when_asked_for(capsys):
    with pytest.raises(SystemExit):
        main(["map", "check", "--help"])
    assert "--picture" in capsys.readouterr().out
    with pytest.raises(SystemExit) as exit_info:
        main(["no-such-command"])
    assert exit_info.value.code == 2 and "invalid choice" in capsys.readouterr().err


def _parsers(parser):
    """`parser` and every subcommand parser below it."""
    yield parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                yield from _parsers(sub)


def test_help_texts_show_a_percent_sign_once():
    # argparse %-formats an option's help but not a description: "%%" in a description shows as is.
    for parser in _parsers(build_parser()):
        text = parser.format_help()
        assert "%%" not in text, f"{parser.prog} --help shows '%%'"
