"""Which model drives each person: the people spec of a scenario's crowd and its seeded assignment.

A people spec names one model, or a mix of models with the share of the crowd each drives:
"sf" (the social force, also "social_force"), "orca", "groups" (social force in walking groups),
"learned:PATH" (a learned human policy file), or e.g. "sf@0.5+orca@0.3+groups@0.2". Every
scenario assigns its people to the models from its own seed, the same way every time: the head
counts by largest remainder of share x people, the people by a seeded permutation.

The world reads the result from WorldState.human_model (SOCIAL_FORCE, ORCA, LEARNED) and
WorldState.human_group (walking groups are social-force people with a group).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from socialzoo.core.validation import check_number

# WorldState.human_model values.
SOCIAL_FORCE = 0
ORCA = 1
LEARNED = 2
# The models of a people spec, and the WorldState.human_model each one sets.
MODEL_IDS: dict[str, int] = {"sf": SOCIAL_FORCE, "orca": ORCA, "groups": SOCIAL_FORCE, "learned": LEARNED}
ALIASES: dict[str, str] = {"social_force": "sf"}
# Shares of a mix must sum to 1 within this.
_SUM_TOLERANCE = 1e-9
# Mixed with a scenario's seed for the assignment's generator (apart from the scenario's own).
_ASSIGN_STREAM = 0x706571706C65  # "people"


class PeopleSpecError(ValueError):
    """A people spec that cannot be used: an unknown model, a bad share, shares that do not sum
    to 1, a model named twice, a learned model without its file. The message names the spec."""


@dataclass(frozen=True)
class PeoplePart:
    """One model of a people spec.

    Attributes:
        model: "sf", "orca", "groups" or "learned".
        share: the share of each scenario's people it drives, in (0, 1].
        path: the policy file of a learned model, else None.
    """

    model: str
    share: float
    path: str | None = None

    @property
    def name(self) -> str:
        """The part as a spec names it ("learned:PATH" for a learned model)."""
        return self.model if self.path is None else f"{self.model}:{self.path}"


def parse_people(spec: str) -> tuple[PeoplePart, ...]:
    """The parts of a people spec.

    Raises:
        PeopleSpecError: naming the spec and what is wrong with it.
    """
    if not isinstance(spec, str) or not spec.strip():
        raise PeopleSpecError(
            f"a people spec is a non-empty string such as 'sf' or 'sf@0.5+orca@0.5', got {spec!r}"
        )
    tokens = [t.strip() for t in spec.split("+")]
    parts: list[PeoplePart] = []
    for token in tokens:
        name, share = token, None
        head, at, tail = token.rpartition("@")
        if at:
            try:
                share = float(tail)
            except ValueError:
                raise PeopleSpecError(
                    f"people spec {spec!r}: the share of {head!r} must be a number, got {tail!r}"
                ) from None
            name = head.strip()
        if share is None:
            if len(tokens) > 1:
                raise PeopleSpecError(
                    f"people spec {spec!r}: every model of a mix needs its share, as {token}@0.5"
                )
            share = 1.0
        if not (math.isfinite(share) and 0.0 < share <= 1.0):
            raise PeopleSpecError(
                f"people spec {spec!r}: the share of {name!r} must be in (0, 1], got {share!r}"
            )
        model, sep, path = name.partition(":")
        model = ALIASES.get(model.strip().lower(), model.strip().lower())
        if model not in MODEL_IDS:
            raise PeopleSpecError(
                f"people spec {spec!r}: unknown model {name!r}; known: sf (social_force), orca, groups, learned:PATH"
            )
        if model == "learned" and not path:
            raise PeopleSpecError(f"people spec {spec!r}: name the learned policy file as learned:PATH")
        if model != "learned" and sep:
            raise PeopleSpecError(f"people spec {spec!r}: {model} takes no file")
        parts.append(PeoplePart(model, share, path or None))
    names = [p.model for p in parts]
    if len(set(names)) != len(names):
        raise PeopleSpecError(f"people spec {spec!r} names a model twice")
    total = math.fsum(p.share for p in parts)
    if abs(total - 1.0) > _SUM_TOLERANCE:
        raise PeopleSpecError(f"people spec {spec!r}: the shares sum to {total:g}, not 1")
    return tuple(parts)


@dataclass(frozen=True, kw_only=True)
class PeopleConfig:
    """The people of every scenario: which models drive them, how walking groups form, and
    whether each scenario also runs without the robot (what the robot costs people).

    Attributes:
        models: a people spec (see the module docstring): "sf" (the benchmark's people), "orca",
            "groups", "learned:PATH", or a mix such as "sf@0.5+orca@0.5".
        group_sizes: weights of groups of 2, 3 and 4 people among those of the "groups" model
            (pairs most common, as Moussaid et al. 2010 observed).
        counterfactual: run each scenario also without the robot, beside it in the same batch,
            and report each person's time lost and extra distance walked because of the robot.
    """

    models: str = "sf"
    group_sizes: tuple[float, ...] = (0.6, 0.3, 0.1)
    counterfactual: bool = False

    def __post_init__(self) -> None:
        try:
            parse_people(self.models)
        except PeopleSpecError as err:
            raise PeopleSpecError(f"PeopleConfig.models: {err}") from None
        sizes = tuple(self.group_sizes) if isinstance(self.group_sizes, (list, tuple)) else self.group_sizes
        if not isinstance(sizes, tuple) or len(sizes) != 3:
            raise ValueError(
                f"PeopleConfig.group_sizes must be 3 weights (groups of 2, 3, 4), got {self.group_sizes!r}"
            )
        for k, weight in enumerate(sizes):
            check_number("PeopleConfig", f"group_sizes[{k}]", weight, low=0.0)
        if sum(sizes) <= 0:
            raise ValueError(f"PeopleConfig.group_sizes must not all be 0, got {sizes!r}")
        object.__setattr__(self, "group_sizes", tuple(float(w) for w in sizes))
        if not isinstance(self.counterfactual, bool):
            raise ValueError(f"PeopleConfig.counterfactual must be a bool, got {self.counterfactual!r}")

    @property
    def parts(self) -> tuple[PeoplePart, ...]:
        """The models of the spec with their shares."""
        return parse_people(self.models)

    @property
    def learned_path(self) -> str | None:
        """The learned policy file of the spec, or None."""
        return next((p.path for p in self.parts if p.model == "learned"), None)

    @property
    def has_groups(self) -> bool:
        """Some people walk in groups."""
        return any(p.model == "groups" for p in self.parts)

    @property
    def is_default(self) -> bool:
        """The benchmark's people: social force only, no counterfactual rows."""
        return all(p.model == "sf" for p in self.parts) and not self.counterfactual


def head_counts(shares: list[float], num_people: int) -> np.ndarray:
    """People per model: largest remainder of share x num_people (ties to the earlier model)."""
    quota = np.array(shares, dtype=np.float64) * num_people
    counts = np.floor(quota).astype(np.int64)
    left = num_people - int(counts.sum())
    order = np.argsort(-(quota - counts), kind="stable")
    counts[order[:left]] += 1
    return counts


def assign_models(parts: tuple[PeoplePart, ...], num_people: int, seed: int) -> np.ndarray:
    """(num_people,) the index into `parts` of each person's model, drawn from the scenario seed.

    A single model needs no draw; a mix gives each model its head count (head_counts) and
    shuffles who gets which with a generator of its own, seeded by (seed, a fixed stream).
    """
    if len(parts) == 1:
        return np.zeros(num_people, dtype=np.int64)
    counts = head_counts([p.share for p in parts], num_people)
    kinds = np.repeat(np.arange(len(parts)), counts)
    rng = np.random.default_rng([int(seed), _ASSIGN_STREAM])
    return kinds[rng.permutation(num_people)]
