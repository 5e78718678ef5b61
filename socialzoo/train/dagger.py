"""DAgger (Ross, Gordon & Bagnell 2011): behaviour cloning that also learns on the states its own
policy reaches, labelled by the expert, Ref."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.train import bc
from socialzoo.train.checks import check_int
from socialzoo.train.imitation import INPUT_FILES, imitation_parts
from socialzoo.train.skeleton import Trainer, TrainingRun, run_training

TRAINER = Trainer("dagger", policy_file="dagger.safetensors", inputs=INPUT_FILES)
# Base seeds of the rollout scenarios: round k drives scenarios of TestSet(map, ROLLOUT_BASE_SEED +
# k, episodes). Their own seeds, like the demonstrations' (socialzoo.bench.demonstrations), so no
# validation or test scenario is ever driven in training.
ROLLOUT_BASE_SEED = 20_221_000
ROLLOUT_DIR = "rollouts"


@dataclass(frozen=True, kw_only=True)
class Args(bc.Args):
    """DAgger with Ref as the expert, on BC's fit.

    Every round fits as socialzoo.train.bc.Args says: BC's epochs, min_updates, batch_size, lr and
    weight_decay.

    Attributes:
        out: run folder: dagger.safetensors, run.json, tensorboard/, checkpoints/ (one policy per
            round), rollouts/ (each round's rollout).
        iterations: rounds of rollout, labelling and refit after the first fit (0: plain BC).
        episodes: scenarios the policy drives in each round.

    BC's checkpoint_every does not apply: every round's policy is a checkpoint (step = round), and
    with eval_trials each is evaluated on validation scenarios.
    """

    out: Path = Path("runs/dagger")
    iterations: int = 3
    episodes: int = 60

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int(self, "iterations", low=0)
        check_int(self, "episodes", low=1)


def train(args: Args) -> Path:
    """Run DAgger on the trainer skeleton; returns dagger.safetensors (a finished run of the same
    arguments in args.out is reused; demonstrations of another policy than Ref raise DemonstrationError).

    `socialzoo train dagger --demos FILE --out DIR` fits a policy to Ref's demonstrations exactly as
    `socialzoo train bc` does (round 0), then for each of `iterations` rounds drives the latest policy over
    `episodes` fresh scenarios of the demonstrations' map (their own seeds, never a validation or test
    scenario), labels every state it reached with the action Ref takes there, adds those pairs to the data and
    fits again from new weights. It writes DIR/dagger.safetensors (an MlpPolicy file), DIR/run.json,
    TensorBoard logs, each round's policy in checkpoints/ and each round's rollout in DIR/rollouts/ (a
    demonstration file: the learner's own actions, resumable).

    Why: BC's policy sees its previous action in the paper's observation, and Ref's actions persist for many
    steps, so a cloned policy leans on that input (the "copycat" problem, Wen et al. 2020): it agrees with Ref
    on 99.3% of Ref's own states yet differs from Ref on 22% of the states it reaches itself, and drives on
    where Ref halts (about twice Ref's blame). DAgger's labels on those states are what corrects it;
    docs/imitation.md gives the measurements.
    """
    return run_training(TRAINER, args, lambda run: _fit(run, args))


def expert_of(data: Any) -> Any:
    """The expert that labels the learner's states: the Ref that recorded `data`, with its
    parameters, acting on the paper observation alone.

    Raises:
        socialzoo.agents.demonstrations.DemonstrationError: demonstrations of another policy, or
            of another observation layout.
    """
    from socialzoo.agents.demonstrations import DemonstrationError
    from socialzoo.agents.engineered import Ref

    config = data.metadata.get("config", {})
    if config.get("policy") != "ref":
        raise DemonstrationError(
            f"{data.path}: DAgger's expert is Ref, and these demonstrations are of {config.get('policy')!r}; "
            "record Ref's (`socialzoo demos --episodes 125 --out FILE`)"
        )
    layout = data.observation.get("layout")
    if layout != "paper":
        raise DemonstrationError(
            f"{data.path}: Ref labels states from the paper observation layout; these demonstrations "
            f"use {layout!r}"
        )
    return Ref(**dict(config.get("policy_kwargs", {})))


def _fit(run: TrainingRun, args: Args) -> Mapping[str, Any]:
    from socialzoo.agents.demonstrations import load_demonstrations
    from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations
    from socialzoo.train.demo_data import load_demo_steps
    from socialzoo.train.policy_net import init_linear

    parts = imitation_parts(run, args)
    data, net = parts.data, parts.net
    expert = expert_of(data)
    validation = load_demo_steps(args.validation) if args.validation is not None else None
    env_overrides = dict(data.metadata.get("config", {}).get("env_overrides", {}))
    obs_sets, action_sets = [data.obs], [data.action]
    disagreement: list[float] = []
    bar = run.progress(args.iterations + 1, unit="round")
    writer = run.writer
    for k in range(args.iterations + 1):
        if k > 0:
            init_linear(net, parts.generator)  # each round fits from new weights, as round 0 did
        obs, action = np.concatenate(obs_sets), np.concatenate(action_sets)
        loss = bc.fit_actions(bc.bc_loss_module(net), obs, action, args, parts.generator)
        writer.add_scalar("dagger/loss", loss, k)
        found = bc.agreements(net, obs, action, validation)
        for key, value in found.items():
            writer.add_scalar(f"dagger/{key}", value, k)
        writer.add_scalar("dagger/steps", len(obs), k)
        steps = len(obs)
        policy = run.checkpoint(k, functools.partial(parts.save, round=k, steps=steps))
        bar.update(1)
        if k == args.iterations:
            break
        rollout = record_demonstrations(
            run.path / ROLLOUT_DIR / f"round_{k:03d}.npz",
            DemoConfig(
                policy=TRAINER.name, policy_kwargs={"path": str(policy)}, map=data.map,
                episodes=args.episodes, base_seed=ROLLOUT_BASE_SEED + k, env_overrides=env_overrides,
            ),
        )  # fmt: skip
        arrays, _ = load_demonstrations(rollout)
        learner_obs = arrays["obs"].astype(np.float32)
        labels = expert.act(learner_obs)
        disagreement.append(float(np.mean(labels != arrays["action"])))
        writer.add_scalar("dagger/closed_loop_disagreement", disagreement[-1], k)
        bar.set_postfix(steps=len(obs) + len(labels), differs=f"{disagreement[-1]:.3f}")
        obs_sets.append(learner_obs)
        action_sets.append(labels)
    parts.save(run.policy, rounds=args.iterations + 1, steps=len(obs))
    return {
        "rounds": args.iterations + 1,
        "demonstration_steps": len(data),
        "rollout_steps": int(len(obs) - len(data)),
        "updates_last_round": bc.update_count(len(obs), args),
        # Per round: the fraction of the learner's own states where its action was not Ref's.
        "closed_loop_disagreement": disagreement,
        **found,
    }
