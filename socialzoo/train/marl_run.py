"""One multi-agent training run from its arguments: the run folder, envs, networks, collector, loop, files.

`socialzoo train humans` and `socialzoo train cotrain` differ in which groups learn (humans; or
robots and humans, at once or in turns); everything else about a run is here: seeds, the fixed
input normalisation, the TorchRL collector, TensorBoard scalars, the progress bar, checkpoints,
history.csv (one row per batch: the training curves) and the final policy files. The untrained
policy is saved as the step-0 checkpoint, the baseline a trained one is measured against.
"""

from __future__ import annotations

import csv
import logging
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import torch
from tensordict.nn import TensorDictSequential

from socialzoo.agents.learned_humans import LearnedHumanPolicy
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.human_agents import human_mirror_signs
from socialzoo.nav.subpolicies import NUM_ACTIONS
from socialzoo.train.mappo import (
    GroupLearner,
    PPOSettings,
    critic,
    env_factories,
    env_id,
    export_humans,
    export_robot,
    human_actor,
    make_collector,
    make_env,
    observation_stats,
    robot_actor,
    train_loop,
)
from socialzoo.train.run_dir import RunDir, checkpoint_steps, progress_bar

logger = logging.getLogger(__name__)

HISTORY_FILE = "history.csv"
ROBOT_POLICY_FILE = "robot.safetensors"
# The policy name of a robot trained by `socialzoo train cotrain` (socialzoo.agents.POLICIES).
ROBOT_POLICY_NAME = "mappo"


def _settings(args: Any, prefix: str = "") -> PPOSettings:
    """PPO settings from the run's arguments (prefix "robot_" for the robots' own learning rate)."""
    lr = getattr(args, f"{prefix}lr", args.lr)
    return PPOSettings(
        algo=args.algo,
        lr=lr,
        gamma=args.gamma,
        lmbda=args.lmbda,
        clip_epsilon=args.clip_epsilon,
        entropy_coef=args.entropy_coef,
        epochs=args.epochs,
        minibatch_size=args.minibatch_size,
        max_grad_norm=args.max_grad_norm,
    )


class MarlRun:
    """A multi-agent training run.

    Args:
        args: HumansArgs or CotrainArgs (out, algo, env_config(), PPO and collector fields, seed).
        name: the trainer's name ("humans" or "cotrain"), recorded in run.json.
        policy_file: the final human policy's file name in the run folder.
        robot_policy: the spec of the policy that drives the robots inside the env, or None when
            the robots learn too.
        schedule: batch index -> the groups updated on that batch (default: every learned group).
    """

    def __init__(
        self,
        args: Any,
        name: str,
        policy_file: str,
        *,
        robot_policy: str | None,
        schedule: Callable[[int], Sequence[str]] | None = None,
    ) -> None:
        self.args = args
        self.name = name
        self.policy_file = policy_file
        self.robot_policy = robot_policy
        self.config = args.env_config()
        self.learned = (["robot"] if robot_policy is None else []) + (
            ["human"] if self.config.num_learned_humans else []
        )
        self.schedule = schedule or (lambda _index: self.learned)

    def run(self) -> Path:
        """Train (or report a finished run of the same arguments); returns the human policy file."""
        args = self.args
        run_dir = RunDir(args.out, self.name, args, volatile=("progress",))
        final = run_dir.path / self.policy_file
        if run_dir.finished and final.is_file():
            logger.info("%s: finished run found in %s", self.name, run_dir.path)
            return final
        torch.manual_seed(args.seed)
        torch.set_num_threads(args.threads)
        cfg = self.config
        stats_env = make_env(
            cfg.to_dict(), min(args.batch_size, 16), args.seed + 1_000_003, self.robot_policy
        )
        learners: dict[str, GroupLearner] = {}
        actors = []
        nets: dict[str, Any] = {}
        if "robot" in self.learned:
            loc, scale = observation_stats(stats_env, "robot", args.stats_steps)
            actor = robot_actor(cfg.observation.size, NUM_ACTIONS, args.hidden, args.depth, loc, scale)
            value = critic(
                "robot", cfg.observation.size, cfg.num_robots, args.algo, args.hidden, args.depth, loc, scale
            )
            learners["robot"] = GroupLearner("robot", actor, value, _settings(args, "robot_"))
            actors.append(actor)
            nets["robot"] = actor
        if "human" in self.learned:
            size = stats_env.observation_spec["human", "observation"].shape[-1]
            loc, scale = observation_stats(stats_env, "human", args.stats_steps)
            actor = human_actor(
                size,
                args.hidden,
                args.depth,
                loc,
                scale,
                args.walk_prior,
                args.init_std,
                cfg.human_action_scale,
                torch.from_numpy(human_mirror_signs(cfg.num_human_neighbours))
                if args.mirror_symmetric
                else None,
            )
            value = critic(
                "human", size, cfg.num_learned_humans, args.algo, args.hidden, args.depth, loc, scale
            )
            learners["human"] = GroupLearner("human", actor, value, _settings(args))
            actors.append(actor)
            nets["human"] = actor
        stats_env.close()
        if not learners:
            raise ValueError(f"{self.name}: nothing to learn (no learned humans and the robots run a policy)")
        groups = ["robot"] + (["human"] if cfg.num_learned_humans else [])
        policy = TensorDictSequential(*actors)
        workers = args.workers if args.collector != "single" else 1
        factories = env_factories(cfg, args.batch_size, args.seed, self.robot_policy, workers)
        collector = make_collector(
            args.collector, factories, policy, args.frames_per_batch, args.frames, args.ray_address
        )

        def training(frames: int) -> dict[str, Any]:
            return {
                "algo": args.algo,
                "trainer": self.name,
                "command": run_dir.record.get("command"),
                "seed": args.seed,
                "frames": frames,
                "map": cfg.map,
                "robot": self.robot_policy,
                "human_reward": dict(args.reward),
            }

        def export(frames: int) -> tuple[LearnedHumanPolicy | None, MlpPolicy | None]:
            humans = export_humans(nets["human"], cfg) if "human" in nets else None
            robot = export_robot(nets["robot"], ROBOT_POLICY_NAME, cfg) if "robot" in nets else None
            return humans, robot

        def write(
            humans: LearnedHumanPolicy | None,
            robot: MlpPolicy | None,
            stem: Callable[[str], Path],
            frames: int,
        ):
            files = []
            record = training(frames)
            if humans is not None:
                files.append(humans.save(stem(".humans.safetensors"), env_id(), record))
            if robot is not None:
                files.append(robot.save(stem(".robot.safetensors"), {"env_id": env_id(), "training": record}))
            return files

        def checkpoint(frames: int) -> list[Path]:
            return write(*export(frames), lambda suffix: run_dir.checkpoint_path(frames, suffix), frames)

        # The untrained policy, step 0: the baseline that the trained one is compared with.
        initial = checkpoint(0)
        logger.info(
            "%s: %s on %s, %d frames, collector %s",
            self.name,
            args.algo,
            cfg.map,
            args.frames,
            args.collector,
        )
        try:
            with run_dir.tensorboard() as writer:
                bar = progress_bar(args.frames, f"{self.name} ({args.algo})", args.progress, unit="frame")
                try:
                    result = train_loop(
                        collector,
                        learners,
                        self.schedule,
                        groups,
                        args.frames,
                        checkpoint_steps(args.frames, args.checkpoint_every),
                        checkpoint,
                        writer,
                        bar,
                        args.seed,
                        on_batch=lambda history: write_history(run_dir.path / HISTORY_FILE, history),
                    )
                finally:
                    bar.close()
        finally:
            collector.shutdown()
        humans, robot = export(result.frames)
        files = []
        if humans is not None:
            files.append(humans.save(final, env_id(), training(result.frames)))
        if robot is not None:
            robot_file = run_dir.path / ROBOT_POLICY_FILE
            files.append(robot.save(robot_file, {"env_id": env_id(), "training": training(result.frames)}))
        files.append(write_history(run_dir.path / HISTORY_FILE, result.history))
        last = result.history[-1] if result.history else {}
        run_dir.finish(
            frames=result.frames,
            seconds=result.seconds,
            frames_per_s=result.frames / max(result.seconds, 1e-9),
            final=last,
            files=[f.name for f in files],
            checkpoints=[str(p.relative_to(run_dir.path)) for p in initial + result.checkpoints],
        )
        return final if humans is not None else run_dir.path / ROBOT_POLICY_FILE


def write_history(path: Path, history: list[dict[str, float]]) -> Path:
    """The training curves: one CSV row per collected batch (frames, seconds, stats, losses)."""
    keys: list[str] = []
    for row in history:
        keys += [k for k in row if k not in keys]
    tmp = path.with_name(path.name + ".tmp")
    with tmp.open("w", newline="") as f:
        out = csv.DictWriter(f, fieldnames=keys)
        out.writeheader()
        out.writerows(history)
    tmp.replace(path)
    return path


def read_history(path: str | Path) -> list[dict[str, float]]:
    """history.csv back as rows of floats (missing values are NaN)."""
    with Path(path).open() as f:
        return [
            {k: float(v) if v != "" else float("nan") for k, v in row.items()} for row in csv.DictReader(f)
        ]
