"""PPO fine-tuning from a learned policy file: does RL on the benchmark reward move an imitation
policy past Ref's success-against-blame front?"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.agents import policy_file_or_shipped
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.config import EnvConfig
from socialzoo.train.checks import MAX_SB3_SEED, check_int, check_number, check_seed, coerce
from socialzoo.train.skeleton import Trainer, TrainingRun, run_training

TRAINER = Trainer("ppo-finetune", policy_file="ppo_finetune.safetensors", inputs=("init",))
# PPO's settings besides the arguments: 50 rows x 40 steps a rollout, minibatches of 500, 4 epochs.
NUM_ENVS = 50
PPO_SETTINGS: dict[str, Any] = {"n_steps": 40, "batch_size": 500, "n_epochs": 4, "ent_coef": 0.0}


@dataclass(frozen=True, kw_only=True)
class Args:
    """Fine-tune a learned policy file with PPO (Stable-Baselines3) on the benchmark reward.

    Attributes:
        init: the MlpPolicy file to start from (an MLP with an observation normaliser), or a
            learned policy's name for its shipped file ("dagger").
        out: the run folder: run.json and the fine-tuned ppo_finetune.safetensors.
        w_blame: reward weight of blame (benchmark: -0.1).
        w_collision: reward weight of collisions (benchmark: 0).
        warmup: critic-only env steps first (the actor frozen).
        steps: PPO env steps after the warm-up.
        lr: Adam learning rate.
        clip: PPO clip range.
        gamma: discount factor (SB3's and the paper's: 0.99).
        seed: seeds PPO and the training scenarios.
        threads: torch CPU threads.
        progress: show progress (in env steps).
    """

    init: Path
    out: Path = Path("runs/ppo_finetune")
    w_blame: float = -0.1
    w_collision: float = 0.0
    warmup: int = 40_000
    steps: int = 400_000
    lr: float = 1e-5
    clip: float = 0.1
    gamma: float = 0.99
    seed: int = 0
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        coerce(self, init=policy_file_or_shipped, out=Path)
        check_int(self, "warmup", "steps", low=0)
        check_seed(self, MAX_SB3_SEED)
        check_int(self, "threads", low=1)
        check_number(self, "lr", low=0.0, low_open=True, high=1.0)
        check_number(self, "clip", low=0.0, low_open=True, high=10.0)
        check_number(self, "gamma", low=0.0, high=1.0)
        check_number(self, "w_blame", "w_collision", low=-1e6, high=1e6)


def train(args: Args) -> Path:
    """Fine-tune on the trainer skeleton; returns DIR/ppo_finetune.safetensors (a finished run of
    the same arguments in args.out is reused).

    Starts Stable-Baselines3 PPO from an MlpPolicy file (`--init FILE`, or a learned policy's name for its
    shipped file; a ReLU or tanh MLP with its observation normaliser, such as the shipped DAgger or BC: `--init
    dagger`): the actor's layers are copied from the file and
    the file's normaliser is kept fixed (VecNormalize's observation statistics never update), so the untrained
    model acts exactly as the file does (checked before training). The critic, new, first learns for
    `--warmup` steps with the actor frozen; then PPO trains both with a small learning rate for `--steps`
    steps on the benchmark env's own training scenarios (never a validation or test scenario), in the
    observation layout the file was trained with, with the reward's blame and collision weights set by
    `--w-blame` and `--w-collision`. The policy has the name of
    the source ("dagger" for the shipped DAgger), so `socialzoo study ref-tradeoff --learned` evaluates it
    beside Ref's settings. docs/reproduce.md ("A learned policy against Ref") gives the measurements.
    """
    return run_training(TRAINER, args, lambda run: _fit(run, args))


def ppo_from_policy(
    source: MlpPolicy, config: EnvConfig, *, num_envs: int = NUM_ENVS, seed: int = 0, **ppo: Any
) -> Any:
    """An SB3 PPO model on `config` whose actor is `source`'s network and whose observations are
    normalised by `source`'s fixed normaliser; `ppo`: PPO keyword arguments.

    Raises:
        ValueError: a source without a normaliser, or with an activation PPO's MLP cannot have.
    """
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.running_mean_std import RunningMeanStd
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from socialzoo.env.sb3_vec import SB3VecEnv
    from socialzoo.train.policy_net import ACTIVATION_MODULES
    from socialzoo.train.sb3_common import quiet_logger

    fixed = source.normalizer
    if fixed is None or source.activation not in ACTIVATION_MODULES:
        raise ValueError(
            f"{source.path}: fine-tuning needs an MLP with an observation normaliser and a ReLU or tanh "
            f"activation (this one: normaliser {fixed is not None}, activation {source.activation!r})"
        )
    venv = VecNormalize(
        VecMonitor(SB3VecEnv(num_envs, config)),
        gamma=ppo.get("gamma", 0.99),
        clip_obs=fixed.clip,
        epsilon=fixed.epsilon,
    )
    rms = venv.obs_rms  # one RunningMeanStd: the observations are one array
    assert isinstance(rms, RunningMeanStd)
    rms.mean = fixed.mean.astype(np.float64)
    rms.var = fixed.var.astype(np.float64)
    setattr(rms, "update", lambda batch: None)  # noqa: B010  # the source's statistics stay as they are
    hidden = [int(w.shape[0]) for w, _ in source.layers[:-1]]
    model = PPO(
        "MlpPolicy",
        venv,
        seed=seed,
        device="cpu",
        verbose=0,
        policy_kwargs={
            "net_arch": {"pi": hidden, "vf": hidden},
            "activation_fn": ACTIVATION_MODULES[source.activation],
        },
        **ppo,
    )
    model.set_logger(quiet_logger())
    policy = model.policy
    linears = [m for m in policy.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)] + [
        policy.action_net
    ]
    with torch.no_grad():
        for layer, (w, b) in zip(linears, source.layers, strict=True):
            assert isinstance(layer, torch.nn.Linear)
            layer.weight.copy_(torch.as_tensor(w))
            layer.bias.copy_(torch.as_tensor(b))
    return model


def actor_parameters(model: Any) -> list[Any]:
    """The parameters of a PPO model's actor (its policy MLP and action head)."""
    policy = model.policy
    return [*policy.mlp_extractor.policy_net.parameters(), *policy.action_net.parameters()]


def finetune(model: Any, warmup: int, steps: int, bar: Any = None) -> None:
    """Train the critic alone for `warmup` env steps (the actor frozen), then both for `steps`;
    `bar` (a progress display, e.g. TrainingRun.progress) advances by the env steps taken."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Progress(BaseCallback):
        def _on_step(self) -> bool:
            bar.update(self.training_env.num_envs)
            return True

    callback = None if bar is None else Progress()
    actor = actor_parameters(model)
    for p in actor:
        p.requires_grad_(False)
    if warmup:
        model.learn(warmup, callback=callback)
    for p in actor:
        p.requires_grad_(True)
    if steps:
        model.learn(steps, reset_num_timesteps=not warmup, callback=callback)


def exported(model: Any, source: MlpPolicy) -> MlpPolicy:
    """The model's actor as an MlpPolicy of `source`'s name and observation."""
    from socialzoo.train.sb3_export import export_policy

    policy, _ = export_policy(model, source.name, source.observation, model.get_env())
    return policy


def _fit(run: TrainingRun, args: Args) -> Mapping[str, Any]:
    source = MlpPolicy.load(args.init)
    # The benchmark env in the observation layout the file reads (the paper's 25 person slots, or
    # the layout it was trained with), so its actor acts on what it learned from.
    config = EnvConfig().replace(
        observation=source.observation, reward={"w_blame": args.w_blame, "w_collision": args.w_collision}
    )
    model = ppo_from_policy(
        source, config, seed=args.seed, learning_rate=args.lr, clip_range=args.clip, gamma=args.gamma,
        **PPO_SETTINGS,
    )  # fmt: skip
    normalizer = source.normalizer
    assert normalizer is not None  # ppo_from_policy refuses a policy without one
    probe = np.random.default_rng(0).normal(
        normalizer.mean, np.sqrt(normalizer.var), (512, source.input_size)
    )
    if not np.array_equal(exported(model, source).act(probe), source.act(probe)):
        raise RuntimeError(f"{args.init}: the PPO actor does not act as the file does before training")
    start = time.perf_counter()
    finetune(
        model, args.warmup, args.steps, run.progress(args.warmup + args.steps, desc="train ppo-finetune")
    )
    finetuned = {**run.record["args"], "seconds": round(time.perf_counter() - start, 1)}
    header = dict(source.header)
    header["training"] = {**header.get("training", {}), "finetune": finetuned}
    exported(model, source).save(run.policy, header)
    model.get_env().close()
    return {"env_steps": args.warmup + args.steps, "source": source.name}
