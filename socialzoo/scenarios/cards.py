"""Scenario cards: each suite scenario's card (the guidelines' scenario card: metadata, definition, usage) kept as
data beside its family, socialzoo/scenarios/cards/FAMILY.toml, checked on load."""

from __future__ import annotations

import json
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

from socialzoo.core.metrics import names as metric_names
from socialzoo.scenarios.catalogue import SeedSplit
from socialzoo.scenarios.suite import SUITE, SUITE_NAMES, SUITE_SPLITS

SCHEMA_FILE = "card.schema.json"
CARD_DIR = "cards"

GoalKind = Literal["reach", "follow", "lead", "accompany", "join"]


class CardError(ValueError):
    """A scenario card that cannot be read, breaks the schema or disagrees with the suite: names
    the file and the field.

    Attributes:
        source: the card's file (or the name asked for).
        field: the field's path in the card, e.g. "definition.people[0].count" ("(file)" for the
            whole file).
        problem: what is wrong with it.
    """

    def __init__(self, source: str, field: str, problem: str) -> None:
        super().__init__(f"{source}: {field}: {problem}")
        self.source, self.field, self.problem = source, field, problem


@dataclass(frozen=True)
class RobotTask:
    """What the robot does: where it starts, where it goes, and the kind of goal.

    Attributes:
        start: where the robot starts (prose).
        goal: where it goes (prose).
        goal_kind: "reach" a place; "follow", "lead" or "accompany" a person there (the escort's
            distance band holds at the goal); "join" a group at a place.
    """

    start: str
    goal: str
    goal_kind: GoalKind


@dataclass(frozen=True)
class PeopleRole:
    """The people of one role in the scenario.

    Attributes:
        role: what they are, e.g. "oncoming pedestrian".
        count: (least, most) people of the role.
        speed: (least, most) preferred walking speed, m/s.
        behaviour: what they do (prose).
    """

    role: str
    count: tuple[int, int]
    speed: tuple[float, float]
    behaviour: str


@dataclass(frozen=True)
class Variation:
    """One thing the seed varies: a numeric range with its unit, or a set of values.

    Attributes:
        what: what varies (prose).
        range: (least, most), or None for a set of values.
        unit: the range's unit ("" for a set of values; "-" for a pure number).
        values: the values it takes (empty for a range).
    """

    what: str
    range: tuple[float, float] | None
    unit: str
    values: tuple[str, ...]


@dataclass(frozen=True, kw_only=True)
class ScenarioCard:
    """One scenario's card (Francis et al. 2025's scenario card: metadata, definition, usage).

    Attributes:
        letter: the scenario's letter in Fig. 7 (a to y).
        family: its family's registry name (socialzoo.scenarios.catalogue).
        title: its title, as socialzoo.scenarios.suite spells it.
        version: the card's version (raised when the definition changes).
        source: where the scenario comes from, and what socialzoo chose itself.
        description: what happens (prose).
        map_name: the shipped map the family is designed for.
        robot: the robot's start, goal and goal kind.
        people: the people, by role.
        defining_event: what makes an episode this scenario.
        success: the success criteria.
        variation: what the seed varies.
        seeds: the seed splits ("val", "test", "train"), as socialzoo.scenarios.suite.SUITE_SPLITS.
        metrics: metrics of interest (names in socialzoo.core.metrics).
        notes: usage notes.
        limitations: known limitations, and where socialzoo's scenario differs from the guidelines'.
        path: the file the card was read from.
    """

    letter: str
    family: str
    title: str
    version: int
    source: str
    description: str
    map_name: str
    robot: RobotTask
    people: tuple[PeopleRole, ...]
    defining_event: str
    success: tuple[str, ...]
    variation: tuple[Variation, ...]
    seeds: Mapping[str, SeedSplit]
    metrics: tuple[str, ...]
    notes: tuple[str, ...]
    limitations: tuple[str, ...]
    path: str

    @property
    def num_people(self) -> tuple[int, int]:
        """(least, most) people in the scenario, every role together."""
        return sum(p.count[0] for p in self.people), sum(p.count[1] for p in self.people)


@cache
def schema() -> dict[str, Any]:
    """The card's JSON Schema (draft 2020-12), shipped as package data."""
    text = (resources.files("socialzoo.scenarios") / SCHEMA_FILE).read_text(encoding="utf-8")
    return dict(json.loads(text))


def card_path(name: str) -> Path:
    """The shipped card of a suite scenario, by family name or Fig. 7 letter.

    Raises:
        CardError: not a suite scenario.
    """
    for entry in SUITE:
        if name in (entry.family, entry.letter):
            return Path(str(resources.files("socialzoo.scenarios") / CARD_DIR / f"{entry.family}.toml"))
    raise CardError(name, "(name)", f"not a suite scenario; known: {', '.join(SUITE_NAMES)}")


def load_card(path_or_name: str | Path) -> ScenarioCard:
    """Read and check a scenario card: a file (a Path, or a string ending in .toml), or a suite
    scenario's shipped card by family name or letter.

    A card is read with tomllib and checked against its JSON Schema (socialzoo/scenarios/card.schema.json),
    then against the suite (socialzoo.scenarios.suite: the family, its letter and title, the seed
    splits) and the metric registry (socialzoo.core.metrics).

    Raises:
        CardError: the file cannot be read or is not UTF-8 TOML, a field is missing or has the wrong
            type, the family is not a suite scenario, the letter or title disagrees with the suite,
            a range is out of order, a metric is not registered, the seed splits are not the
            suite's; the message names the file and the field.
    """
    is_file = isinstance(path_or_name, Path) or str(path_or_name).endswith(".toml")
    path = Path(path_or_name) if is_file else card_path(str(path_or_name))
    source = str(path)
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # the same parser, a dependency before Python 3.11
        import tomli as tomllib

    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as err:
        raise CardError(source, "(file)", f"is not UTF-8 text: {err.reason} at byte {err.start}") from None
    except OSError as err:
        raise CardError(source, "(file)", f"cannot be read: {err.strerror or err}") from None
    except tomllib.TOMLDecodeError as err:
        raise CardError(source, "(file)", f"is not TOML: {err}") from None
    validate_card(data, source)
    card = _card(data, source)
    if card.family != path.stem:
        raise CardError(source, "metadata.family", f"{card.family!r} must be the file's name ({path.stem!r})")
    return card


@cache
def suite_cards() -> tuple[ScenarioCard, ...]:
    """Every suite scenario's shipped card, in the suite's order (socialzoo.scenarios.suite.SUITE).

    Raises:
        CardError: a card is missing or invalid.
    """
    return tuple(load_card(entry.family) for entry in SUITE)


def _path(parts: Sequence[Any]) -> str:
    """jsonschema's path as "definition.people[0].count" ("(top level)" when empty)."""
    text = ""
    for part in parts:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "(top level)"


def validate_card(data: Any, source: str = "<card>") -> None:
    """Check a card's data (the parsed TOML) against the schema, the suite and the metric registry.

    Raises:
        CardError: the first problem, naming `source` and the field.
    """
    import jsonschema

    validator = jsonschema.Draft202012Validator(schema())
    error = jsonschema.exceptions.best_match(validator.iter_errors(data))
    if error is not None:
        where = list(error.absolute_path)
        if error.validator == "required" and isinstance(error.instance, Mapping):
            # Name the missing field itself, not the table it is missing from.
            missing = [k for k in error.validator_value if k not in error.instance]
            if missing:
                raise CardError(source, _path([*where, missing[0]]), "is missing (a required field)")
        if error.validator == "oneOf":
            # jsonschema's message quotes the whole table; say which fields would do instead.
            choices = " or ".join("/".join(s.get("required", ())) for s in error.validator_value)
            raise CardError(source, _path(where), f"must give exactly one of: {choices}")
        raise CardError(source, _path(where), error.message)
    meta = data["metadata"]
    entry = next((e for e in SUITE if e.family == meta["family"]), None)
    if entry is None:
        raise CardError(
            source,
            "metadata.family",
            f"unknown family {meta['family']!r}: not a suite scenario ({', '.join(SUITE_NAMES)})",
        )
    if meta["letter"] != entry.letter:
        raise CardError(
            source,
            "metadata.letter",
            f"{meta['letter']!r}, but the suite gives {entry.family} letter {entry.letter!r}",
        )
    if meta["title"] != entry.title:
        raise CardError(
            source, "metadata.title", f"{meta['title']!r}, but the suite calls {entry.family} {entry.title!r}"
        )
    definition = data["definition"]
    for i, role in enumerate(definition["people"]):
        for key in ("count", "speed"):
            low, high = role[key]
            if low > high or (key == "speed" and low < 0):
                raise CardError(
                    source,
                    f"definition.people[{i}].{key}",
                    f"must be [least, most] with 0 <= least <= most, got {role[key]}",
                )
    for i, item in enumerate(definition["variation"]):
        if "range" in item and item["range"][0] > item["range"][1]:
            raise CardError(
                source, f"definition.variation[{i}].range", f"must be [least, most], got {item['range']}"
            )
    for split, want in SUITE_SPLITS.items():
        got = definition["seeds"][split]
        if (got["first"], got.get("size")) != tuple(want):
            raise CardError(
                source,
                f"definition.seeds.{split}",
                f"{got} is not the suite's {split} split (first={want.first}, size={want.size})",
            )
    known = set(metric_names())
    for i, name in enumerate(data["usage"]["metrics"]):
        if name not in known:
            raise CardError(
                source, f"usage.metrics[{i}]", f"{name!r} is not a registered metric (socialzoo.core.metrics)"
            )


def _card(data: Mapping[str, Any], source: str) -> ScenarioCard:
    """The ScenarioCard of checked card data."""
    meta, definition, usage = data["metadata"], data["definition"], data["usage"]
    robot = definition["robot"]
    return ScenarioCard(
        letter=meta["letter"],
        family=meta["family"],
        title=meta["title"],
        version=meta["version"],
        source=meta["source"],
        description=definition["description"],
        map_name=definition["map"],
        robot=RobotTask(robot["start"], robot["goal"], robot["goal_kind"]),
        people=tuple(
            PeopleRole(
                p["role"],
                (p["count"][0], p["count"][1]),
                (float(p["speed"][0]), float(p["speed"][1])),
                p["behaviour"],
            )
            for p in definition["people"]
        ),
        defining_event=definition["defining_event"],
        success=tuple(definition["success"]),
        variation=tuple(
            Variation(
                v["what"],
                (float(v["range"][0]), float(v["range"][1])) if "range" in v else None,
                v.get("unit", ""),
                tuple(v.get("values", ())),
            )
            for v in definition["variation"]
        ),
        seeds=MappingProxyType(
            {k: SeedSplit(s["first"], s.get("size")) for k, s in definition["seeds"].items()}
        ),
        metrics=tuple(usage["metrics"]),
        notes=tuple(usage["notes"]),
        limitations=tuple(usage["limitations"]),
        path=source,
    )
