"""Checks of "a finite number in range" (or one of a few choices) for config dataclasses and input files,
with one wording."""

from __future__ import annotations

import math
import numbers
from collections.abc import Collection
from dataclasses import fields
from typing import Any

# Field annotations (as written, or as strings under `from __future__ import annotations`) that
# `check_fields` checks; an optional one may also be None.
_FLOAT_TYPES: tuple[Any, ...] = (float, "float", float | None, "float | None")
_INT_TYPES: tuple[Any, ...] = (int, "int", int | None, "int | None")


class UnknownFieldError(ValueError, TypeError):
    """A config given a keyword that is none of its fields: a ValueError as every bad config is, and
    a TypeError with Python's own words ("got an unexpected keyword argument 'x'"), as any callable
    raises for an unknown keyword, so callers that probe for an optional keyword and drop it on that
    error (TorchRL's GymEnv passes `frameskip` to gymnasium.make) work."""


def unknown_fields(where: str, given: Collection[str], known: Collection[str]) -> UnknownFieldError | None:
    """The error for the keywords of `given` that are not in `known` (named, with the known ones),
    or None when every one is known."""
    unknown = sorted(set(given) - set(known))
    if not unknown:
        return None
    return UnknownFieldError(
        f"{where}: unknown field(s) {unknown}; known: {sorted(known)} "
        f"(got an unexpected keyword argument {unknown[0]!r})"
    )


def _range_text(low: float | None, high: float | None, low_open: bool, high_open: bool) -> str:
    """The allowed range in words: ">= 0", "> 0", "<= 360" or "in (0, 90]"; "" for any."""
    if low is not None and high is not None:
        return f"in {'(' if low_open else '['}{low}, {high}{')' if high_open else ']'}"
    if low is not None:
        return f"{'>' if low_open else '>='} {low}"
    if high is not None:
        return f"{'<' if high_open else '<='} {high}"
    return ""


def is_finite_number(value: Any) -> bool:
    """Whether `value` is an int or float (not a bool) with a finite float value: NaN, infinities and
    ints beyond a float's range (10**400, which JSON reads as an int) are not."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # math.isfinite converts an int to a float first
        return False


def check_number(
    owner: str,
    field: str,
    value: Any,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    integer: bool = False,
    allow_none: bool = False,
    error: type[ValueError] = ValueError,
) -> Any:
    """Check that `value` is a finite number (an int with `integer`) within [low, high].

    bool is not a number here. A float field takes ints and floats (numpy float64 included);
    an int field takes Python ints only, so that configs stay plain JSON.

    Args:
        owner: who owns the value, usually the class name ("ScenarioConfig"), or a file entry.
        field: the field's name; messages say "owner.field".
        value: the value to check.
        low: lower bound, or None for none.
        high: upper bound, or None for none.
        low_open: the lower bound itself is refused (value > low).
        high_open: the upper bound itself is refused (value < high).
        integer: the value must be an int.
        allow_none: None passes.
        error: the exception class raised (a ValueError).

    Returns:
        `value`, unchanged.

    Raises:
        ValueError (or `error`): naming owner.field, the allowed range and the bad value, e.g.
            "ScenarioConfig.min_speed must be > 0.0, got 0.0" or "EnvConfig.max_steps must be an
            int >= 1, got 0".
    """
    if value is None and allow_none:
        return value
    rng = _range_text(low, high, low_open, high_open)
    or_none = " or None" if allow_none else ""
    if integer:
        ok = isinstance(value, int) and not isinstance(value, bool)
        if ok and not _in_range(value, low, high, low_open, high_open):
            ok = False
        if not ok:
            kind = f"an int {rng}" if rng else "an int"
            raise error(f"{owner}.{field} must be {kind}{or_none}, got {value!r}")
        return value
    if not is_finite_number(value):
        raise error(f"{owner}.{field} must be a finite number{or_none}, got {value!r}")
    if not _in_range(value, low, high, low_open, high_open):
        raise error(f"{owner}.{field} must be {rng}, got {value!r}")
    return value


def _in_range(value: float, low: float | None, high: float | None, low_open: bool, high_open: bool) -> bool:
    if low is not None and (value < low or (low_open and value == low)):
        return False
    return not (high is not None and (value > high or (high_open and value == high)))


def check_int(
    owner: str,
    field: str,
    value: Any,
    *,
    low: int | None = None,
    high: int | None = None,
    allow_none: bool = False,
    error: type[ValueError] = ValueError,
) -> Any:
    """Check that `value` is an int (not a bool) within [low, high]; see `check_number`.

    Returns:
        `value`, unchanged.

    Raises:
        ValueError (or `error`): "owner.field must be an int >= low, got value".
    """
    return check_number(
        owner, field, value, low=low, high=high, integer=True, allow_none=allow_none, error=error
    )


def check_seed(owner: str, seed: Any) -> int | None:
    """A reset or set_seed seed as Gymnasium takes it: None, or an int >= 0 (numpy's integers too,
    which PettingZoo and TorchRL callers pass); returns it as a Python int.

    Raises:
        ValueError: "owner: seed must be an int >= 0 or None, got seed" (a float, a list, a negative
            int), before any state changes.
    """
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise ValueError(f"{owner}: seed must be an int >= 0 or None, got {seed!r}")
    return int(seed)


def check_choice(owner: str, field: str, value: Any, choices: Collection[Any]) -> Any:
    """Check that `value` is one of `choices`; returns it.

    Raises:
        ValueError: "owner.field must be one of choices, got value".
    """
    if value not in choices:
        raise ValueError(f"{owner}.{field} must be one of {choices}, got {value!r}")
    return value


def check_fields(obj: Any, *, nonnegative: Collection[str] = (), signed: Collection[str] = ()) -> None:
    """Check every number field of a config dataclass: finite and > 0 (an int: >= 1) unless listed otherwise.

    Number fields are those annotated `float` or `int` (an int field must hold an int), or
    `float | None` or `int | None` (None passes); fields of other types are left to the caller.

    Args:
        obj: the dataclass instance; messages name its class.
        nonnegative: fields that may also be 0.
        signed: fields that may be any finite number.

    Raises:
        ValueError: the first bad field, as `check_number` words it.
        TypeError: `nonnegative` or `signed` names a field `obj` does not have as a number field.
    """
    owner = type(obj).__name__
    numbers = {f.name: f.type for f in fields(obj) if f.type in _FLOAT_TYPES + _INT_TYPES}
    unknown = (set(nonnegative) | set(signed)) - set(numbers)
    if unknown:
        raise TypeError(f"check_fields({owner}): not number fields: {sorted(unknown)}")
    for name, kind in numbers.items():
        integer = kind in _INT_TYPES
        # A positive int field is worded as one >= 1, as check_int(low=1) words it.
        low = None if name in signed else 1 if integer and name not in nonnegative else 0
        open_low = low == 0 and name not in nonnegative
        optional = str(kind).endswith("None")
        check_number(
            owner, name, getattr(obj, name), low=low, low_open=open_low, integer=integer, allow_none=optional
        )
