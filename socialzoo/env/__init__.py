"""Robot tasks on the batched core (socialzoo.env.tasks) and one adapter per ecosystem, generic over
the task: Gymnasium env and VectorEnv, PettingZoo ParallelEnv, SB3 VecEnv, TorchRL EnvBase."""

from __future__ import annotations

from typing import Any

_WHERE = {
    "ActionSelectionEnv": "socialzoo.env.gym_env",
    "ActionSelectionVectorEnv": "socialzoo.env.vector",
    "BatchedCore": "socialzoo.env.core",
    "BlackDeath": "socialzoo.env.parallel",
    "CrowdNavEnv": "socialzoo.env.gym_env",
    "CrowdNavVectorEnv": "socialzoo.env.vector",
    "EnvConfig": "socialzoo.env.config",
    "SocialNavParallelEnv": "socialzoo.env.parallel",
    "Task": "socialzoo.env.tasks.base",
    "TaskEnv": "socialzoo.env.gym_env",
    "TaskParallelEnv": "socialzoo.env.parallel",
    "TaskVectorEnv": "socialzoo.env.vector",
    "make_task": "socialzoo.env.tasks",
    "parallel_env": "socialzoo.env.parallel",
}
__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        import importlib

        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(f"module 'socialzoo.env' has no attribute {name!r}")
