"""Fitted parameter sets of the crowd models, usable by name in a people spec ("sf-eth-ucy", "orca-eth-ucy", or
"hybrid:sf-eth-ucy"; socialzoo.humans.models), fitted by `socialzoo humans calibrate` (docs/humans.md)."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import Any

from socialzoo.core.config import WorldConfig

PRESETS: dict[str, dict[str, Any]] = {
    # socialzoo humans calibrate --model sf --persons 30 --windows 2 --generations 5 --popsize 6 --seed 0
    "sf-eth-ucy": {
        "model": "sf",
        "human": {
            "relaxation_time": 2.0752,
            "social_strength": 0.3168,
            "social_lambda": 4.6222,
            "social_gamma": 0.2099,
        },
    },
    # socialzoo humans calibrate --model orca --persons 30 --windows 2 --generations 10 --popsize 8 --seed 0
    "orca-eth-ucy": {
        "model": "orca",
        "orca": {"neighbor_dist": 3.8604, "time_horizon": 6.8048, "radius": 0.1593},
    },
}


def with_presets(world: WorldConfig, presets: Iterable[str]) -> WorldConfig:
    """The world with each named preset's parameters in place of its own.

    A preset is its model with some of the world's HumanConfig (social force) or OrcaConfig fields
    replaced; it sets them for everyone that model drives in the world (walking groups share the social
    force's).

    Raises:
        KeyError: an unknown preset (the message lists the known ones).
    """
    for name in presets:
        if name not in PRESETS:
            raise KeyError(f"unknown people preset {name!r}; known: {sorted(PRESETS)}")
        for part in ("human", "orca"):
            if part in PRESETS[name]:
                params = dataclasses.replace(getattr(world, part), **PRESETS[name][part])
                world = dataclasses.replace(world, **{part: params})
    return world
