"""Policies of the benchmark, by registry name: `make_policy("ref")` builds one.

Entries name their class as "module:Class" and are imported only when built, so learned policies
(which need torch) cost nothing until used. Learned policies are built with `path=` (their file).
"""

from __future__ import annotations

import importlib
from typing import Any

from socialzoo.agents.base import LoadablePolicy, Policy

__all__ = ["POLICIES", "LoadablePolicy", "Policy", "make_policy", "register_policy"]

# Registry name -> "module:Class".
POLICIES: dict[str, str] = {
    "goalone": "socialzoo.agents.engineered:GoAlone",
    "ref": "socialzoo.agents.engineered:Ref",
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


def make_policy(name: str, **kwargs: Any) -> Policy:
    """Build the policy registered as `name` (case-insensitive).

    Args:
        name: a key of POLICIES, e.g. "goalone" or "ref".
        **kwargs: the policy's parameters; for a learned policy, path= its saved file.

    Raises:
        ValueError: an unknown name (the message lists the known ones).
    """
    key = name.lower() if isinstance(name, str) else name
    if key not in POLICIES:
        raise ValueError(f"unknown policy {name!r}; known policies: {', '.join(sorted(POLICIES))}")
    module_name, class_name = POLICIES[key].split(":")
    cls = getattr(importlib.import_module(module_name), class_name)
    if set(kwargs) == {"path"} and hasattr(cls, "load"):
        return cls.load(kwargs["path"])
    return cls(**kwargs)
