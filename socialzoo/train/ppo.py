"""`socialzoo train ppo`: PPO (Stable-Baselines3) on the benchmark, through the batched SB3VecEnv."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from socialzoo.train.checks import check_int, check_minibatch, check_number
from socialzoo.train.sb3_common import SB3Args, SB3Trainer, run_sb3

TRAINER = SB3Trainer("ppo", policy_file="ppo.safetensors", model="PPO", activation="Tanh")


@dataclass(frozen=True, kw_only=True)
class PPOArgs(SB3Args):
    """Train PPO (Stable-Baselines3) on the Social Action Selection benchmark.

    The arguments every SB3 trainer takes are socialzoo.train.sb3_common.SB3Args (their defaults
    are this trainer's); these are PPO's own, passed to stable_baselines3.PPO by name.

    Attributes:
        out: the run folder: run.json, checkpoints/, tensorboard/ and the final ppo.safetensors.
        n_steps: env steps per row per rollout; a rollout is num_envs * n_steps env steps.
        n_epochs: passes over each rollout (SB3: 10).
        gae_lambda: GAE lambda (SB3: 0.95).
        clip_range: PPO clipping (SB3: 0.2).
        ent_coef: entropy bonus weight (SB3: 0.0).
        vf_coef: value loss weight (SB3: 0.5).
    """

    out: Path = Path("runs/ppo")
    n_steps: int = 40
    n_epochs: int = 10
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int(self, "n_steps", "n_epochs", low=1)
        # SB3's PPO normalises each minibatch's advantages, which takes two samples at least.
        check_int(self, "batch_size", low=2)
        rollout = (self.num_envs * self.n_steps, "the rollout, num_envs * n_steps")
        self.check_block(*rollout)
        check_minibatch(self, "batch_size", *rollout)
        check_number(self, "gae_lambda", low=0.0, high=1.0)
        check_number(self, "clip_range", "ent_coef", "vf_coef", low=0.0, high=10.0)


def train(args: PPOArgs) -> Path:
    """Train PPO as `args` say; returns the final policy file (see socialzoo.train.sb3_common).

    The paper's set-up (SPEC section 10): 84,000 env steps on gdc1, a checkpoint every 2,000, SB3's default
    PPO hyperparameters, observations normalised by VecNormalize; a new scenario every reset. socialzoo's
    differences: the rollout is 50 rows x 40 steps = 2,000 env steps (SB3's default is one env x 2,048) so
    that every checkpoint falls on an update, and the normalisation statistics are saved in the policy file
    and used at evaluation (the original evaluated without them).
    """
    return run_sb3(TRAINER, args)
