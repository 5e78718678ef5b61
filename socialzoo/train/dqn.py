"""`socialzoo train dqn`: DQN (Stable-Baselines3) on the benchmark, through the batched SB3VecEnv."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from socialzoo.train.checks import check_int, check_minibatch, check_number
from socialzoo.train.sb3_common import SB3Args, SB3Trainer, run_sb3

TRAINER = SB3Trainer("dqn", policy_file="dqn.safetensors", model="DQN", activation="ReLU")


@dataclass(frozen=True, kw_only=True)
class DQNArgs(SB3Args):
    """Train DQN (Stable-Baselines3) on the Social Action Selection benchmark.

    The arguments every SB3 trainer takes are socialzoo.train.sb3_common.SB3Args; these are DQN's
    own (passed to stable_baselines3.DQN by name), and the defaults DQN changes (SB3's DQN defaults,
    the original's scenario repeats).

    Attributes:
        out: the run folder: run.json, checkpoints/, tensorboard/ and the final dqn.safetensors.
        scenario_repeats: episodes run on each scenario before a new one is drawn (the original:
            20 for DQN).
        num_envs: rows of the batched training env (SB3's default set-up: 1).
        learning_rate: Adam learning rate, > 0 (SB3: 1e-4).
        batch_size: replay minibatch size, at most buffer_size (SB3: 32).
        max_grad_norm: gradient clipping (SB3: 10).
        normalize: normalise observations with VecNormalize (saved with the policy; the original
            DQN did not).
        normalize_reward: normalise rewards with VecNormalize during training.
        buffer_size: replay buffer capacity in transitions (SB3: 1,000,000).
        learning_starts: env steps of random actions before learning, below total_steps (SB3: 100).
        tau: target network soft-update coefficient (SB3: 1.0, a hard copy).
        train_freq: vec-env steps between gradient phases (SB3: 4).
        gradient_steps: gradient steps per phase (SB3: 1).
        target_update_interval: env steps between target network updates (SB3: 10,000).
        exploration_fraction: share of training over which epsilon falls (SB3: 0.1).
        exploration_initial_eps: epsilon at the start (SB3: 1.0).
        exploration_final_eps: epsilon after the fall (SB3: 0.05).
    """

    out: Path = Path("runs/dqn")
    scenario_repeats: int = 20
    num_envs: int = 1
    learning_rate: float = 1e-4
    batch_size: int = 32
    max_grad_norm: float = 10.0
    normalize: bool = False
    normalize_reward: bool = False
    buffer_size: int = 1_000_000
    learning_starts: int = 100
    tau: float = 1.0
    train_freq: int = 4
    gradient_steps: int = 1
    target_update_interval: int = 10_000
    exploration_fraction: float = 0.1
    exploration_initial_eps: float = 1.0
    exploration_final_eps: float = 0.05

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int(self, "buffer_size", "train_freq", "gradient_steps", "target_update_interval", low=1)
        check_int(self, "learning_starts", low=0)
        if self.learning_starts >= self.total_steps:
            raise ValueError(
                f"DQNArgs.learning_starts ({self.learning_starts}) must be below total_steps "
                f"({self.total_steps}): DQN takes no gradient step before it, and its policy would be "
                "the untrained network"
            )
        check_minibatch(self, "batch_size", self.buffer_size, "the replay buffer, buffer_size")
        self.check_block(self.num_envs * self.train_freq, "num_envs * train_freq")
        names = ("tau", "exploration_fraction", "exploration_initial_eps", "exploration_final_eps")
        check_number(self, *names, low=0.0, high=1.0)


def train(args: DQNArgs) -> Path:
    """Train DQN as `args` say; returns the final policy file (see socialzoo.train.sb3_common).

    The paper's set-up (SPEC section 10): 84,000 env steps on gdc1, a checkpoint every 2,000, SB3's default
    DQN hyperparameters on one env (a gradient step every 4 env steps, epsilon from 1 to 0.05 over the first
    10% of training, the target network copied every 10,000 steps), raw observations, and a new scenario only
    every 20 resets (the original's scenario repeats for DQN).
    """
    return run_sb3(TRAINER, args)
