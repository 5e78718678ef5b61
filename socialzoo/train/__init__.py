"""Trainers of the learned baselines: one readable file per algorithm (cleanrl style).

Each trainer module defines a frozen keyword-only dataclass of arguments (every field a command-line
option of `socialzoo train <name>`, with defaults that reproduce the paper's set-up) and a function
`train(args) -> Path` that writes the trained policy and returns its path. Modules import torch and
the learning libraries inside `train`, so listing the trainers stays cheap.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["TRAINERS", "trainer_args", "trainer_function"]

# Trainer name -> "module:ArgsClass"; the module's `train(args)` runs it.
TRAINERS: dict[str, str] = {
    "ppo": "socialzoo.train.ppo:PPOArgs",
    "dqn": "socialzoo.train.dqn:DQNArgs",
    "bc": "socialzoo.train.bc:Args",
    "gail": "socialzoo.train.gail:Args",
    "pips": "socialzoo.train.pips:PipsArgs",
    # Multi-agent: learned humans (MAPPO/IPPO), and robots and humans trained together.
    "humans": "socialzoo.train.humans:HumansArgs",
    "cotrain": "socialzoo.train.cotrain:CotrainArgs",
}


def trainer_args(name: str) -> type:
    """The argument dataclass of trainer `name`.

    Raises:
        ValueError: an unknown trainer (the message lists the known ones).
    """
    if name not in TRAINERS:
        raise ValueError(f"unknown trainer {name!r}; known trainers: {', '.join(sorted(TRAINERS)) or 'none'}")
    module_name, class_name = TRAINERS[name].split(":")
    return getattr(importlib.import_module(module_name), class_name)


def trainer_function(name: str) -> Any:
    """The `train(args)` function of trainer `name`."""
    trainer_args(name)
    return importlib.import_module(TRAINERS[name].split(":")[0]).train
