"""The reference code's quirks (SPEC section 11) as switches: socialzoo follows the paper by
default, and `ReferenceQuirks.reference()` turns on what social_gym 1.0 did instead."""

from __future__ import annotations

from dataclasses import dataclass, fields


@dataclass(frozen=True, kw_only=True)
class ReferenceQuirks:
    """What the reference implementation did where it departed from the paper.

    Each switch is off by default, so a config without quirks runs exactly the documented
    benchmark; the `socialzoo/ActionSelectionReference-v2` ids (socialzoo.env.registration) turn
    all of them on.

    Attributes:
        goal_distance_x_only: the distance gained d_g measures the goal distance along the world x
            axis only, d_g = |x_{t-1} - x_g| - |x_t - x_g| (the reference's goal distance was
            |x_robot - x_goal|); progress along y is worth nothing. Success still needs the
            Euclidean goal radius.
        collision_penalty_dropped: the collision term is computed but never added, whatever
            `RewardConfig.w_collision` says (with the default weight 0 this changes nothing).
        reward_distance_plus_bonus: the reward the reference's learners saw, by a type slip:
            r = w1 * d_g + (c if success), the progress term (w1 = 5, or 10 when d_g < 0) and the
            success bonus only; blame, force and collision terms are not added. SPEC section 11
            names the terms ("distance gained + bonus"), not the weights: the progress weights of
            `RewardConfig` are kept. Every reward of the env changes, so the metric "average step
            reward" is this reward too.
        human_theta_index: the socialgym1 layout's human "theta" entry holds the person's index
            (its slot in the world's person arrays, which is the slot the reference's unsorted
            layout gave it) instead of 0; empty and occluded slots stay 0. The paper layout has no
            such entry and does not change.
        ppo_eval_without_normalisation: PPO trained with observation normalisation is evaluated
            without it (the raw observations fed to the network trained on normalised ones). A
            switch of the evaluation, not of the env: the env's rollouts do not change; the
            reproduction (socialzoo.reproduce, `--reference`) evaluates PPO's policy file through
            `socialzoo.agents.mlp.without_normalisation` when the evaluation env's config has it on.
    """

    goal_distance_x_only: bool = False
    collision_penalty_dropped: bool = False
    reward_distance_plus_bonus: bool = False
    human_theta_index: bool = False
    ppo_eval_without_normalisation: bool = False

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, bool):
                raise ValueError(f"ReferenceQuirks.{f.name} must be a bool, got {value!r}")

    @classmethod
    def reference(cls) -> ReferenceQuirks:
        """Every quirk on: the reference code's behaviour."""
        return cls(**{f.name: True for f in fields(cls)})

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The switches, in declaration order."""
        return tuple(f.name for f in fields(cls))

    @property
    def any(self) -> bool:
        """True when at least one quirk is on."""
        return any(getattr(self, name) for name in self.names())

    @property
    def trains(self) -> bool:
        """True when a quirk of the env a learner trains in is on (every switch but the evaluation's
        EVALUATION_QUIRKS): a policy trained without them is another policy."""
        return any(getattr(self, name) for name in self.names() if name not in EVALUATION_QUIRKS)

    @classmethod
    def named(cls, name: str) -> ReferenceQuirks:
        """The quirk set `name`: ALL_QUIRKS (every quirk, `reference()`) or one switch alone.

        Raises:
            ValueError: an unknown name (listing the known ones).
        """
        if name == ALL_QUIRKS:
            return cls.reference()
        if name not in cls.names():
            raise ValueError(
                f"unknown reference quirk {name!r}; known: {', '.join((ALL_QUIRKS, *cls.names()))}"
            )
        return cls(**{name: True})

    @property
    def drops_collision(self) -> bool:
        """True when the collision term is left out of the reward (either switch does it)."""
        return self.collision_penalty_dropped or self.reward_distance_plus_bonus


# The switches of the evaluation alone (the env's rollouts do not change with them).
EVALUATION_QUIRKS: tuple[str, ...] = ("ppo_eval_without_normalisation",)
# The name of the set of every quirk together (`ReferenceQuirks.named`).
ALL_QUIRKS = "all"
# Each switch in a few words, for tables and notes.
QUIRK_LABELS: dict[str, str] = {
    "goal_distance_x_only": "goal distance along x only",
    "collision_penalty_dropped": "collision penalty dropped",
    "reward_distance_plus_bonus": 'reward "distance gained + bonus"',
    "human_theta_index": "a person's index as its theta",
    "ppo_eval_without_normalisation": "PPO evaluated without its normalisation",
}

REFERENCE_QUIRKS = ReferenceQuirks.reference()
"""Every quirk on (the `reference` preset of the ActionSelectionReference ids)."""
