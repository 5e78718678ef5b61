"""Shared pieces of the trainers' argument dataclasses: option types, and validation whose errors name the trainer,
the field and the value. Free of torch, so listing the trainers stays cheap."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal, get_args

from socialzoo.core import validation

# Hidden-layer activations of the trainers' MLPs (socialzoo.agents.mlp.ACTIVATIONS).
Activation = Literal["tanh", "relu"]


def owner(args: Any) -> str:
    """How messages name a trainer's arguments: the class's name ("PPOArgs"), and for a class named
    plain Args its module's ("bc Args" for socialzoo.train.bc.Args)."""
    name = type(args).__name__
    return f"{type(args).__module__.rsplit('.', 1)[-1]} Args" if name == "Args" else name


def coerce(args: Any, **kinds: Callable[[Any], Any]) -> None:
    """Set each named field of frozen dataclass `args` to kind(its value): out=Path, net_arch=tuple."""
    for name, kind in kinds.items():
        object.__setattr__(args, name, kind(getattr(args, name)))


def check_int(args: Any, *names: str, low: int, high: int | None = None, optional: bool = False) -> None:
    """Raise ValueError unless each args.<name> is an int >= low (<= high if given; or None when
    optional)."""
    for name in names:
        validation.check_int(owner(args), name, getattr(args, name), low=low, high=high, allow_none=optional)


# The largest seed a trainer takes: torch.manual_seed's, and for the trainers on Stable-Baselines3,
# which also seeds numpy's legacy generator (np.random.seed), that generator's.
MAX_SEED = 2**64 - 1
MAX_SB3_SEED = 2**32 - 1


def check_seed(args: Any, high: int = MAX_SEED) -> None:
    """Raise ValueError unless args.seed is an int in [0, high] (a larger one ended the run in a
    traceback when the trainer seeded torch or numpy)."""
    check_int(args, "seed", low=0, high=high)


def check_number(
    args: Any,
    *names: str,
    low: float,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> None:
    """Raise ValueError unless each args.<name> is a finite number >= low (> low with low_open),
    <= high if given (< high with high_open)."""
    for name in names:
        value = getattr(args, name)
        validation.check_number(
            owner(args), name, value, low=low, high=high, low_open=low_open, high_open=high_open
        )


def check_sizes(args: Any, *names: str, low: int = 1) -> None:
    """Raise ValueError unless each args.<name> is a non-empty sequence of ints >= low (layer sizes,
    demonstration sizes)."""
    for name in names:
        value = getattr(args, name)
        if not value or any(not isinstance(n, int) or isinstance(n, bool) or n < low for n in value):
            raise ValueError(f"{owner(args)}.{name} must be ints >= {low}, got {value!r}")


def check_choice(args: Any, name: str, choices: Any) -> None:
    """Raise ValueError unless args.<name> is one of `choices`, a collection or the Literal type of
    the field (the message lists them)."""
    validation.check_choice(owner(args), name, getattr(args, name), get_args(choices) or choices)


def check_minibatch(args: Any, name: str, pool: int, what: str) -> None:
    """Raise ValueError unless the minibatch size args.<name> is at most `pool`, the samples it is
    drawn from (a rollout or a replay buffer, named by `what`): SB3's PPO would take the whole
    rollout as its minibatch and DQN draw the buffer's transitions again and again, each training
    otherwise than its run record says."""
    value = getattr(args, name)
    if value > pool:
        raise ValueError(f"{owner(args)}.{name} ({value}) must be at most {what} ({pool})")


def check_eval_trials(args: Any, where: str, family: str | None = None) -> None:
    """Raise ValueError unless args.eval_trials is at most the validation cases a checkpoint evaluation
    can play (socialzoo.train.validation): those of scenario family `family`'s validation split, else
    the training map's validation set ("<map>-val", VALIDATION_SIZE scenarios on any map), the map
    named by `where` ("map 'gdc1'"). More failed at the run's first evaluation, after training up to it."""
    from socialzoo.bench.test_sets import family_validation_size
    from socialzoo.scenarios.scenario_sets import VALIDATION_SIZE

    cases = VALIDATION_SIZE if family is None else family_validation_size(family)
    if args.eval_trials > cases:
        of = where if family is None else f"family {family!r}"
        raise ValueError(
            f"{owner(args)}.eval_trials ({args.eval_trials}) is more than the {cases} validation cases of {of}"
        )


def check_whole_batches(args: Any, name: str, batch: int, what: str) -> None:
    """Raise ValueError unless args.<name>, the steps to train, is a multiple of `batch`, the steps one
    iteration collects (named by `what`): a collector stops after whole batches, so any other count
    trained up to a batch more than asked."""
    if getattr(args, name) % batch:
        raise ValueError(
            f"{owner(args)}.{name} ({getattr(args, name)}) must be a multiple of {what} ({batch})"
        )


def check_block(args: Any, block: int, what: str) -> None:
    """Raise ValueError unless args.checkpoint_every and args.total_steps are multiples of `block` env
    steps (a rollout, or a training interval, named by `what`), so that each checkpoint holds the policy
    at its step."""
    for name in ("checkpoint_every", "total_steps"):
        if getattr(args, name) % block:
            raise ValueError(
                f"{owner(args)}.{name} ({getattr(args, name)}) must be a multiple of {what} ({block})"
            )
