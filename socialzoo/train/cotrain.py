"""`socialzoo train cotrain`: robots and learned humans trained together with MAPPO or IPPO.

Both groups of the native env learn: the robots (several per world share one policy, a
Categorical over the four sub-policies, with the benchmark's reward, SPEC section 9) and the
learned humans (as in `socialzoo train humans`). Schedule "simultaneous" updates both groups on
every collected batch; "alternating" updates one group for `alternate_every` batches, then the
other, while both keep acting (the other group's policy is frozen meanwhile).

Writes humans.safetensors (load with `socialzoo benchmark --humans learned:PATH`) and
robot.safetensors (a socialzoo policy file: `socialzoo benchmark --policies mappo:PATH`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from socialzoo.core.validation import check_int, check_number
from socialzoo.train.humans import (
    ACTION_SCALE,
    DEFAULT_REWARD,
    INIT_STD,
    POLICY_FILE,
    WALK_PRIOR,
    check_args,
    training_env_config,
)
from socialzoo.train.mappo import Algo, CollectorKind

Schedule = Literal["simultaneous", "alternating"]
SCHEDULES: tuple[str, ...] = ("simultaneous", "alternating")


@dataclass(frozen=True, kw_only=True)
class CotrainArgs:
    """Train robots (one shared policy) and learned humans together with MAPPO or IPPO.

    Attributes:
        out: the run folder (run.json, tensorboard/, checkpoints/, humans.safetensors, robot.safetensors).
        algo: "mappo" (centralised critics) or "ippo" (per-agent critics), for both groups.
        schedule: "simultaneous" (both groups learn on every batch) or "alternating" (turns).
        alternate_every: batches per turn with schedule=alternating (robots first).
        map: the training map (its training scenarios; test sets are never used).
        num_robots: robots per world, all sharing one policy.
        num_learned_humans: learned human slots per world; the other humans are social-force.
        max_humans: human slots per world (scenario.max_humans).
        max_steps: episode time limit, steps.
        frames: world steps to collect in all.
        batch_size: worlds per env (B); every collector worker steps one env.
        frames_per_batch: world steps per collected batch, over all workers.
        workers: collector workers (processes or Ray actors; 1 for the single collector).
        collector: "single", "multiprocess" (TorchRL MultiSyncCollector) or "ray" (RayCollector).
        ray_address: Ray cluster address for collector=ray; none starts a local Ray.
        epochs: PPO epochs per batch.
        minibatch_size: world steps per minibatch (each with all its agents).
        lr: Adam learning rate of the humans.
        robot_lr: Adam learning rate of the robots.
        gamma: discount per 0.025 s step.
        lmbda: GAE lambda.
        clip_epsilon: PPO ratio clip.
        entropy_coef: entropy bonus weight.
        max_grad_norm: gradient norm clip.
        hidden: hidden units per layer of the actors and critics.
        depth: hidden layers.
        reward: the humans' reward weights (HumanRewardConfig fields, JSON object).
        action_scale: the humans' action times this times the preferred speed is the desired
            velocity (EnvConfig.human_action_scale; above 1 they can ask for more than the
            preferred speed, though they never walk faster than it).
        walk_prior: the untrained humans' desired velocity: towards the waypoint at this fraction
            of the preferred speed (1: the social-force humans' intent; 0: standing still;
            socialzoo.train.mappo.human_actor), below action_scale.
        init_std: the humans' initial exploration noise (before the tanh).
        mirror_symmetric: the humans' policy acts on a situation and its mirror image alike (no
            handedness; socialzoo.train.mappo.MirrorSymmetric).
        env_overrides: other EnvConfig fields (JSON object), e.g. {"reward": {...}} for the robots.
        stats_steps: random-action steps whose observations set the fixed input normalisation.
        checkpoint_every: frames between checkpoints.
        seed: seeds torch, the scenario streams and the minibatch order.
        threads: torch threads in this process (collector workers use one each).
        progress: show a progress bar.
    """

    out: Path
    algo: Algo = "mappo"
    schedule: Schedule = "simultaneous"
    alternate_every: int = 5
    map: str = "gdc1"
    num_robots: int = 2
    num_learned_humans: int = 25
    max_humans: int = 25
    max_steps: int = 3200
    frames: int = 2_000_000
    batch_size: int = 64
    frames_per_batch: int = 6400
    workers: int = 1
    collector: CollectorKind = "single"
    ray_address: str | None = None
    epochs: int = 4
    minibatch_size: int = 400
    lr: float = 1e-3
    robot_lr: float = 3e-4
    gamma: float = 0.99
    lmbda: float = 0.95
    clip_epsilon: float = 0.2
    entropy_coef: float = 0.001
    max_grad_norm: float = 1.0
    hidden: int = 64
    depth: int = 2
    reward: dict[str, Any] = field(default_factory=lambda: dict(DEFAULT_REWARD))
    action_scale: float = ACTION_SCALE
    walk_prior: float = WALK_PRIOR
    init_std: float = INIT_STD
    mirror_symmetric: bool = True
    env_overrides: dict[str, Any] = field(default_factory=dict)
    stats_steps: int = 64
    checkpoint_every: int = 500_000
    seed: int = 0
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        if self.schedule not in SCHEDULES:
            raise ValueError(f"CotrainArgs.schedule must be one of {SCHEDULES}, got {self.schedule!r}")
        check_int("CotrainArgs", "alternate_every", self.alternate_every, low=1)
        check_number("CotrainArgs", "robot_lr", self.robot_lr, low=0, low_open=True)
        check_args(self, "CotrainArgs")

    def env_config(self) -> Any:
        """The training EnvConfig (socialzoo.train.humans.training_env_config)."""
        return training_env_config(self)

    def groups_at(self, index: int) -> Sequence[str]:
        """The groups updated on collected batch `index` (robots take the first turn)."""
        learned = ["robot", "human"] if self.num_learned_humans else ["robot"]
        if self.schedule == "simultaneous" or len(learned) == 1:
            return learned
        return [learned[(index // self.alternate_every) % 2]]


def train(args: CotrainArgs) -> Path:
    """Train robots and humans together; returns the path of humans.safetensors (robot.safetensors
    beside it), or of robot.safetensors when no human is learned."""
    from socialzoo.train.marl_run import MarlRun

    return MarlRun(args, "cotrain", POLICY_FILE, robot_policy=None, schedule=args.groups_at).run()
