"""One multi-agent training run on the trainer skeleton: envs, networks, collector, loop, files."""

from __future__ import annotations

import csv
import dataclasses
import functools
import logging
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import torch
from tensordict.nn import TensorDictSequential

from socialzoo.bench.tables import write_csv
from socialzoo.env.human_agents import human_mirror_signs
from socialzoo.nav.subpolicies import NUM_ACTIONS
from socialzoo.train.mappo import (
    GroupLearner,
    PPOSettings,
    critic,
    env_factories,
    export_humans,
    export_robot,
    human_actor,
    make_collector,
    make_env,
    observation_stats,
    robot_actor,
    train_loop,
)
from socialzoo.train.marl_args import HUMANS_POLICY_FILE, ROBOT_POLICY_FILE, env_id
from socialzoo.train.run_dir import checkpoint_steps
from socialzoo.train.skeleton import Trainer, TrainingRun, run_training

logger = logging.getLogger(__name__)

HISTORY_FILE = "history.csv"
# The policy name of a robot trained by `socialzoo train cotrain` (socialzoo.agents.POLICIES).
ROBOT_POLICY_NAME = "mappo"


def _settings(args: Any, prefix: str = "") -> PPOSettings:
    """PPO settings from the run's arguments of the same names (prefix "robot_" for the robots' own
    learning rate)."""
    settings = {f.name: getattr(args, f.name) for f in dataclasses.fields(PPOSettings)}
    return PPOSettings(**{**settings, "lr": getattr(args, f"{prefix}lr", args.lr)})


def run_marl(
    trainer: Trainer,
    args: Any,
    *,
    robot_policy: str | None,
    schedule: Callable[[int], Sequence[str]] | None = None,
) -> Path:
    """One multi-agent training run on the trainer skeleton; returns the trainer's policy file.

    `socialzoo train humans` and `socialzoo train cotrain` differ in which groups learn (humans; or robots and
    humans, at once or in turns); what is common to their runs is here: the fixed input normalisation, the
    TorchRL collector, the training loop, history.csv (one row per batch: the training curves) and each
    learned group's policy files. The untrained policy is saved as the step-0 checkpoint, the baseline a
    trained one is measured against. The run folder, seed, record, checkpoints, TensorBoard and progress are
    the skeleton's (socialzoo.train.skeleton).

    Args:
        trainer: "humans" or "cotrain", with its final policy file (the humans', or the robots'
            when no human is learned).
        args: HumansArgs or CotrainArgs (socialzoo.train.marl_args.MarlArgs).
        robot_policy: the spec of the policy that drives the robots inside the env, or None when
            the robots learn too.
        schedule: batch index -> the groups updated on that batch (default: every learned group).
    """
    return run_training(trainer, args, lambda run: _fit(run, args, robot_policy, schedule))


def _learners(
    args: Any, cfg: Any, learned: Sequence[str], robot_policy: str | None
) -> dict[str, GroupLearner]:
    """The learner (actor, critic, loss) of each learned group, with input normalisation from
    random-action steps of a small env of their own."""
    stats_env = make_env(cfg.to_dict(), min(args.batch_size, 16), args.seed + 1_000_003, robot_policy)
    learners: dict[str, GroupLearner] = {}
    if "robot" in learned:
        loc, scale = observation_stats(stats_env, "robot", args.stats_steps)
        actor = robot_actor(cfg.observation.size, NUM_ACTIONS, args.hidden, args.depth, loc, scale)
        value = critic(
            "robot", cfg.observation.size, cfg.num_robots, args.algo, args.hidden, args.depth, loc, scale
        )
        learners["robot"] = GroupLearner("robot", actor, value, _settings(args, "robot_"))
    if "human" in learned:
        size = stats_env.observation_spec["human", "observation"].shape[-1]
        loc, scale = observation_stats(stats_env, "human", args.stats_steps)
        mirror = (
            torch.from_numpy(human_mirror_signs(cfg.num_human_neighbours)) if args.mirror_symmetric else None
        )
        actor = human_actor(
            size,
            args.hidden,
            args.depth,
            loc,
            scale,
            args.walk_prior,
            args.init_std,
            cfg.human_action_scale,
            mirror,
        )
        value = critic("human", size, cfg.num_learned_humans, args.algo, args.hidden, args.depth, loc, scale)
        learners["human"] = GroupLearner("human", actor, value, _settings(args))
    stats_env.close()
    return learners


def _fit(
    run: TrainingRun,
    args: Any,
    robot_policy: str | None,
    schedule: Callable[[int], Sequence[str]] | None,
) -> dict[str, Any]:
    cfg = args.env_config()
    learned = (["robot"] if robot_policy is None else []) + (["human"] if cfg.num_learned_humans else [])
    if not learned:
        raise ValueError(
            f"{run.trainer.name}: nothing to learn (no learned humans and the robots run a policy)"
        )
    learners = _learners(args, cfg, learned, robot_policy)
    nets = {group: learner.actor for group, learner in learners.items()}
    groups = ["robot"] + (["human"] if cfg.num_learned_humans else [])
    policy = TensorDictSequential(*nets.values())
    workers = args.workers if args.collector != "single" else 1
    factories = env_factories(cfg, args.batch_size, args.seed, robot_policy, workers)
    collector = make_collector(
        args.collector, factories, policy, args.frames_per_batch, args.frames, args.ray_address
    )

    def training(frames: int) -> dict[str, Any]:
        return run.recorded(
            {
                "algo": args.algo,
                "trainer": run.trainer.name,
                "command": run.record.get("command"),
                "seed": args.seed,
                "frames": frames,
                "map": cfg.map,
                "robot": robot_policy,
                "human_reward": dict(args.reward),
            }
        )

    def save_humans(path: Path, frames: int) -> Path:
        return export_humans(nets["human"], cfg).save(path, env_id(), training(frames))

    def save_robot(path: Path, frames: int) -> Path:
        robot = export_robot(nets["robot"], ROBOT_POLICY_NAME, cfg)
        return robot.save(path, {"env_id": env_id(), "training": training(frames)})

    # Each learned group's policy file: (checkpoint suffix, final file name, saver).
    savers = [
        (suffix, name, save)
        for group, suffix, name, save in (
            ("human", ".humans.safetensors", HUMANS_POLICY_FILE, save_humans),
            ("robot", ".robot.safetensors", ROBOT_POLICY_FILE, save_robot),
        )
        if group in nets
    ]

    def checkpoint(frames: int) -> list[Path]:
        return [
            run.checkpoint(frames, functools.partial(save, frames=frames), suffix)
            for suffix, _, save in savers
        ]

    # The untrained policy, step 0: the baseline that the trained one is compared with.
    checkpoint(0)
    logger.info(
        "%s: %s on %s, %d frames, collector %s",
        run.trainer.name,
        args.algo,
        cfg.map,
        args.frames,
        args.collector,
    )
    bar = run.progress(args.frames, desc=f"{run.trainer.name} ({args.algo})", unit="frame")
    try:
        result = train_loop(
            collector,
            learners,
            schedule or (lambda _index: learned),
            groups,
            args.frames,
            checkpoint_steps(args.frames, args.checkpoint_every),
            checkpoint,
            run.writer,
            bar,
            args.seed,
            on_batch=functools.partial(write_history, run.path / HISTORY_FILE),
        )
    finally:
        collector.shutdown()
    files = [save(run.path / name, result.frames) for _, name, save in savers]
    files.append(write_history(run.path / HISTORY_FILE, result.history))
    return {
        "frames": result.frames,
        "seconds": result.seconds,
        "frames_per_s": result.frames / max(result.seconds, 1e-9),
        "final": result.history[-1] if result.history else {},
        "files": [f.name for f in files],
    }


def write_history(path: Path, history: list[dict[str, float]]) -> Path:
    """The training curves: one CSV row per collected batch (frames, seconds, stats, losses)."""
    return write_csv(history, path, blank_nan=False)


def read_history(path: str | Path) -> list[dict[str, float]]:
    """history.csv back as rows of floats (missing values are NaN)."""
    with Path(path).open() as f:
        return [
            {k: float(v) if v != "" else float("nan") for k, v in row.items()} for row in csv.DictReader(f)
        ]
