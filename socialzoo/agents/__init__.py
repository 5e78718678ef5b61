"""Policies of the benchmark, by registry name: `make_policy("ref")` builds one.

Entries name their class as "module:Class" and are imported only when built. A policy is named by a
spec: "ref" (an engineered policy, or a learned one's shipped file in socialzoo/agents/shipped/) or
"ppo:PATH" (a learned policy loaded from PATH with its class's `load`).
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from socialzoo.agents.base import LoadablePolicy, Policy

__all__ = [
    "POLICIES",
    "SHIPPED_DIR",
    "LoadablePolicy",
    "Policy",
    "check_policy_spec",
    "make_policy",
    "register_policy",
    "shipped_policy_file",
    "split_policy_spec",
]

# Trained policies that ship with the package: <name>.safetensors or <name>.json, with the run
# record of the command that made them beside (<name>.run.json).
SHIPPED_DIR = Path(__file__).resolve().parent / "shipped"
SHIPPED_SUFFIXES = (".safetensors", ".json")

# Registry name -> "module:Class".
POLICIES: dict[str, str] = {
    "goalone": "socialzoo.agents.engineered:GoAlone",
    "ref": "socialzoo.agents.engineered:Ref",
    # Neural baselines, all saved as socialzoo.env.policy_file files (see socialzoo.train).
    "ppo": "socialzoo.agents.mlp:MlpPolicy",
    "dqn": "socialzoo.agents.mlp:MlpPolicy",
    "bc": "socialzoo.agents.mlp:MlpPolicy",
    "gail": "socialzoo.agents.mlp:MlpPolicy",
    # BC with DAgger's rounds on its own states, labelled by Ref (`socialzoo train dagger`).
    "dagger": "socialzoo.agents.mlp:MlpPolicy",
    # Robots co-trained with learned humans (`socialzoo train cotrain`, robot.safetensors).
    "mappo": "socialzoo.agents.mlp:MlpPolicy",
    # Program synthesis: a JSON program (socialzoo.agents.pips_program).
    "pips": "socialzoo.agents.pips:PipsPolicy",
    # The CrowdNav task's learned velocity policy (`socialzoo train crowdnav`): PPO with attention.
    "crowdnav": "socialzoo.agents.crowd_policy:CrowdAttentionPolicy",
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


def split_policy_spec(spec: str) -> tuple[str, str | None]:
    """("ppo", "runs/ppo/policy.safetensors") for "ppo:runs/ppo/policy.safetensors"; ("ref", None) for
    "ref". The registry name is lower-cased; the path is kept as written.

    Raises:
        ValueError: an unknown registry name (the message lists the known ones), or an empty path.
    """
    if not isinstance(spec, str) or not spec:
        raise ValueError(f"a policy is named by a non-empty string, got {spec!r}")
    name, sep, path = spec.partition(":")
    key = name.strip().lower()
    if key not in POLICIES:
        raise ValueError(f"unknown policy {name!r}; known policies: {', '.join(sorted(POLICIES))}")
    if sep and not path:
        raise ValueError(f"policy {spec!r}: no file after ':'")
    return key, (path or None)


def _policy_class(key: str) -> type:
    module_name, class_name = POLICIES[key].split(":")
    return getattr(importlib.import_module(module_name), class_name)


def shipped_policy_file(name: str) -> Path | None:
    """The shipped file of learned policy `name`, or None."""
    for suffix in SHIPPED_SUFFIXES:
        path = SHIPPED_DIR / f"{name}{suffix}"
        if path.is_file():
            return path
    return None


def check_policy_spec(spec: str) -> str:
    """Validate a policy spec without building the policy; returns it.

    Raises:
        ValueError: an unknown name, a path that is not a file, or a learned policy named without
            a path that has no shipped file.
    """
    key, path = split_policy_spec(spec)
    cls = _policy_class(key)
    if path is not None:
        if not hasattr(cls, "load"):
            raise ValueError(f"policy {key!r} is not loaded from a file; name it without ':PATH'")
        if not Path(path).is_file():
            raise ValueError(f"policy {spec!r}: no such file {path!r}")
    elif hasattr(cls, "load") and shipped_policy_file(key) is None:
        raise ValueError(
            f"no shipped {key!r} policy in {SHIPPED_DIR}; train one (`socialzoo train {key} --out DIR`) "
            f"and name it '{key}:PATH'"
        )
    return spec


def make_policy(name: str, **kwargs: Any) -> Policy:
    """Build the policy named by a spec (case-insensitive registry name).

    Args:
        name: "goalone", "ref", a learned policy's registry name (its shipped file), or
            "NAME:PATH" (a learned policy's file).
        **kwargs: an engineered policy's parameters; for a learned policy, path= its file (the
            same as "NAME:PATH").

    Raises:
        ValueError: an unknown name (the message lists the known ones), or a learned policy with
            neither a path nor a shipped file.
    """
    key, path = split_policy_spec(name)
    cls = _policy_class(key)
    if path is not None:
        if kwargs:
            raise ValueError(f"policy {name!r} names its file; got keyword arguments {sorted(kwargs)} too")
        kwargs = {"path": path}
    if hasattr(cls, "load"):
        if set(kwargs) == {"path"}:
            return cls.load(kwargs["path"])
        if not kwargs:
            check_policy_spec(key)
            return cls.load(shipped_policy_file(key))
    return cls(**kwargs)
