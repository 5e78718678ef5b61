"""Trainers of the learned baselines: one readable file per algorithm (cleanrl style) on one shared skeleton
(socialzoo.train.skeleton: run folder, seed, run record, checkpoints, resume, evaluation, TensorBoard, progress)."""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["TRAINERS", "trainer_args", "trainer_function", "trainer_spec"]

# Trainer name -> "module:ArgsClass"; the module's `train(args)` runs it.
TRAINERS: dict[str, str] = {
    "ppo": "socialzoo.train.ppo:PPOArgs",
    "dqn": "socialzoo.train.dqn:DQNArgs",
    "bc": "socialzoo.train.bc:Args",
    "gail": "socialzoo.train.gail:Args",
    "dagger": "socialzoo.train.dagger:Args",
    # A learned policy file fine-tuned with PPO on the benchmark reward.
    "ppo-finetune": "socialzoo.train.ppo_finetune:Args",
    "pips": "socialzoo.train.pips:PipsArgs",
    # Multi-agent: learned humans (MAPPO/IPPO), and robots and humans trained together.
    "humans": "socialzoo.train.humans:HumansArgs",
    "cotrain": "socialzoo.train.cotrain:CotrainArgs",
    # The CrowdNav task: PPO with attention over people (velocity control).
    "crowdnav": "socialzoo.train.crowdnav:CrowdNavArgs",
    # Learned people cloned from recorded ETH/UCY tracks.
    "people-bc": "socialzoo.train.people_bc:Args",
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


def trainer_spec(name: str) -> Any:
    """What trainer `name` is for the skeleton (its module's TRAINER: socialzoo.train.skeleton.Trainer)."""
    trainer_args(name)
    return importlib.import_module(TRAINERS[name].split(":")[0]).TRAINER
