"""Command-line options from a frozen dataclass of arguments (the trainers' `Args`): each field a `--field-name`,
typed from its annotation, with its default and the help text of the class docstring's "Attributes:" section."""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import json
import re
import types
import typing
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin

from socialzoo.cli.arg_types import out_dir


def attribute_docs(cls: type) -> dict[str, str]:
    """Field name -> description, from the "Attributes:" sections of the Google-style docstrings of
    `cls` and its bases (a class's own description of a field wins over its base's)."""
    found: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        found.update(_own_attribute_docs(klass))
    return found


def _own_attribute_docs(cls: type) -> dict[str, str]:
    """Field name -> description from the "Attributes:" section of `cls`'s own docstring."""
    doc = inspect.cleandoc(cls.__dict__.get("__doc__") or "")
    found: dict[str, str] = {}
    section = False
    current: str | None = None
    for line in doc.splitlines():
        if re.match(r"^\S.*:$", line):
            section = line.strip() == "Attributes:"
            current = None
            continue
        if not section:
            continue
        match = re.match(r"^    (\w+)(?: \([^)]*\))?: (.*)$", line)
        if match:
            current = match.group(1)
            found[current] = match.group(2).strip()
        elif current and line.startswith("        "):
            found[current] += " " + line.strip()
    return found


def _optional(annotation: Any) -> tuple[Any, bool]:
    """(inner type, True) for `X | None`, else (annotation, False)."""
    if get_origin(annotation) in (Union, types.UnionType):
        inner = [a for a in get_args(annotation) if a is not type(None)]
        if len(inner) == 1 and len(get_args(annotation)) == 2:
            return inner[0], True
    return annotation, False


def _scalar_parser(annotation: Any, name: str) -> Any:
    if annotation is Path and name == "out":  # the run folder: checked before training starts
        return out_dir
    if annotation in (int, float, str, Path):
        return annotation
    if get_origin(annotation) in (dict, typing.Mapping) or annotation is dict:

        def parse_json(text: str) -> Any:
            try:
                value = json.loads(text)
            except json.JSONDecodeError as err:
                raise argparse.ArgumentTypeError(f"--{name}: not JSON ({err})") from None
            if not isinstance(value, dict):
                raise argparse.ArgumentTypeError(f"--{name}: expected a JSON object, got {text!r}")
            return value

        return parse_json
    raise TypeError(f"dataclass_args: field {name!r} has an unsupported type {annotation!r}")


def add_dataclass_arguments(parser: argparse.ArgumentParser, cls: type) -> None:
    """Add one option per field of dataclass `cls` to `parser` (dest = the field name).

    Types: int, float, str, Path, bool (`--x/--no-x`), Literal choices, `X | None` ("none" for None),
    tuples (several values) and JSON objects (dicts).
    """
    hints = typing.get_type_hints(cls)
    docs = attribute_docs(cls)
    for field in dataclasses.fields(cls):
        if not field.init:
            continue
        flag = "--" + field.name.replace("_", "-")
        annotation, optional = _optional(hints[field.name])
        default = field.default
        if default is dataclasses.MISSING and field.default_factory is not dataclasses.MISSING:
            default = field.default_factory()
        required = default is dataclasses.MISSING
        help_text = docs.get(field.name, "")
        if not required:
            help_text += f" (default: {json.dumps(default, default=str)})"  # a Path as its text
        kwargs: dict[str, Any] = {"dest": field.name, "help": help_text}
        if required:
            kwargs["required"] = True
        else:
            kwargs["default"] = default
        if annotation is bool:
            kwargs["action"] = argparse.BooleanOptionalAction
        elif get_origin(annotation) is tuple:
            kwargs["nargs"] = "+"
            kwargs["type"] = _scalar_parser(get_args(annotation)[0], field.name)
        else:
            if get_origin(annotation) is Literal:
                choices = list(get_args(annotation))
                kwargs["choices"] = choices + ([None] if optional else [])
                base = _literal_parser(choices)
            else:
                base = _scalar_parser(annotation, field.name)
            kwargs["type"] = _none_or(base) if optional else base
        parser.add_argument(flag, **kwargs)


def _none_or(parse: Any) -> Any:
    def parse_optional(text: str) -> Any:
        return None if text.lower() == "none" else parse(text)

    return parse_optional


def _literal_parser(choices: list[Any]) -> Any:
    def parse_choice(text: str) -> Any:
        for choice in choices:
            if str(choice) == text:
                return choice
        raise argparse.ArgumentTypeError(f"expected one of {choices}, got {text!r}")

    return parse_choice


def dataclass_from_namespace(cls: type, namespace: argparse.Namespace, **values: Any) -> Any:
    """Build `cls` from `values` and, for its other init fields, the namespace's options of the same
    name (tuples from lists): the options `add_dataclass_arguments` added, or a subcommand's own
    options named as its config's fields."""
    for field in dataclasses.fields(cls):
        if field.init and field.name not in values and hasattr(namespace, field.name):
            value = getattr(namespace, field.name)
            values[field.name] = tuple(value) if isinstance(value, list) else value
    return cls(**values)
