"""Environment adapters over the batched core: Gymnasium single-agent and vector envs, PettingZoo.

    import gymnasium as gym, socialzoo
    env = gym.make("socialzoo/ActionSelection-v2")

Heavy modules load on first use, so `import socialzoo` stays quick.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "ActionSelectionEnv",
    "ActionSelectionVectorEnv",
    "BlackDeath",
    "EnvConfig",
    "SocialNavCore",
    "SocialNavParallelEnv",
    "parallel_env",
]

_WHERE = {
    "ActionSelectionEnv": "socialzoo.env.benchmark_env",
    "ActionSelectionVectorEnv": "socialzoo.env.vector",
    "BlackDeath": "socialzoo.env.parallel",
    "EnvConfig": "socialzoo.env.config",
    "SocialNavCore": "socialzoo.env.core",
    "SocialNavParallelEnv": "socialzoo.env.parallel",
    "parallel_env": "socialzoo.env.parallel",
}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        import importlib

        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(f"module 'socialzoo.env' has no attribute {name!r}")
