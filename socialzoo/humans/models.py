"""Which model drives each person: the people spec of a scenario's crowd (`parse_people`) and its seeded
assignment (`assign_models`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from socialzoo.core.validation import check_number
from socialzoo.humans.presets import PRESETS

# WorldState.human_model values.
SOCIAL_FORCE = 0
ORCA = 1
LEARNED = 2
# A recorded person on its track (socialzoo.env.replay writes where it is; no model moves it).
REPLAY = 3
# The models of a people spec, and the WorldState.human_model each one sets.
MODEL_IDS: dict[str, int] = {
    "sf": SOCIAL_FORCE,
    "orca": ORCA,
    "groups": SOCIAL_FORCE,
    "learned": LEARNED,
    "replay": REPLAY,
    "hybrid": REPLAY,
}
# The models a hybrid person may switch to.
REACTING_MODELS = ("sf", "orca", "learned")
# Models only recorded people can have.
RECORDED_MODELS = ("replay", "hybrid")
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
        model: "sf", "orca", "groups", "learned", "replay" or "hybrid".
        share: the share of each scenario's people it drives, in (0, 1].
        path: the policy file of a learned model (a hybrid one's included), else None.
        reacts_as: the model a hybrid person switches to ("sf", "orca" or "learned"), else None.
        preset: the fitted parameters its model walks with (socialzoo.humans.presets: "sf-eth-ucy",
            "orca-eth-ucy"), else None (the world's own).
    """

    model: str
    share: float
    path: str | None = None
    reacts_as: str | None = None
    preset: str | None = None

    @property
    def name(self) -> str:
        """The part as a spec names it ("learned:PATH", "hybrid:sf", "sf-eth-ucy", "hybrid:learned:PATH")."""
        inner = self.model if self.reacts_as is None else self.reacts_as
        inner = self.preset or inner
        inner = inner if self.path is None else f"{inner}:{self.path}"
        return inner if self.reacts_as is None else f"{self.model}:{inner}"

    @property
    def walks_as(self) -> str:
        """The model that moves the person when it is not on its track: reacts_as for a hybrid
        person, the model itself otherwise ("replay": none, it never leaves its track)."""
        return self.reacts_as or self.model


def _model_of(name: str) -> tuple[str, str | None]:
    """(the model, the preset or None) a spec's model name stands for (aliases and presets resolved)."""
    name = ALIASES.get(name.strip().lower(), name.strip().lower())
    return (PRESETS[name]["model"], name) if name in PRESETS else (name, None)


def _learned(token: str) -> bool:
    """Whether a part of a spec names a learned policy's file (learned:PATH, hybrid:learned:PATH)."""
    model, _, rest = token.strip().partition(":")
    return _model_of(model)[0] == "learned" or (
        _model_of(model)[0] == "hybrid" and _model_of(rest.partition(":")[0])[0] == "learned"
    )


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _mix_tokens(spec: str) -> list[str]:
    """The parts of a mix, split at its '+' signs, but a '+' inside a learned policy's file name (a part
    that names no model, after a learned part) stays in that name."""
    tokens: list[str] = []
    for token in spec.split("+"):
        model = _model_of(token.partition(":")[0].partition("@")[0])[0]
        known = model in MODEL_IDS or model in ALIASES
        if tokens and not known and _learned(tokens[-1]):
            tokens[-1] += "+" + token
        else:
            tokens.append(token)
    return [t.strip() for t in tokens]


def parse_people(spec: str) -> tuple[PeoplePart, ...]:
    """The parts of a people spec.

    A people spec names one model, or a mix of models with the share of the crowd each drives:
    "sf" (the social force, also "social_force"), "orca", "groups" (social force in walking groups),
    "learned:PATH" (a learned human policy file), a fitted preset of a model ("sf-eth-ucy",
    "orca-eth-ucy": socialzoo.humans.presets), or e.g. "sf@0.5+orca@0.3+groups@0.2".

    Recorded people (a scene's scenarios, socialzoo.scenarios.recorded) take two more: "replay" (they
    follow their recorded tracks and ignore the robot) and "hybrid:MODEL" with MODEL one of sf, orca
    or learned:PATH (they follow their tracks until a robot comes near, then MODEL walks them along the
    rest of their recorded path; the rule is socialzoo.env.replay's). On a recorded scene the other
    models walk each person from where and when it enters towards where it leaves.

    Raises:
        PeopleSpecError: naming the spec and what is wrong with it.
    """
    if not isinstance(spec, str) or not spec.strip():
        raise PeopleSpecError(
            f"a people spec is a non-empty string such as 'sf' or 'sf@0.5+orca@0.5', got {spec!r}"
        )
    tokens = _mix_tokens(spec)
    parts: list[PeoplePart] = []
    for token in tokens:
        name, share = token, None
        head, at, tail = token.rpartition("@")
        if at and _learned(token) and not _is_number(tail):
            at = ""  # an '@' of a learned policy's file name, not a share
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
        model, preset = _model_of(model)
        if model not in MODEL_IDS:
            raise PeopleSpecError(
                f"people spec {spec!r}: unknown model {name!r}; known: sf (social_force), orca, groups, "
                f"learned:PATH, the presets {', '.join(PRESETS)}, and for recorded people replay and hybrid:MODEL"
            )
        reacts_as = None
        if model == "hybrid":
            inner, _, path = path.partition(":")
            reacts_as, preset = _model_of(inner)
            if reacts_as not in REACTING_MODELS:
                raise PeopleSpecError(
                    f"people spec {spec!r}: a hybrid person reacts as one of {REACTING_MODELS} "
                    f"(hybrid:sf, hybrid:orca, hybrid:learned:PATH), got {name!r}"
                )
            sep = ":" if reacts_as == "learned" else ""
        learned = (reacts_as or model) == "learned"
        if learned and not path:
            raise PeopleSpecError(f"people spec {spec!r}: name the learned policy file as learned:PATH")
        if not learned and sep:
            raise PeopleSpecError(f"people spec {spec!r}: {model} takes no file")
        parts.append(PeoplePart(model, share, path or None, reacts_as, preset))
    names = [p.model for p in parts]
    if len(set(names)) != len(names):
        twice = next(n for n in names if names.count(n) > 1)
        preset = next((p.preset for p in parts if p.model == twice and p.preset), None)
        why = ""
        if preset:
            why = (
                f" (the preset {preset} sets {twice}'s parameters for everyone {twice} walks, so it cannot "
                f"share a crowd with {twice} itself)"
            )
        elif twice == "hybrid":
            why = " (the hybrid people of a crowd react as one model: hybrid:sf, hybrid:orca or hybrid:learned:PATH)"
        raise PeopleSpecError(f"people spec {spec!r} names the model {twice!r} twice{why}")
    files = {p.path for p in parts if p.path is not None}
    if len(files) > 1:
        raise PeopleSpecError(
            f"people spec {spec!r}: learned people share one policy file, got {sorted(files)}"
        )
    total = math.fsum(p.share for p in parts)
    if abs(total - 1.0) > _SUM_TOLERANCE:
        raise PeopleSpecError(f"people spec {spec!r}: the shares sum to {total:g}, not 1")
    return tuple(parts)


@dataclass(frozen=True, kw_only=True)
class PeopleConfig:
    """The people of every scenario: which models drive them, how walking groups form, and
    whether each scenario also runs without the robot (what the robot costs people).

    Attributes:
        models: a people spec (see parse_people): "sf" (the benchmark's people), "orca",
            "groups", "learned:PATH", or a mix such as "sf@0.5+orca@0.5".
        group_sizes: weights of groups of 2, 3 and 4 people among those of the "groups" model
            (pairs most common, as Moussaid et al. 2010 observed).
        counterfactual: run each scenario also without the robot, beside it in the same batch,
            and report each person's time lost and extra distance walked because of the robot.
        react_radius: a hybrid person leaves its track when a robot's centre comes this near, m.
        react_time: ... or when it would meet a robot (their centres within the world's
            collision distance) within this many seconds, both keeping their velocities, s.
    """

    models: str = "sf"
    group_sizes: tuple[float, ...] = (0.6, 0.3, 0.1)
    counterfactual: bool = False
    react_radius: float = 1.5
    react_time: float = 2.0

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
        check_number("PeopleConfig", "react_radius", self.react_radius, low=0.0)
        check_number("PeopleConfig", "react_time", self.react_time, low=0.0)

    @property
    def parts(self) -> tuple[PeoplePart, ...]:
        """The models of the spec with their shares."""
        return parse_people(self.models)

    @property
    def learned_path(self) -> str | None:
        """The learned policy file of the spec, or None."""
        return next((p.path for p in self.parts if p.path is not None), None)

    @property
    def presets(self) -> tuple[str, ...]:
        """The fitted parameter sets the spec names (socialzoo.humans.presets)."""
        return tuple(p.preset for p in self.parts if p.preset is not None)

    @property
    def recorded(self) -> bool:
        """Some people follow recorded tracks (replay or hybrid): only recorded scenes have them."""
        return any(p.model in RECORDED_MODELS for p in self.parts)

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

    The world reads the result from WorldState.human_model (SOCIAL_FORCE, ORCA, LEARNED, REPLAY) and
    WorldState.human_group (walking groups are social-force people with a group).
    """
    if len(parts) == 1:
        return np.zeros(num_people, dtype=np.int64)
    counts = head_counts([p.share for p in parts], num_people)
    kinds = np.repeat(np.arange(len(parts)), counts)
    rng = np.random.default_rng([int(seed), _ASSIGN_STREAM])
    return kinds[rng.permutation(num_people)]
