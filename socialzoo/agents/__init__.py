"""Policies of every task, by registry name: `make_policy("ref")`, `make_policy("orca", task="crowdnav")`."""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from socialzoo.agents.base import LoadablePolicy, Policy
from socialzoo.core.files import no_file

__all__ = [
    "POLICIES",
    "POLICY_TASKS",
    "SHIPPED_DIR",
    "LoadablePolicy",
    "Policy",
    "PolicyTaskError",
    "check_observation_size",
    "check_policy_spec",
    "make_policy",
    "policy_file",
    "policy_file_or_shipped",
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
    # The same learner trained on the scenario suite's 25 families (`socialzoo train crowdnav --families suite`).
    "suite_crowdnav": "socialzoo.agents.crowd_policy:CrowdAttentionPolicy",
    # The CrowdNav task's engineered robots: CrowdNav's ORCA robot, a social-force robot.
    "orca": "socialzoo.agents.crowd_engineered:CrowdOrcaRobot",
    "social_force": "socialzoo.agents.crowd_engineered:CrowdSocialForceRobot",
}
# Registry name -> the task its policy acts in (socialzoo.env.tasks.TASKS); the rest act in
# "action_selection".
POLICY_TASKS: dict[str, str] = {
    "crowdnav": "crowdnav",
    "suite_crowdnav": "crowdnav",
    "orca": "crowdnav",
    "social_force": "crowdnav",
}
# Registry name -> the `socialzoo train` command that makes its file, where it is not the name's own.
POLICY_TRAINERS: dict[str, str] = {
    "mappo": "cotrain",
    "suite_crowdnav": "crowdnav --families suite",
}
DEFAULT_TASK = "action_selection"


class PolicyTaskError(ValueError):
    """A policy asked for in a task it does not act in, or with another observation size."""


def policy_task(name: str) -> str:
    """The task the registered policy `name` acts in."""
    return POLICY_TASKS.get(name, DEFAULT_TASK)


def register_policy(name: str, target: str, task: str = DEFAULT_TASK) -> None:
    """Add a policy to the registry.

    The class is imported only when a policy is built.

    Args:
        name: lower-case registry name.
        target: "module:Class"; the class is built with make_policy's keyword arguments, or
            through its `load(path)` classmethod when `path` is the only one.
        task: the task the policy acts in (a socialzoo.env.tasks registry name or "module:Class").

    Raises:
        ValueError: a bad name or target, or a name already taken by another target or task.
    """
    if not isinstance(name, str) or not name or name != name.lower():
        raise ValueError(f"register_policy: name must be a non-empty lower-case string, got {name!r}")
    if not isinstance(target, str) or target.count(":") != 1:
        raise ValueError(f"register_policy: target must be 'module:Class', got {target!r}")
    if POLICIES.get(name, target) != target or (name in POLICIES and policy_task(name) != task):
        raise ValueError(
            f"register_policy: {name!r} is already registered as {POLICIES[name]!r} for task {policy_task(name)!r}"
        )
    POLICIES[name] = target
    if task != DEFAULT_TASK:
        POLICY_TASKS[name] = task


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
    """The shipped file of learned policy `name`, or None.

    Shipped files live in socialzoo/agents/shipped/.
    """
    for suffix in SHIPPED_SUFFIXES:
        path = SHIPPED_DIR / f"{name}{suffix}"
        if path.is_file():
            return path
    return None


def policy_file(spec: str) -> Path | None:
    """The policy file a spec names: PATH of "name:PATH", the shipped file of a learned policy
    named alone; None for an engineered policy.

    Raises:
        ValueError: an unknown name (see split_policy_spec).
    """
    key, path = split_policy_spec(spec)
    if path is not None:
        return Path(path)
    return shipped_policy_file(key) if hasattr(_policy_class(key), "load") else None


def policy_file_or_shipped(value: str | Path) -> Path:
    """`value` as a file path; where no such file exists and `value` is a learned policy's registry
    name with a shipped file ("dagger"), that file: so a command that takes a policy file also
    takes a shipped policy by name, from a checkout or an installed package alike."""
    path = Path(value)
    key = str(value).strip().lower()
    if not path.exists() and key in POLICIES and hasattr(_policy_class(key), "load"):
        return shipped_policy_file(key) or path
    return path


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
            raise ValueError(f"policy {spec!r}: {no_file(path)}")
    elif hasattr(cls, "load") and shipped_policy_file(key) is None:
        trainer = POLICY_TRAINERS.get(key, key)
        raise ValueError(
            f"no shipped {key!r} policy in {SHIPPED_DIR}; train one (`socialzoo train {trainer} --out DIR`) "
            f"and name it '{key}:PATH'"
        )
    return spec


def make_policy(
    name: str, *, task: Any = DEFAULT_TASK, observation_space: Any = None, **kwargs: Any
) -> Policy:
    """Build the policy named by a spec (case-insensitive registry name) for a task.

    Args:
        name: "goalone", "ref", a learned policy's registry name (its shipped file), or
            "NAME:PATH" (a learned policy's file).
        task: the task the policy is to act in: a task registry name (default the action-selection
            task), or a Task object (socialzoo.env.tasks.base.Task), whose observation size a
            learned policy must also match.
        observation_space: the task's observation space (a gymnasium Box), when `task` is a name:
            a learned policy must read observations of its size.
        **kwargs: an engineered policy's parameters; for a learned policy, path= its file (the
            same as "NAME:PATH").

    Raises:
        ValueError: an unknown name (the message lists the known ones), a learned policy with
            neither a path nor a shipped file, or a file given to an engineered policy.
        PolicyTaskError: a policy of another task, or a learned policy whose observations are not
            the size of the task's, or (a Task given) that was trained on another of its settings
            (the policy's check_config: a CrowdNav learner's robot kinematics).
    """
    task_name = task if isinstance(task, str) else getattr(task, "name", None)
    others = sorted(k for k in POLICIES if policy_task(k) == task_name)
    if isinstance(name, str) and name.partition(":")[0].strip().lower() not in POLICIES:
        raise ValueError(f"unknown policy {name!r}; policies of task {task_name!r}: {', '.join(others)}")
    key, path = split_policy_spec(name)
    if task_name != policy_task(key):
        raise PolicyTaskError(
            f"policy {name!r} acts in task {policy_task(key)!r}, not {task_name!r}; "
            f"policies of {task_name!r}: {', '.join(others) or 'none registered'}"
        )
    cls = _policy_class(key)
    if path is not None:
        if kwargs:
            raise ValueError(f"policy {name!r} names its file; got keyword arguments {sorted(kwargs)} too")
        kwargs = {"path": path}
    if "path" in kwargs and not hasattr(cls, "load"):
        raise ValueError(f"policy {key!r} is not loaded from a file; name it without ':PATH'")
    if hasattr(cls, "load"):
        if set(kwargs) == {"path"}:
            policy = cls.load(kwargs["path"])
        elif not kwargs:
            check_policy_spec(key)
            policy = cls.load(shipped_policy_file(key))
        else:
            policy = cls(**kwargs)
    else:
        policy = cls(**kwargs)
    space = getattr(task, "observation_space", observation_space)
    if space is not None:
        check_observation_size(name, policy, task_name, space)
    config = getattr(task, "config", None)
    if config is not None and hasattr(policy, "check_config"):  # what else it was trained for
        policy.check_config(config)
    return policy


def check_observation_size(name: str, policy: Any, task: str, space: Any) -> None:
    """Refuse a learned policy whose observations are not the size of the task's, naming both."""
    size = getattr(policy, "observation_size", getattr(policy, "input_size", None))
    shape = getattr(space, "shape", None)
    if size is None or not shape or len(shape) != 1 or int(size) == int(shape[0]):
        return
    trained = getattr(policy, "header", {}).get("env_id", "another configuration")
    raise PolicyTaskError(
        f"policy {name!r} reads observations of {size} numbers (trained on {trained}), but this "
        f"{task!r} task's observations have {int(shape[0])}; use a policy trained on this configuration"
    )
