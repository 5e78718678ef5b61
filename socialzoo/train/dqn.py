"""`socialzoo train dqn`: DQN (Stable-Baselines3) on the benchmark, through the batched SB3VecEnv.

The paper's set-up (SPEC section 10): 84,000 env steps on gdc1, a checkpoint every 2,000, SB3's
default DQN hyperparameters on one env (a gradient step every 4 env steps, epsilon from 1 to 0.05
over the first 10% of training, the target network copied every 10,000 steps), raw observations,
and a new scenario only every 20 resets (the original's scenario repeats for DQN).

    socialzoo train dqn --out runs/dqn --seed 0
"""

from __future__ import annotations

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
class DQNArgs:
    """Train DQN (Stable-Baselines3) on the Social Action Selection benchmark.

    Attributes:
        out: the run folder: run.json, checkpoints/, tensorboard/ and the final dqn.safetensors.
        seed: seeds the network, SB3's exploration and replay sampling, and the env's scenario stream.
        total_steps: env steps of training (the paper: 84,000).
        checkpoint_every: a policy file every this many env steps (the paper: 2,000); a multiple
            of num_envs * train_freq.
        map: the training map; scenarios come from the env's own seeded stream, never a test set.
        family: a scenario family instead of the benchmark's scenarios (None: the benchmark).
        max_steps: episode time limit in steps (the benchmark: 3,200 = 80 s).
        scenario_repeats: episodes run on each scenario before a new one is drawn (the original:
            20 for DQN).
        env_overrides: other EnvConfig fields, as a JSON object (e.g. {"reward": {"w_force": -0.02}}).
        num_envs: rows of the batched training env (SB3's default set-up: 1).
        learning_rate: Adam learning rate (SB3: 1e-4).
        buffer_size: replay buffer capacity in transitions (SB3: 1,000,000).
        learning_starts: env steps of random actions before learning (SB3: 100).
        batch_size: replay minibatch size (SB3: 32).
        tau: target network soft-update coefficient (SB3: 1.0, a hard copy).
        gamma: discount factor (SB3: 0.99).
        train_freq: vec-env steps between gradient phases (SB3: 4).
        gradient_steps: gradient steps per phase (SB3: 1).
        target_update_interval: env steps between target network updates (SB3: 10,000).
        exploration_fraction: share of training over which epsilon falls (SB3: 0.1).
        exploration_initial_eps: epsilon at the start (SB3: 1.0).
        exploration_final_eps: epsilon after the fall (SB3: 0.05).
        max_grad_norm: gradient clipping (SB3: 10).
        net_arch: hidden layer sizes of the Q-network (SB3: 64 64, ReLU).
        normalize: normalise observations with VecNormalize (saved with the policy; the original
            DQN did not).
        normalize_reward: normalise rewards with VecNormalize during training.
        threads: torch CPU threads.
        progress: show a progress bar.
    """

    out: Path = Path("runs/dqn")
    seed: int = 0
    total_steps: int = 84_000
    checkpoint_every: int = 2_000
    map: str = "gdc1"
    family: str | None = None
    max_steps: int = 3200
    scenario_repeats: int = 20
    env_overrides: dict[str, Any] = field(default_factory=dict)
    num_envs: int = 1
    learning_rate: float = 1e-4
    buffer_size: int = 1_000_000
    learning_starts: int = 100
    batch_size: int = 32
    tau: float = 1.0
    gamma: float = 0.99
    train_freq: int = 4
    gradient_steps: int = 1
    target_update_interval: int = 10_000
    exploration_fraction: float = 0.1
    exploration_initial_eps: float = 1.0
    exploration_final_eps: float = 0.05
    max_grad_norm: float = 10.0
    net_arch: tuple[int, ...] = (64, 64)
    normalize: bool = False
    normalize_reward: bool = False
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "out", Path(self.out))
        object.__setattr__(self, "net_arch", tuple(self.net_arch))
        for name in ("buffer_size", "batch_size", "train_freq", "gradient_steps", "target_update_interval"):
            check_int("DQNArgs", name, getattr(self, name), low=1)
        check_int("DQNArgs", "learning_starts", self.learning_starts, low=0)
        check_common("DQNArgs", self, self.num_envs * self.train_freq, "num_envs * train_freq")
        for name, low, high in (
            ("learning_rate", 0.0, 1.0),
            ("tau", 0.0, 1.0),
            ("gamma", 0.0, 1.0),
            ("exploration_fraction", 0.0, 1.0),
            ("exploration_initial_eps", 0.0, 1.0),
            ("exploration_final_eps", 0.0, 1.0),
            ("max_grad_norm", 0.0, 1e6),
        ):
            check_number("DQNArgs", name, getattr(self, name), low=low, high=high)


def train(args: DQNArgs) -> Path:
    """Train DQN as `args` say; returns the final policy file (see socialzoo.train.sb3_common)."""
    config = training_env_config(
        args.map, args.family, args.max_steps, args.scenario_repeats, args.env_overrides
    )

    def build(config: EnvConfig) -> tuple[Any, Any]:
        import torch
        from stable_baselines3 import DQN

        venv, norm = make_training_env(
            config,
            args.num_envs,
            normalize=args.normalize,
            normalize_reward=args.normalize_reward,
            gamma=args.gamma,
        )
        model = DQN(
            "MlpPolicy",
            venv,
            learning_rate=args.learning_rate,
            buffer_size=args.buffer_size,
            learning_starts=args.learning_starts,
            batch_size=args.batch_size,
            tau=args.tau,
            gamma=args.gamma,
            train_freq=args.train_freq,
            gradient_steps=args.gradient_steps,
            target_update_interval=args.target_update_interval,
            exploration_fraction=args.exploration_fraction,
            exploration_initial_eps=args.exploration_initial_eps,
            exploration_final_eps=args.exploration_final_eps,
            max_grad_norm=args.max_grad_norm,
            policy_kwargs={"net_arch": list(args.net_arch), "activation_fn": torch.nn.ReLU},
            seed=args.seed,
            device="cpu",
            verbose=0,
        )
        return model, norm

    return run_sb3("dqn", args, config, build)
