"""What the imitation trainers (bc, gail) share: their common arguments, and the demonstrations, policy network and
policy files of a run. Free of torch at import, so listing the trainers stays cheap."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.train.checks import (
    Activation,
    check_choice,
    check_eval_trials,
    check_int,
    check_number,
    check_seed,
    check_sizes,
    coerce,
)
from socialzoo.train.skeleton import TrainingRun

# The imitation trainers' arguments that name input files (socialzoo.train.skeleton.Trainer.inputs).
INPUT_FILES: tuple[str, ...] = ("demos", "validation")


@dataclass(frozen=True, kw_only=True)
class ImitationArgs:
    """The arguments every imitation trainer takes; the defaults are BC's, and each trainer states
    where it differs.

    Attributes:
        demos: the demonstration file (`socialzoo demos --episodes 125 --out runs/lfd/ref_demos.npz`).
        steps: demonstration steps used, the first ones of the file (the paper's sizes: 155400,
            116600, 77700, 38800, 3500); None: all of them.
        hidden: hidden layer sizes of the policy MLP.
        activation: hidden activation, tanh or relu.
        lr: Adam learning rate.
        seed: seed of the weights, the minibatch order and anything else the trainer draws.
        out: the run folder: <trainer>.safetensors, run.json, tensorboard/, checkpoints/.
        checkpoint_every: write a checkpoint policy every this many steps of the trainer's unit
            (BC: gradient updates; GAIL: env steps).
        eval_trials: evaluate every checkpoint on this many validation scenarios of the
            demonstrations' map (never a test set; evaluations.csv, TensorBoard eval/*); 0: none.
        threads: torch CPU threads (small networks train fastest on one; more threads on a
            shared machine mostly wait on each other).
        progress: show progress.
    """

    demos: Path = Path("runs/lfd/ref_demos.npz")
    steps: int | None = 155_400
    hidden: tuple[int, ...] = (256, 256)
    activation: Activation = "relu"
    lr: float = 1e-3
    seed: int = 0
    out: Path = Path("runs/imitation")
    checkpoint_every: int = 2000
    eval_trials: int = 0
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        coerce(self, demos=Path, out=Path, hidden=tuple)
        check_int(self, "steps", low=1, optional=True)
        check_int(self, "checkpoint_every", "threads", low=1)
        check_int(self, "eval_trials", low=0)
        check_eval_trials(self, "the demonstrations' map")
        check_seed(self)
        check_sizes(self, "hidden")
        check_choice(self, "activation", Activation)
        check_number(self, "lr", low=0.0, low_open=True)


@dataclass
class ImitationParts:
    """The pieces an imitation run starts from.

    Attributes:
        data: the demonstrations (socialzoo.train.demo_data.DemoSteps).
        stats: the observation normaliser's (mean, var) from the demonstrations.
        generator: the torch Generator of the run's seed (weights, minibatches).
        net: the policy network (normaliser, MLP, one logit per sub-policy).
        save: (path, **training record entries) -> the policy file written as an MlpPolicy.
    """

    data: Any
    stats: tuple[Any, Any]
    generator: Any
    net: Any
    save: Callable[..., Path]


def imitation_parts(run: TrainingRun, args: ImitationArgs, *, max_steps: int | None = None) -> ImitationParts:
    """Load the demonstrations, build the seeded policy network and its saver, and give the run its
    checkpoint evaluator when args.eval_trials asks for one (on the demonstrations' map, in episodes
    of `max_steps`, a trainer's own time limit in its env; None: the benchmark's)."""
    import torch

    from socialzoo.train.demo_data import load_demo_steps
    from socialzoo.train.policy_net import normalizer_stats, policy_header, policy_network, to_mlp_policy
    from socialzoo.train.validation import validation_evaluator

    data = load_demo_steps(args.demos, args.steps)
    stats = normalizer_stats(data.obs)
    generator = torch.Generator().manual_seed(args.seed)
    net = policy_network(data.obs.shape[1], args.hidden, args.activation, stats, generator)
    name = run.trainer.name
    if args.eval_trials:
        limit = {} if max_steps is None else {"max_steps": max_steps}
        run.evaluator = validation_evaluator(
            name, data.map, args.eval_trials, env_overrides={"observation": data.observation, **limit}
        )

    def save(path: Path, **training: Any) -> Path:
        policy = to_mlp_policy(name, net, data.observation, args.activation)
        header = policy_header(name, data, run.record, wall_seconds=run.seconds, **training)
        return policy.save(path, {**header, "training": run.recorded(header["training"])})

    return ImitationParts(data, stats, generator, net, save)
