"""What the Stable-Baselines3 trainers (ppo, dqn) share: the training env, policy-file checkpoints,
logs and the run record.

A run trains on the batched SB3VecEnv (scenarios from the env's own seeded stream, never a test
set), optionally behind VecNormalize, and writes into its RunDir: a policy file every
`checkpoint_every` env steps (checkpoints/step_<steps>.safetensors: the policy after training on
that many steps), TensorBoard logs of SB3's losses and of the episodes' success, and the final
policy file <algo>.safetensors.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from socialzoo.core.validation import check_int
from socialzoo.env.config import EnvConfig
from socialzoo.train.run_dir import RunDir, checkpoint_steps, plain, progress_bar

logger = logging.getLogger(__name__)

POLICY_SUFFIX = ".safetensors"
# Fields of every SB3 trainer's Args that do not change what is trained (a run folder may move).
VOLATILE = ("progress", "out")


def training_env_config(
    map_name: str, family: str | None, max_steps: int, repeats: int, overrides: Mapping[str, Any]
) -> EnvConfig:
    """The training env's config: the benchmark's, on `map_name` (or a scenario family), with each
    scenario run `repeats` times before the next is drawn, and other EnvConfig overrides."""
    config = EnvConfig().replace(**dict(overrides))
    return config.replace(map=map_name, family=family, max_steps=max_steps, scenario={"repeats": repeats})


def env_id_of(config: EnvConfig) -> str:
    """The registered Gymnasium id a policy trained on `config` records (its version is checked when
    the policy loads): the benchmark id of the map, the family's id, else the benchmark's id."""
    from socialzoo.env.registration import BENCHMARK_IDS, FAMILY_IDS

    for env_id, kwargs in FAMILY_IDS.items() if config.family else BENCHMARK_IDS.items():
        if kwargs.get("family") == config.family and kwargs.get("map") == config.map:
            return env_id
    return next(iter(BENCHMARK_IDS))


def make_training_env(
    config: EnvConfig, num_envs: int, *, normalize: bool, normalize_reward: bool, gamma: float
) -> tuple[Any, Any]:
    """(the VecEnv to train on, its VecNormalize or None): SB3VecEnv -> VecMonitor (episode returns
    and lengths for SB3's logs) -> VecNormalize (observations, and rewards if asked)."""
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from socialzoo.env.sb3_vec import SB3VecEnv

    venv = VecMonitor(SB3VecEnv(num_envs, config))
    if not (normalize or normalize_reward):
        return venv, None
    norm = VecNormalize(venv, norm_obs=normalize, norm_reward=normalize_reward, gamma=gamma)
    return norm, norm


def check_common(cls: str, args: Any, block: int, what: str) -> None:
    """Validate the fields every SB3 trainer's Args has. Checkpoints must fall on `block` env steps
    (a rollout, or a training interval), so each holds the policy at exactly its step.

    Raises:
        ValueError: naming the field and the bad value.
    """
    for name in ("seed", "total_steps", "checkpoint_every", "max_steps", "scenario_repeats", "num_envs"):
        check_int(cls, name, getattr(args, name), low=0 if name == "seed" else 1)
    check_int(cls, "threads", args.threads, low=1)
    if args.checkpoint_every % block:
        raise ValueError(
            f"{cls}.checkpoint_every ({args.checkpoint_every}) must be a multiple of {what} ({block})"
        )
    if args.total_steps % block:
        raise ValueError(f"{cls}.total_steps ({args.total_steps}) must be a multiple of {what} ({block})")
    if not args.net_arch or any(not isinstance(n, int) or n < 1 for n in args.net_arch):
        raise ValueError(f"{cls}.net_arch must be positive layer sizes, got {args.net_arch!r}")
    try:
        training_env_config(args.map, args.family, args.max_steps, args.scenario_repeats, args.env_overrides)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{cls}: bad training env ({err})") from None


def checkpoint_callback(
    run: RunDir, total_steps: int, every: int, save: Callable[[Path, int], None], progress: bool
) -> Any:
    """An SB3 BaseCallback that calls save(path, steps) for each checkpoint step once the model has
    trained on that many env steps (at the start of the next rollout, or at the end of training),
    logs the success rate and metrics of finished episodes, and drives a progress bar."""
    from stable_baselines3.common.callbacks import BaseCallback

    class PolicyCheckpoints(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.pending = checkpoint_steps(total_steps, every)
            self.bar: Any = None

        def _on_training_start(self) -> None:
            self.bar = progress_bar(total_steps, f"train {run.algo}", progress)

        def _save_due(self) -> None:
            while self.pending and self.pending[0] <= self.num_timesteps:
                step = self.pending.pop(0)
                if step != self.num_timesteps:
                    logger.warning("checkpoint %d written at step %d", step, self.num_timesteps)
                save(run.checkpoint_path(step, POLICY_SUFFIX), step)

        def _on_rollout_start(self) -> None:
            self._save_due()

        def _on_step(self) -> bool:
            self.bar.update(self.training_env.num_envs)
            for info in self.locals.get("infos", ()):
                metrics = info.get("metrics")
                if metrics is not None:
                    self.logger.record_mean("episode/success", float(metrics["success"]))
                    self.logger.record_mean("episode/reached", float(metrics["reached"]))
                    self.logger.record_mean("episode/average_step_reward", metrics["average_step_reward"])
            return True

        def _on_training_end(self) -> None:
            self._save_due()
            self.bar.close()

    return PolicyCheckpoints()


def run_sb3(
    algo: str,
    args: Any,
    config: EnvConfig,
    build_model: Callable[[EnvConfig], tuple[Any, Any]],
) -> Path:
    """Train one SB3 model as `args` say and write the run folder; returns the final policy file.

    Args:
        algo: "ppo" or "dqn" (the registry name of the policy files).
        args: the trainer's Args (fields out, seed, total_steps, checkpoint_every, threads, progress).
        config: the training env config.
        build_model: config -> (the SB3 model on its training env, seeded with args.seed; the
            env's VecNormalize or None).

    A finished run of the same arguments in args.out is not repeated: its policy file is returned.
    """
    import torch
    from stable_baselines3.common.logger import configure

    from socialzoo.train.sb3_export import export_policy

    run = RunDir(args.out, algo, args, volatile=VOLATILE)
    final = run.path / f"{algo}{POLICY_SUFFIX}"
    if run.finished and final.is_file():
        logger.info("%s: finished run of these arguments, nothing to do", run.path)
        return final
    torch.set_num_threads(args.threads)
    observation = plain(config.observation)
    start = time.perf_counter()
    model, norm = build_model(config)
    model.set_logger(configure(str(run.path / "tensorboard"), ["tensorboard"]))

    def save(path: Path, step: int) -> None:
        policy, output = export_policy(model, algo, observation, norm)
        header = {
            "env_id": env_id_of(config),
            "network": {"output": output},
            "training": {
                "algo": algo,
                "library": "stable-baselines3",
                "seed": args.seed,
                "steps": step,
                "command": run.record["command"],
                "args": run.record["args"],
                "env": config.to_dict(),
            },
        }
        policy.save(path, header)

    callback = checkpoint_callback(run, args.total_steps, args.checkpoint_every, save, args.progress)
    model.learn(total_timesteps=args.total_steps, callback=callback, progress_bar=False)
    seconds = time.perf_counter() - start
    steps = int(model.num_timesteps)
    last = run.checkpoint_path(args.total_steps, POLICY_SUFFIX)
    if not last.is_file():
        save(last, steps)
    final.write_bytes(last.read_bytes())
    model.get_env().close()
    run.finish(
        wall_seconds=round(seconds, 1),
        env_steps=steps,
        env_steps_per_second=round(steps / seconds, 1),
        policy=final.name,
        checkpoints=[p.name for _, p in run.checkpoints(POLICY_SUFFIX)],
    )
    logger.info("%s: %d steps in %.1f s -> %s", algo, steps, seconds, final)
    return final
