"""Shared pieces of the trainers' argument dataclasses: option types, and validation whose errors
name the trainer, the field and the value. Free of torch, so listing the trainers stays cheap.
"""

from __future__ import annotations

from typing import Any, Literal

# Hidden-layer activations of the trainers' MLPs (socialzoo.agents.mlp.ACTIVATIONS).
Activation = Literal["tanh", "relu"]


def _where(args: Any, name: str) -> str:
    return f"{type(args).__module__.rsplit('.', 1)[-1]} Args.{name}"


def check_int(args: Any, name: str, low: int, optional: bool = False) -> None:
    """Raise ValueError unless args.<name> is an int >= low (or None when optional)."""
    value = getattr(args, name)
    if optional and value is None:
        return
    if not isinstance(value, int) or isinstance(value, bool) or value < low:
        raise ValueError(
            f"{_where(args, name)} must be an int >= {low}{' or None' if optional else ''}, got {value!r}"
        )


def check_number(
    args: Any, name: str, low: float, *, strict: bool = False, high: float | None = None
) -> None:
    """Raise ValueError unless args.<name> is a number >= low (> low when strict), <= high if given."""
    value = getattr(args, name)
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    ok = ok and (value > low if strict else value >= low) and (high is None or value <= high)
    if not ok:
        bound = f"{'>' if strict else '>='} {low}" + (f" and <= {high}" if high is not None else "")
        raise ValueError(f"{_where(args, name)} must be a number {bound}, got {value!r}")


def check_sizes(args: Any, name: str) -> None:
    """Raise ValueError unless args.<name> is a non-empty tuple of positive ints."""
    value = getattr(args, name)
    if not value or any(not isinstance(h, int) or isinstance(h, bool) or h < 1 for h in value):
        raise ValueError(f"{_where(args, name)} must be positive ints, got {value!r}")
