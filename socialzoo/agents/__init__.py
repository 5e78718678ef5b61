"""Policies of the benchmark, by registry name: `make_policy("ref")` builds one.

Entries name their class as "module:Class" and are imported only when built, so learned policies
(which need torch) cost nothing until used. Learned policies are built with `path=` (their file),
or named "NAME:PATH" (e.g. "pips:runs/pips.json"): the registered class's `load(PATH)`.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from socialzoo.agents.base import LoadablePolicy, Policy

__all__ = [
    "POLICIES",
    "LoadablePolicy",
    "Policy",
    "check_policy_name",
    "make_policy",
    "register_policy",
    "split_policy_name",
]

# Registry name -> "module:Class".
POLICIES: dict[str, str] = {
    "goalone": "socialzoo.agents.engineered:GoAlone",
    "ref": "socialzoo.agents.engineered:Ref",
    "pips": "socialzoo.agents.pips:PipsPolicy",
}


def register_policy(name: str, target: str) -> None:
    """Add a policy to the registry.

    Args:
        name: lower-case registry name.
        target: "module:Class"; the class is built with make_policy's keyword arguments, or
            through its `load(path)` classmethod when `path` is the only one.

    Raises:
        ValueError: a bad name or target, or a name already taken by another target.
    """
    if not isinstance(name, str) or not name or name != name.lower():
        raise ValueError(f"register_policy: name must be a non-empty lower-case string, got {name!r}")
    if not isinstance(target, str) or target.count(":") != 1:
        raise ValueError(f"register_policy: target must be 'module:Class', got {target!r}")
    if POLICIES.get(name, target) != target:
        raise ValueError(f"register_policy: {name!r} is already registered as {POLICIES[name]!r}")
    POLICIES[name] = target


def split_policy_name(name: str) -> tuple[str, str | None]:
    """A policy name's registry key (lower case) and file: "ref" -> ("ref", None),
    "pips:runs/a.json" -> ("pips", "runs/a.json"). Only the key's case is folded."""
    key, sep, path = name.partition(":")
    return key.lower(), (path if sep else None)


def _policy_class(key: str) -> Any:
    module_name, class_name = POLICIES[key].split(":")
    return getattr(importlib.import_module(module_name), class_name)


def check_policy_name(name: str) -> None:
    """Check that `name` is a registered policy, or "NAME:PATH" with NAME registered, its class
    able to load a file (a `load` classmethod) and PATH an existing file.

    Raises:
        ValueError: naming the bad name, class or file.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"a policy name must be a non-empty string, got {name!r}")
    key, path = split_policy_name(name)
    if key not in POLICIES:
        raise ValueError(f"unknown policy {name!r}; known policies: {', '.join(sorted(POLICIES))}")
    if path is None:
        return
    if not path:
        raise ValueError(f"policy {name!r}: no file after {key + ':'!r}")
    if not hasattr(_policy_class(key), "load"):
        raise ValueError(f"policy {name!r}: {key!r} does not load from a file")
    if not Path(path).is_file():
        raise ValueError(f"policy {name!r}: no such file {path!r}")


def make_policy(name: str, **kwargs: Any) -> Policy:
    """Build the policy registered as `name` (case-insensitive).

    Args:
        name: a key of POLICIES, e.g. "goalone" or "ref"; or "NAME:PATH", the policy NAME
            loaded from the file PATH (its class's `load`).
        **kwargs: the policy's parameters; for a learned policy, path= its saved file.

    Raises:
        ValueError: an unknown name (the message lists the known ones), or "NAME:PATH" with
            other keyword arguments or for a class that does not load files.
    """
    if not isinstance(name, str):
        raise ValueError(f"unknown policy {name!r}; known policies: {', '.join(sorted(POLICIES))}")
    key, path = split_policy_name(name)
    if key not in POLICIES:
        raise ValueError(f"unknown policy {name!r}; known policies: {', '.join(sorted(POLICIES))}")
    cls = _policy_class(key)
    if path is not None:
        if kwargs:
            raise ValueError(f"policy {name!r} names its file; got keyword arguments {sorted(kwargs)} too")
        kwargs = {"path": path}
    if set(kwargs) == {"path"} and hasattr(cls, "load"):
        return cls.load(kwargs["path"])
    if path is not None:
        raise ValueError(f"policy {name!r}: {key!r} does not load from a file")
    return cls(**kwargs)
