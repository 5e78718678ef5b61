"""Behaviour cloning (BC) of the reference policy's demonstrations with TorchRL's BCLoss."""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.nav.subpolicies import NUM_ACTIONS
from socialzoo.train.checks import check_int, check_number
from socialzoo.train.imitation import INPUT_FILES, ImitationArgs, imitation_parts
from socialzoo.train.skeleton import Trainer, TrainingRun, run_training

TRAINER = Trainer("bc", policy_file="bc.safetensors", inputs=INPUT_FILES)


@dataclass(frozen=True, kw_only=True)
class Args(ImitationArgs):
    """Behaviour cloning of Ref demonstrations (TorchRL BCLoss).

    The arguments every imitation trainer takes are socialzoo.train.imitation.ImitationArgs (their
    defaults are this trainer's); these are BC's own.

    Attributes:
        out: run folder: bc.safetensors, run.json, tensorboard/, checkpoints/.
        checkpoint_every: write a checkpoint policy every this many gradient updates.
        epochs: passes over the demonstration steps.
        min_updates: at least this many gradient updates (more passes for small sets).
        batch_size: demonstration steps per gradient update.
        weight_decay: Adam weight decay (L2).
        validation: another demonstration file whose action agreement is logged each pass
            (reported only, never used to choose anything); None: none.
    """

    out: Path = Path("runs/bc")
    epochs: int = 10
    min_updates: int = 2000
    batch_size: int = 512
    weight_decay: float = 0.0
    validation: Path | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.validation is not None:
            object.__setattr__(self, "validation", Path(self.validation))
        check_int(self, "epochs", "batch_size", low=1)
        check_int(self, "min_updates", low=0)
        check_number(self, "weight_decay", low=0.0)


def agreement(net: Any, obs: np.ndarray, action: np.ndarray, batch: int = 8192) -> float:
    """Fraction of steps where the network's greedy action equals the demonstrated one."""
    import torch

    hits = 0
    with torch.no_grad():
        for lo in range(0, len(obs), batch):
            logits = net(torch.as_tensor(obs[lo : lo + batch]))
            hits += int((logits.argmax(-1).numpy() == action[lo : lo + batch]).sum())
    return hits / max(len(obs), 1)


def agreements(net: Any, obs: np.ndarray, action: np.ndarray, validation: Any) -> dict[str, float]:
    """The network's `agreement` with (obs, action), "train_agreement", and with the demonstrations
    `validation` (DemoSteps or None), "validation_agreement" (only when given)."""
    found = {"train_agreement": agreement(net, obs, action)}
    if validation is not None:
        found["validation_agreement"] = agreement(net, validation.obs, validation.action)
    return found


def train(args: Args) -> Path:
    """Run behaviour cloning on the trainer skeleton; returns bc.safetensors (a finished run of the
    same arguments in args.out is reused; a short demonstration file raises ValueError).

    `socialzoo train bc --demos FILE --steps N --out DIR` fits a policy network (fixed observation normaliser
    from the demonstrations, then an MLP giving one logit per sub-policy) to the first N demonstration steps
    by minimising the negative log-likelihood of the demonstrated actions (BCLoss on a TorchRL
    ProbabilisticActor over one-hot actions, i.e. cross-entropy), and writes DIR/bc.safetensors (an MlpPolicy
    file: greedy actions), DIR/run.json, TensorBoard logs and a checkpoint every `checkpoint_every` gradient
    updates. Demonstrations come from `socialzoo demos` (Ref on gdc1 scenarios of their own seeds, never a
    test set).
    """
    return run_training(TRAINER, args, lambda run: _fit(run, args))


def bc_loss_module(net: Any) -> Any:
    """TorchRL's BCLoss on a ProbabilisticActor over `net`'s logits (cross-entropy)."""
    from torchrl.objectives import BCLoss

    from socialzoo.train.policy_net import make_actor

    with warnings.catch_warnings():
        # TorchRL's LossModule warns about a target-network attribute that BCLoss never declares.
        warnings.filterwarnings(
            "ignore", message="The name target_actor_network_params", category=UserWarning
        )
        return BCLoss(make_actor(net))


def update_count(steps: int, args: Args) -> int:
    """Gradient updates of a fit to `steps` demonstration steps: args.epochs passes, at least
    args.min_updates."""
    return max(args.epochs * math.ceil(steps / args.batch_size), args.min_updates)


def fit_actions(
    loss_module: Any,
    obs: np.ndarray,
    action: np.ndarray,
    args: Args,
    generator: Any,
    *,
    after_update: Callable[[int, float], None] | None = None,
    after_pass: Callable[[int, float], None] | None = None,
) -> float:
    """Fit the policy to (obs, action) pairs: update_count(len(obs), args) Adam updates of BCLoss
    on minibatches of args.batch_size in a fresh `generator` order each pass.

    Args:
        loss_module: bc_loss_module(net).
        obs: (N, D) float32 observations.
        action: (N,) int64 sub-policy indices.
        args: the optimiser settings (lr, weight_decay, batch_size, epochs, min_updates).
        generator: the run's torch Generator (the minibatch order).
        after_update: called with (updates done, loss) after each update.
        after_pass: called with (updates done, loss) after each pass over the data.

    Returns:
        The last minibatch's loss.
    """
    import torch
    from tensordict import TensorDict
    from torchrl.envs.utils import ExplorationType, set_exploration_type

    optimizer = torch.optim.Adam(loss_module.parameters(), lr=args.lr, weight_decay=args.weight_decay)
    obs_t = torch.as_tensor(obs)
    one_hot = torch.as_tensor(np.eye(NUM_ACTIONS, dtype=np.float32)[action])
    n = len(obs_t)
    updates = update_count(n, args)
    step, loss_value = 0, float("nan")
    with set_exploration_type(ExplorationType.DETERMINISTIC):
        while step < updates:
            order = torch.randperm(n, generator=generator)
            for lo in range(0, n, args.batch_size):
                if step >= updates:
                    break
                idx = order[lo : lo + args.batch_size]
                batch = TensorDict(observation=obs_t[idx], action=one_hot[idx], batch_size=[len(idx)])
                loss = loss_module(batch)["loss_bc"]
                optimizer.zero_grad()
                loss.backward()
                optimizer.step()
                step += 1
                loss_value = loss.item()
                if after_update is not None:
                    after_update(step, loss_value)
            if after_pass is not None:
                after_pass(step, loss_value)
    return loss_value


def _fit(run: TrainingRun, args: Args) -> Mapping[str, Any]:
    from socialzoo.train.demo_data import load_demo_steps

    parts = imitation_parts(run, args)
    data, net = parts.data, parts.net
    validation = load_demo_steps(args.validation) if args.validation is not None else None
    updates = update_count(len(data), args)
    schedule = run.schedule(updates, args.checkpoint_every)
    bar = run.progress(updates, unit="update")
    writer = run.writer

    def after_update(step: int, loss: float) -> None:
        bar.update(1)
        if step % 50 == 0 or step == updates:
            writer.add_scalar("bc/loss", loss, step)
        for due in schedule.due(step):
            run.checkpoint(due, functools.partial(parts.save, updates=due))

    def after_pass(step: int, loss: float) -> None:
        found = agreements(net, data.obs, data.action, validation)
        for key, value in found.items():
            writer.add_scalar(f"bc/{key}", value, step)
        bar.set_postfix(loss=f"{loss:.3f}", agree=f"{found['train_agreement']:.3f}")

    fit_actions(
        bc_loss_module(net), data.obs, data.action, args, parts.generator,
        after_update=after_update, after_pass=after_pass,
    )  # fmt: skip
    parts.save(run.policy, updates=updates)
    return {
        "updates": updates,
        "demonstration_steps": len(data),
        **agreements(net, data.obs, data.action, validation),
    }
