"""Shared pieces of the trainers' argument dataclasses: option types, and validation whose errors name the trainer,
the field and the value. Free of torch, so listing the trainers stays cheap."""

from __future__ import annotations

from typing import Any, Literal

from socialzoo.core import validation

# Hidden-layer activations of the trainers' MLPs (socialzoo.agents.mlp.ACTIVATIONS).
Activation = Literal["tanh", "relu"]


def owner(args: Any) -> str:
    """How messages name a trainer's arguments: "bc Args" for socialzoo.train.bc.Args."""
    return f"{type(args).__module__.rsplit('.', 1)[-1]} Args"


def check_int(args: Any, name: str, low: int, optional: bool = False) -> None:
    """Raise ValueError unless args.<name> is an int >= low (or None when optional)."""
    validation.check_int(owner(args), name, getattr(args, name), low=low, allow_none=optional)


def check_number(
    args: Any, name: str, low: float, *, strict: bool = False, high: float | None = None
) -> None:
    """Raise ValueError unless args.<name> is a finite number >= low (> low when strict), <= high if
    given."""
    validation.check_number(owner(args), name, getattr(args, name), low=low, high=high, low_open=strict)


def check_sizes(args: Any, name: str) -> None:
    """Raise ValueError unless args.<name> is a non-empty tuple of positive ints."""
    value = getattr(args, name)
    if not value or any(not isinstance(h, int) or isinstance(h, bool) or h < 1 for h in value):
        raise ValueError(f"{owner(args)}.{name} must be positive ints, got {value!r}")
