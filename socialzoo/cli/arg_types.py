"""Argument types shared by the subcommands."""

from __future__ import annotations

import argparse
import json
import math
import os
from collections.abc import Callable
from pathlib import Path
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


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0 (a length, a time); the error names the value."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def out_path(text: str) -> Path:
    """argparse type of an output path (--out): one the command can create, checked before it runs
    (the error names the path and the folder in its way), so a long run does not end in a traceback."""
    path = Path(text)
    folder = next((p for p in path.parents if p.exists()), Path("."))
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: {str(folder)!r} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: no permission to write in {str(folder)!r}")
    return path


def out_dir(text: str) -> Path:
    """argparse type of an output folder (--out DIR): out_path, and not the name of an existing file
    (the command would end in a FileExistsError traceback when it makes the folder)."""
    path = out_path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: it is a file, not a folder")
    return path


def out_file(text: str) -> Path:
    """argparse type of an output file (--out FILE): out_path, and not the name of an existing folder
    (the command would end in an IsADirectoryError traceback when it writes the file, after its run)."""
    path = out_path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: it is a folder, not a file")
    return path


def given(args: argparse.Namespace, *names: str) -> dict[str, Any]:
    """The options among `names` that the command line set (not None), by name (for --max-steps:
    the env overrides)."""
    return {name: getattr(args, name) for name in names if getattr(args, name) is not None}


def given_flags(args: argparse.Namespace, *names: str) -> str:
    """The options among `names` that the command line set, as "--a, --b" ("" for none)."""
    return ", ".join(f"--{name.replace('_', '-')}" for name in given(args, *names))


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


def config_field(text: str) -> tuple[str, Any]:
    """argparse type of --task-config: KEY=VALUE, the value read as JSON where it parses (numbers,
    true, null, {"models": "orca"}) and kept as text otherwise (family=recorded_zara1)."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    try:
        return key.strip(), json.loads(value)
    except json.JSONDecodeError:
        return key.strip(), value


def task_config(fields: list[tuple[str, Any]] | None) -> dict[str, Any]:
    """The --task-config fields as a task config's overrides; a dotted key sets a nested config's
    field (reward.discomfort_dist=0.3 -> {"reward": {"discomfort_dist": 0.3}}). family=MODULE:NAME
    imports MODULE, which registers the family NAME, as --family does (catalogue.family_name).

    Raises:
        ValueError: a key given a value and nested fields at once, or a MODULE:NAME that MODULE
            cannot be imported or registers no family NAME.
    """
    from socialzoo.scenarios.catalogue import family_name

    config: dict[str, Any] = {}
    for key, value in fields or ():
        *parents, name = key.split(".")
        node = config
        for parent in parents:
            node = node.setdefault(parent, {})
            if not isinstance(node, dict):
                raise ValueError(f"--task-config {key}: {parent} is given a value and fields at once")
        node[name] = value
    if isinstance(config.get("family"), str):
        config["family"] = family_name(config["family"])
    return config


def add_task_config_argument(parser: argparse.ArgumentParser) -> None:
    """--task-config KEY=VALUE (repeatable): a registered task id's config fields."""
    parser.add_argument(
        "--task-config",
        type=config_field,
        action="append",
        metavar="KEY=VALUE",
        help="a config field of the task ids (repeatable; VALUE read as JSON where it parses, a dotted KEY "
        "sets a nested field), e.g. family=recorded_zara1 (MODULE:NAME for a family that MODULE registers), "
        "humans=hybrid:orca, "
        'humans=\'{"models": "hybrid:orca", "react_radius": 3}\', reward.discomfort_dist=0.3',
    )


def add_case_arguments(parser: argparse.ArgumentParser) -> None:
    """--env, --case, --split and --task-config: one fixed case of any registered task id, where one
    episode is played (demo, replay) instead of a benchmark map's scenario."""
    parser.add_argument(
        "--env",
        default=None,
        help="a registered task id (socialzoo/CrowdNav-v1, any task's id; MODULE:ID for an id that MODULE "
        "registers): play its fixed case --case of --split instead of a benchmark map's scenario",
    )
    parser.add_argument("--case", type=count, default=None, help="the case of --env to play (default 0)")
    parser.add_argument("--split", default=None, help="the case split of --env (default test)")
    add_task_config_argument(parser)


def add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    """--map and --family: where one episode is played (demo, replay)."""
    parser.add_argument(
        "--map", default=None, help="map name or JSON path (default: the --family's own map, else gdc1)"
    )
    parser.add_argument(
        "--family",
        default=None,
        help="a scenario family instead of the benchmark's (MODULE:NAME for a family that MODULE registers)",
    )


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
