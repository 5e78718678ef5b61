"""The reproduction's parts and settings: the full protocol (SPEC section 10) and `--quick`, with the hash that
names the folder DIR/<hash>/ holding a run's items."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from socialzoo.core.validation import check_fields, check_int, unknown_fields
from socialzoo.studies.lfd import LFD_SIZES

# The parts, in the order they run (later parts reuse what earlier ones trained).
PARTS: tuple[str, ...] = ("demos", "rl-curves", "lfd", "performance", "transfer")
# The part that `--reference` adds after the chosen ones (socialzoo.reproduce.parts.run_reference):
# the learned rows with the reference code's quirks; never run unless asked for.
REFERENCE_PART = "reference"
# Bumped when the layout of DIR/<hash>/ changes, so old items are never read as current ones.
LAYOUT_VERSION = 1


def _frozen(mapping: Mapping[str, Mapping[str, Any]]) -> Mapping[str, Mapping[str, Any]]:
    return MappingProxyType({k: MappingProxyType(dict(v)) for k, v in mapping.items()})


@dataclass(frozen=True, kw_only=True)
class Settings:
    """What a reproduction trains and evaluates.

    Attributes:
        name: "full" (the paper's protocol) or "quick" (a small version of everything).
        seed: the first training seed; run k of every learned policy has seed `seed + k`.
        seeds: training seeds of every learned policy (PPO, DQN, BC and GAIL at every LfD size,
            PIPS): each seed is its own run folder, its own policy file and its own trials.
        select_trials: validation scenarios (the training map's "<map>-val", never a test set) on
            which PPO and DQN checkpoints are evaluated while they train; the kept policy of a
            run (the one of `performance` and `transfer`) is its best validation checkpoint.
            0: the final policy is kept.
        select_every: evaluate a checkpoint every this many training steps (a multiple of
            rl_checkpoint_every; the last checkpoint is evaluated too).
        seed_trials: scenarios of each test set on which seeds after the first are evaluated in
            `performance` and `transfer` (the first ones; None: all of them). The aggregates
            over seeds use the scenarios every seed ran.
        rl_total_steps: PPO and DQN training steps.
        rl_checkpoint_every: steps between their checkpoints.
        rl_overrides: per trainer ("ppo", "dqn"), extra trainer arguments.
        curve_trials: gdc1-test scenarios per checkpoint (the first ones).
        demo_episodes: Ref demonstration episodes (their own seeds, not a test set).
        demo_env_overrides: EnvConfig overrides of the demonstration env.
        lfd_sizes: demonstration steps BC and GAIL train on (largest first).
        lfd_overrides: per trainer ("bc", "gail", "pips"), extra trainer arguments.
        pips_steps: demonstration steps PIPS synthesises from.
        lfd_trials: gdc1-test scenarios per LfD policy.
        performance_trials: gdc1-test scenarios per policy.
        transfer_trials: ghc3-test scenarios per policy.
        eval_env_overrides: EnvConfig overrides of every evaluation env.
        workers: local evaluation processes (or Ray chunks).
        batch_size: env rows stepped together per evaluation worker.
    """

    name: str = "full"
    seed: int = 0
    seeds: int = 1
    select_trials: int = 100
    select_every: int = 12_000
    seed_trials: int | None = None
    rl_total_steps: int = 84_000
    rl_checkpoint_every: int = 2_000
    rl_overrides: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    curve_trials: int = 100
    demo_episodes: int = 125
    demo_env_overrides: Mapping[str, Any] = field(default_factory=dict)
    lfd_sizes: tuple[int, ...] = LFD_SIZES
    lfd_overrides: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    pips_steps: int = 3_500
    lfd_trials: int = 100
    performance_trials: int = 2_000
    transfer_trials: int = 2_000
    eval_env_overrides: Mapping[str, Any] = field(default_factory=dict)
    workers: int = 2
    # 256 rows: a step costs about a third less per row than at 64 (benchmarks/reproduce_profile.py).
    batch_size: int = 256

    def __post_init__(self) -> None:
        if self.name not in ("full", "quick"):
            raise ValueError(f"Settings.name must be 'full' or 'quick', got {self.name!r}")
        # Every int field > 0, but the first seed and select_trials (0: keep the final policy).
        check_fields(self, nonnegative=("seed", "select_trials"))
        check_int("Settings", "seed_trials", self.seed_trials, low=1, allow_none=True)
        if self.select_every % self.rl_checkpoint_every:
            raise ValueError(
                f"Settings.select_every ({self.select_every}) must be a multiple of "
                f"rl_checkpoint_every ({self.rl_checkpoint_every})"
            )
        object.__setattr__(self, "lfd_sizes", tuple(self.lfd_sizes))
        if not self.lfd_sizes:
            raise ValueError("Settings.lfd_sizes is empty")
        for size in self.lfd_sizes:
            check_int("Settings", "lfd_sizes", size, low=1)
        for name, known in (("rl_overrides", ("ppo", "dqn")), ("lfd_overrides", ("bc", "gail", "pips"))):
            value = getattr(self, name)
            bad = sorted(set(value) - set(known))
            if bad:
                raise ValueError(f"Settings.{name} names unknown trainers {bad}; known: {list(known)}")
            object.__setattr__(self, name, _frozen(value))
        object.__setattr__(self, "demo_env_overrides", MappingProxyType(dict(self.demo_env_overrides)))
        object.__setattr__(self, "eval_env_overrides", MappingProxyType(dict(self.eval_env_overrides)))

    @property
    def seed_list(self) -> tuple[int, ...]:
        """The training seeds, in order: seed, seed + 1, ..., seed + seeds - 1."""
        return tuple(range(self.seed, self.seed + self.seeds))

    @property
    def lfd_largest(self) -> int:
        """The demonstration size of the BC and GAIL policies in the performance experiments."""
        return max(self.lfd_sizes)

    def to_json(self) -> dict[str, Any]:
        """Plain JSON form (sorted mappings), the input of `settings_hash`."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, Mapping):
                value = {k: dict(v) if isinstance(v, Mapping) else v for k, v in value.items()}
            elif isinstance(value, tuple):
                value = list(value)
            out[f.name] = value
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Settings:
        """Settings from `to_json`'s form.

        Raises:
            ValueError: unknown fields (named).
        """
        error = unknown_fields("Settings", data, [f.name for f in dataclasses.fields(cls)])
        if error is not None:
            raise error
        return cls(**dict(data))


# Fields left out of the hash. workers and batch_size decide how fast, not what: evaluation results
# do not depend on how trials are split. seed_trials decides how far the later seeds' evaluation
# goes, not what any stored item holds: each trial is stored once per scenario, so a rerun with a
# larger value plays only the scenarios still missing (the trained seeds are reused), and one with
# a smaller value reads the first ones (socialzoo.studies.seeds.benchmark_scores).
VOLATILE_FIELDS: tuple[str, ...] = ("workers", "batch_size", "seed_trials")


def settings_hash(settings: Settings) -> str:
    """12 hex digits naming the settings (and the folder layout): DIR/<hash>/ holds their items.

    A rerun with other settings never reads items stored under different ones. How the run is carried
    out (parts chosen, backend, progress bars) is not a setting and does not change the hash, nor are
    the fields of VOLATILE_FIELDS (how fast, and how many test scenarios the later seeds play).
    """
    data = {k: v for k, v in settings.to_json().items() if k not in VOLATILE_FIELDS}
    text = json.dumps({"layout": LAYOUT_VERSION, "settings": data}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def full_settings(**changes: Any) -> Settings:
    """The paper's protocol (SPEC section 10) with the trainers' own defaults."""
    return Settings(name="full", **changes)


def quick_settings(**changes: Any) -> Settings:
    """A small version of everything, a few minutes on 2 cores: tiny trainings on training
    scenarios, and the first few test scenarios (with a shorter time limit) for evaluation."""
    base: dict[str, Any] = {
        "name": "quick",
        "rl_total_steps": 400,
        "rl_checkpoint_every": 200,
        "select_trials": 2,
        "select_every": 200,
        "rl_overrides": {
            # Validation episodes (select_trials) as short as the training ones.
            "ppo": {
                "num_envs": 4,
                "n_steps": 50,
                "n_epochs": 1,
                "max_steps": 400,
                "env_overrides": {"max_steps": 400},
            },
            "dqn": {"max_steps": 400, "learning_starts": 50, "env_overrides": {"max_steps": 400}},
        },
        "curve_trials": 2,
        "demo_episodes": 2,
        "demo_env_overrides": {"max_steps": 800},
        "lfd_sizes": (1_000, 300),
        "lfd_overrides": {
            "bc": {"min_updates": 20, "epochs": 1, "batch_size": 128},
            "gail": {
                "total_steps": 400,
                "num_envs": 4,
                "rollout_len": 50,
                "minibatch": 100,
                "max_episode_steps": 400,
                "ppo_epochs": 1,
                "disc_epochs": 1,
            },
            "pips": {
                "max_depth": 1,
                "beam": 4,
                "pool": 4,
                "partners": 20,
                "solver": "exact",
                "time_budget_s": 10.0,
                "heldout_steps": 0,
            },
        },
        "pips_steps": 1_000,
        "lfd_trials": 2,
        "performance_trials": 2,
        "transfer_trials": 2,
        # 30 s episodes: long enough for GoAlone and Ref to reach most goals.
        "eval_env_overrides": {"max_steps": 1200},
        # One in-process worker: for a handful of trials, starting processes costs more than it saves.
        "workers": 1,
        "batch_size": 8,
    }
    base.update(changes)
    return Settings(**base)


def parse_parts(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """The parts named by --only ("rl-curves,lfd"), in run order; None or empty: every part.

    Raises:
        ValueError: an unknown part (the message lists the known ones).
    """
    if text is None:
        return PARTS
    names = [n.strip() for n in (text.split(",") if isinstance(text, str) else text) if n.strip()]
    if not names:
        return PARTS
    bad = [n for n in names if n not in PARTS]
    if bad:
        raise ValueError(f"unknown part(s) {', '.join(map(repr, bad))}; the parts are: {', '.join(PARTS)}")
    return tuple(p for p in PARTS if p in names)


def reference_sets(value: bool | str | Sequence[str] | None) -> tuple[str, ...]:
    """The quirk sets of the reference part (`--reference [SETS]`): none for False, None or no names,
    every quirk together ("all") for True, else the named sets in the order given, each once.

    Raises:
        ValueError: an unknown quirk (socialzoo.env.quirks.ReferenceQuirks.named names the known ones).
    """
    from socialzoo.env.quirks import ALL_QUIRKS, ReferenceQuirks

    if value is None or value is False:
        return ()
    if value is True:
        return (ALL_QUIRKS,)
    names = [n.strip() for n in (value.split(",") if isinstance(value, str) else value) if n.strip()]
    for name in names:
        ReferenceQuirks.named(name)
    return tuple(dict.fromkeys(names))
