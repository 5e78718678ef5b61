"""Behaviour cloning (BC) of the reference policy's demonstrations with TorchRL's BCLoss.

`socialzoo train bc --demos FILE --steps N --out DIR` fits a policy network (fixed observation
normaliser from the demonstrations, then an MLP giving one logit per sub-policy) to the first N
demonstration steps by minimising the negative log-likelihood of the demonstrated actions
(BCLoss on a TorchRL ProbabilisticActor over one-hot actions, i.e. cross-entropy), and writes
DIR/bc.safetensors (an MlpPolicy file: greedy actions), DIR/run.json, TensorBoard logs and a
checkpoint every `checkpoint_every` gradient updates. Demonstrations come from `socialzoo demos`
(Ref on gdc1 scenarios of their own seeds, never a test set).
"""

from __future__ import annotations

import logging
import math
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.train.checks import Activation, check_int, check_number, check_sizes

logger = logging.getLogger(__name__)

POLICY_FILE = "bc.safetensors"


@dataclass(frozen=True, kw_only=True)
class Args:
    """Behaviour cloning of Ref demonstrations (TorchRL BCLoss).

    Attributes:
        demos: the demonstration file (`socialzoo demos --episodes 125 --out runs/lfd/ref_demos.npz`).
        steps: demonstration steps used, the first ones of the file (the paper's sizes: 155400,
            116600, 77700, 38800, 3500); None: all of them.
        hidden: hidden layer sizes of the policy MLP.
        activation: hidden activation, tanh or relu.
        epochs: passes over the demonstration steps.
        min_updates: at least this many gradient updates (more passes for small sets).
        batch_size: demonstration steps per gradient update.
        lr: Adam learning rate.
        weight_decay: Adam weight decay (L2).
        validation: another demonstration file whose action agreement is logged each pass
            (reported only, never used to choose anything); None: none.
        seed: seed of the weights and of the minibatch order.
        out: run folder: bc.safetensors, run.json, tensorboard/, checkpoints/.
        checkpoint_every: write a checkpoint policy every this many gradient updates.
        threads: torch CPU threads (small networks train fastest on one; more threads on a
            shared machine mostly wait on each other).
        progress: show a progress bar.
    """

    demos: Path = Path("runs/lfd/ref_demos.npz")
    steps: int | None = 155_400
    hidden: tuple[int, ...] = (256, 256)
    activation: Activation = "relu"
    epochs: int = 10
    min_updates: int = 2000
    batch_size: int = 512
    lr: float = 1e-3
    weight_decay: float = 0.0
    validation: Path | None = None
    seed: int = 0
    out: Path = Path("runs/bc")
    checkpoint_every: int = 2000
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "demos", Path(self.demos))
        object.__setattr__(self, "out", Path(self.out))
        object.__setattr__(self, "hidden", tuple(self.hidden))
        if self.validation is not None:
            object.__setattr__(self, "validation", Path(self.validation))
        check_int(self, "steps", 1, optional=True)
        for name in ("epochs", "batch_size", "checkpoint_every", "threads"):
            check_int(self, name, 1)
        for name in ("min_updates", "seed"):
            check_int(self, name, 0)
        check_sizes(self, "hidden")
        if self.activation not in ("tanh", "relu"):
            raise ValueError(f"bc Args.activation must be 'tanh' or 'relu', got {self.activation!r}")
        check_number(self, "lr", 0.0, strict=True)
        check_number(self, "weight_decay", 0.0)


def agreement(net: Any, obs: np.ndarray, action: np.ndarray, batch: int = 8192) -> float:
    """Fraction of steps where the network's greedy action equals the demonstrated one."""
    import torch

    hits = 0
    with torch.no_grad():
        for lo in range(0, len(obs), batch):
            logits = net(torch.as_tensor(obs[lo : lo + batch]))
            hits += int((logits.argmax(-1).numpy() == action[lo : lo + batch]).sum())
    return hits / max(len(obs), 1)


def train(args: Args) -> Path:
    """Run behaviour cloning; returns the policy file (an existing finished run is reused).

    Raises:
        ValueError: a demonstration file with fewer than args.steps steps.
        socialzoo.train.run_dir.RunDirError: args.out holds a run of other arguments.
    """
    from socialzoo.train.policy_net import torch_threads

    with torch_threads(args.threads):
        return _train(args)


def _train(args: Args) -> Path:
    import torch
    from tensordict import TensorDict
    from torchrl.envs.utils import ExplorationType, set_exploration_type
    from torchrl.objectives import BCLoss

    from socialzoo.train.demo_data import load_demo_steps
    from socialzoo.train.policy_net import (
        make_actor,
        normalizer_stats,
        policy_header,
        policy_network,
        to_mlp_policy,
    )
    from socialzoo.train.run_dir import RunDir, checkpoint_steps, progress_bar

    run = RunDir(args.out, "bc", args, volatile=("progress", "threads"))
    final = run.path / POLICY_FILE
    if run.finished and final.exists():
        logger.info("bc: %s is a finished run; nothing to do", run.path)
        return final
    start = time.perf_counter()
    data = load_demo_steps(args.demos, args.steps)
    validation = load_demo_steps(args.validation) if args.validation is not None else None
    generator = torch.Generator().manual_seed(args.seed)
    net = policy_network(
        data.obs.shape[1], args.hidden, args.activation, normalizer_stats(data.obs), generator
    )
    with warnings.catch_warnings():
        # TorchRL's LossModule warns about a target-network attribute that BCLoss never declares.
        warnings.filterwarnings(
            "ignore", message="The name target_actor_network_params", category=UserWarning
        )
        loss_module = BCLoss(make_actor(net))
    optimizer = torch.optim.Adam(loss_module.parameters(), lr=args.lr, weight_decay=args.weight_decay)
    obs = torch.as_tensor(data.obs)
    actions = torch.as_tensor(data.one_hot())
    n = len(data)
    per_epoch = math.ceil(n / args.batch_size)
    updates = max(args.epochs * per_epoch, args.min_updates)
    checkpoints = set(checkpoint_steps(updates, args.checkpoint_every))

    def save(path: Path) -> Path:
        policy = to_mlp_policy("bc", net, data.observation, args.activation)
        header = policy_header("bc", data, run.record, updates=step, wall_seconds=time.perf_counter() - start)
        return policy.save(path, header)

    step = 0
    bar = progress_bar(updates, "bc", args.progress, unit="update")
    with run.tensorboard() as writer, set_exploration_type(ExplorationType.DETERMINISTIC):
        while step < updates:
            order = torch.randperm(n, generator=generator)
            for lo in range(0, n, args.batch_size):
                if step >= updates:
                    break
                idx = order[lo : lo + args.batch_size]
                batch = TensorDict(observation=obs[idx], action=actions[idx], batch_size=[len(idx)])
                loss = loss_module(batch)["loss_bc"]
                optimizer.zero_grad()
                loss.backward()
                optimizer.step()
                step += 1
                bar.update(1)
                if step % 50 == 0 or step == updates:
                    writer.add_scalar("bc/loss", loss.item(), step)
                if step in checkpoints:
                    save(run.checkpoint_path(step, ".safetensors"))
            train_agreement = agreement(net, data.obs, data.action)
            writer.add_scalar("bc/train_agreement", train_agreement, step)
            bar.set_postfix(loss=f"{loss.item():.3f}", agree=f"{train_agreement:.3f}")
            if validation is not None:
                writer.add_scalar(
                    "bc/validation_agreement", agreement(net, validation.obs, validation.action), step
                )
    bar.close()
    path = save(final)
    results: dict[str, Any] = {
        "policy": str(path),
        "updates": updates,
        "demonstration_steps": n,
        "train_agreement": agreement(net, data.obs, data.action),
        "wall_seconds": round(time.perf_counter() - start, 1),
    }
    if validation is not None:
        results["validation_agreement"] = agreement(net, validation.obs, validation.action)
    run.finish(**results)
    logger.info("bc: wrote %s (%s)", path, results)
    return path
