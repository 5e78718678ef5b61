"""`socialzoo train ppo`: PPO (Stable-Baselines3) on the benchmark, through the batched SB3VecEnv.

The paper's set-up (SPEC section 10): 84,000 env steps on gdc1, a checkpoint every 2,000, SB3's
default PPO hyperparameters, observations normalised by VecNormalize; a new scenario every reset.
socialzoo's differences: the rollout is 50 rows x 40 steps = 2,000 env steps (SB3's default is one
env x 2,048) so that every checkpoint falls on an update, and the normalisation statistics are
saved in the policy file and used at evaluation (the original evaluated without them).

    socialzoo train ppo --out runs/ppo --seed 0
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from socialzoo.core.validation import check_int, check_number
from socialzoo.env.config import EnvConfig
from socialzoo.train.sb3_common import (
    check_common,
    make_training_env,
    run_sb3,
    training_env_config,
)


@dataclass(frozen=True, kw_only=True)
class PPOArgs:
    """Train PPO (Stable-Baselines3) on the Social Action Selection benchmark.

    Attributes:
        out: the run folder: run.json, checkpoints/, tensorboard/ and the final ppo.safetensors.
        seed: seeds the network, SB3's sampling and the env's scenario stream.
        total_steps: env steps of training (the paper: 84,000).
        checkpoint_every: a policy file every this many env steps (the paper: 2,000); a multiple
            of the rollout (num_envs * n_steps).
        map: the training map; scenarios come from the env's own seeded stream, never a test set.
        family: a scenario family instead of the benchmark's scenarios (None: the benchmark).
        max_steps: episode time limit in steps (the benchmark: 3,200 = 80 s).
        scenario_repeats: episodes run on each scenario before a new one is drawn (the original:
            1 for PPO).
        env_overrides: other EnvConfig fields, as a JSON object (e.g. {"reward": {"w_force": -0.02}}).
        num_envs: rows of the batched training env.
        n_steps: env steps per row per rollout; a rollout is num_envs * n_steps env steps.
        batch_size: minibatch size of the PPO update (SB3: 64).
        n_epochs: passes over each rollout (SB3: 10).
        learning_rate: Adam learning rate (SB3: 3e-4).
        gamma: discount factor (SB3: 0.99).
        gae_lambda: GAE lambda (SB3: 0.95).
        clip_range: PPO clipping (SB3: 0.2).
        ent_coef: entropy bonus weight (SB3: 0.0).
        vf_coef: value loss weight (SB3: 0.5).
        max_grad_norm: gradient clipping (SB3: 0.5).
        net_arch: hidden layer sizes of the policy and value MLPs (SB3: 64 64, tanh).
        normalize: normalise observations with VecNormalize (saved with the policy).
        normalize_reward: normalise rewards with VecNormalize during training (SB3's default).
        threads: torch CPU threads.
        progress: show a progress bar.
    """

    out: Path = Path("runs/ppo")
    seed: int = 0
    total_steps: int = 84_000
    checkpoint_every: int = 2_000
    map: str = "gdc1"
    family: str | None = None
    max_steps: int = 3200
    scenario_repeats: int = 1
    env_overrides: dict[str, Any] = field(default_factory=dict)
    num_envs: int = 50
    n_steps: int = 40
    batch_size: int = 64
    n_epochs: int = 10
    learning_rate: float = 3e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    net_arch: tuple[int, ...] = (64, 64)
    normalize: bool = True
    normalize_reward: bool = True
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "out", Path(self.out))
        object.__setattr__(self, "net_arch", tuple(self.net_arch))
        for name in ("n_steps", "batch_size", "n_epochs"):
            check_int("PPOArgs", name, getattr(self, name), low=1)
        check_common("PPOArgs", self, self.num_envs * self.n_steps, "the rollout, num_envs * n_steps")
        for name, low, high in (
            ("learning_rate", 0.0, 1.0),
            ("gamma", 0.0, 1.0),
            ("gae_lambda", 0.0, 1.0),
            ("clip_range", 0.0, 10.0),
            ("ent_coef", 0.0, 10.0),
            ("vf_coef", 0.0, 10.0),
            ("max_grad_norm", 0.0, 1e6),
        ):
            check_number("PPOArgs", name, getattr(self, name), low=low, high=high)


def train(args: PPOArgs) -> Path:
    """Train PPO as `args` say; returns the final policy file (see socialzoo.train.sb3_common)."""
    config = training_env_config(
        args.map, args.family, args.max_steps, args.scenario_repeats, args.env_overrides
    )

    def build(config: EnvConfig) -> tuple[Any, Any]:
        import torch
        from stable_baselines3 import PPO

        venv, norm = make_training_env(
            config,
            args.num_envs,
            normalize=args.normalize,
            normalize_reward=args.normalize_reward,
            gamma=args.gamma,
        )
        with warnings.catch_warnings():
            # SB3 warns that 2,000 is no multiple of 64: the last minibatch holds 16 samples, and an
            # epoch has 32 minibatches, as with SB3's default rollout of 2,048.
            warnings.filterwarnings("ignore", message=".*mini-batch size.*")
            model = PPO(
                "MlpPolicy",
                venv,
                n_steps=args.n_steps,
                batch_size=args.batch_size,
                n_epochs=args.n_epochs,
                learning_rate=args.learning_rate,
                gamma=args.gamma,
                gae_lambda=args.gae_lambda,
                clip_range=args.clip_range,
                ent_coef=args.ent_coef,
                vf_coef=args.vf_coef,
                max_grad_norm=args.max_grad_norm,
                policy_kwargs={"net_arch": list(args.net_arch), "activation_fn": torch.nn.Tanh},
                seed=args.seed,
                device="cpu",
                verbose=0,
            )
        return model, norm

    return run_sb3("ppo", args, config, build)
