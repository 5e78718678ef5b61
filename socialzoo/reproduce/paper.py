"""The paper's numbers (SPEC section 10), in one place, for the tables beside ours: the success and LfD tables
re-exported from the code that prints them, plus PIPS's LfD row and the protocol."""

from __future__ import annotations

from socialzoo.bench.tables import PAPER_SUCCESS
from socialzoo.studies.lfd import LFD_SIZES, PAPER_LFD

__all__ = [
    "EXPERIMENT_MAPS",
    "LFD_SIZES",
    "PAPER_LFD",
    "PAPER_LFD_ALL",
    "PAPER_POLICIES",
    "PAPER_PROTOCOL",
    "PAPER_SUCCESS",
    "SPEC_REFERENCE",
    "paper_lfd",
]

SPEC_REFERENCE = "SPEC section 10 (Baselines and experiments)"

# The seven policies of the paper, in its order (SPEC section 10, "Policies").
PAPER_POLICIES: tuple[str, ...] = ("goalone", "ref", "bc", "gail", "pips", "dqn", "ppo")

# Each experiment's map and its index in PAPER_SUCCESS: the training map (0) or the transfer map (1).
EXPERIMENT_MAPS: dict[str, tuple[str, int]] = {"performance": ("gdc1", 0), "transfer": ("ghc3", 1)}

# SPEC section 10, LfD table: "PIPS (3,500) 88/0.16" (success %, average step reward).
PAPER_LFD_PIPS: tuple[int, tuple[float, float]] = (3_500, (88.0, 0.16))
PAPER_LFD_ALL: dict[tuple[str, int], tuple[float, float]] = {
    **PAPER_LFD,
    ("pips", PAPER_LFD_PIPS[0]): PAPER_LFD_PIPS[1],
}

# SPEC section 10, the experiments' protocol.
PAPER_PROTOCOL: dict[str, int] = {
    "rl_total_steps": 84_000,
    "rl_checkpoint_every": 2_000,
    "curve_trials": 100,
    "demo_steps": 155_000,
    "lfd_trials": 100,
    "pips_steps": 3_500,
    "performance_trials": 2_000,
    "transfer_trials": 2_000,
}


def paper_lfd(policy: str, size: int) -> tuple[float, float] | None:
    """The paper's (success %, average step reward) of an LfD policy trained on `size` steps."""
    return PAPER_LFD_ALL.get((policy, size))
