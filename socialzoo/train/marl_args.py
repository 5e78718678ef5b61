"""What the multi-agent trainers (humans, cotrain) share: their common arguments, the humans' training reward and
starting behaviour, and the training env config. Free of torch at import, so listing the trainers stays cheap."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from socialzoo.train.checks import check_choice, check_int, check_minibatch, check_number, check_seed

Algo = Literal["mappo", "ippo"]
CollectorKind = Literal["single", "multiprocess", "ray"]
ALGOS: tuple[str, ...] = ("mappo", "ippo")
COLLECTORS: tuple[str, ...] = ("single", "multiprocess", "ray")
# The final policy files of a run: the learned humans', and the robots' when they learn too.
HUMANS_POLICY_FILE = "humans.safetensors"
ROBOT_POLICY_FILE = "robot.safetensors"
# The env id recorded in policy files: the multi-agent env at the benchmark's env version.
MULTI_AGENT_ENV_ID = "socialzoo/MultiAgent-v{version}"

# The learned humans' reward weights for training (socialzoo.env.human_agents.HumanRewardConfig):
# a metre of progress is worth 1 (about 0.02 per step at walking speed), a waypoint 0.5; walking off
# the preferred speed costs a little; a step in contact with a human costs ten steps of walking, with
# a robot twenty, with a wall twenty-five, so scraping a wall never pays for the corner it cuts (at
# 0.05 per step it did: humans trained with it touched walls six times as often as social-force humans),
# and walking within 0.4 m of a wall costs up to 0.05 per step, a warning before the contact (with
# it, mirror-symmetric humans touched walls 17% less often than social-force humans on validation
# scenarios; without it, 17% more: docs/multi_agent.md).
DEFAULT_REWARD: dict[str, float] = {
    "progress": 1.0,
    "waypoint_bonus": 0.5,
    "speed": 0.01,
    "human_contact": 0.2,
    "robot_contact": 0.4,
    "wall_contact": 0.5,
    "wall_clearance": 0.05,
}
# Training starts from humans that walk towards their waypoint (mappo.human_actor): the social-force
# humans' intent, which the policy then refines, instead of from humans standing still; with little
# exploration noise, so early batches are not spent bumping into walls.
WALK_PRIOR = 0.95
INIT_STD = 0.3
# The learned humans' desired velocity reaches past the preferred speed: with a tanh action capped
# at the preferred speed they could only ask for less than it, and walked 2-4% slower than the
# social-force humans, who ask for exactly it.
ACTION_SCALE = 1.0


def env_id() -> str:
    """The env id and version recorded in the policy files the multi-agent trainers write."""
    from socialzoo.env.policy_file import current_env_version

    return MULTI_AGENT_ENV_ID.format(version=current_env_version())


@dataclass(frozen=True, kw_only=True)
class MarlArgs:
    """The arguments every multi-agent trainer takes (MAPPO or IPPO with shared parameters over the
    native TorchRL env); the defaults are `socialzoo train humans`' set-up.

    Attributes:
        out: the run folder (run.json, tensorboard/, checkpoints/, history.csv, the policy files).
        algo: "mappo" (centralised critic) or "ippo" (per-agent critic).
        map: the training map (its training scenarios; test sets are never used).
        num_robots: robots per world.
        num_learned_humans: learned human slots per world; the other humans are social-force.
        max_humans: human slots per world (scenario.max_humans).
        max_steps: episode time limit, steps.
        frames: world steps to collect in all (whole batches: rounded up to frames_per_batch's next multiple).
        batch_size: worlds per env (B); every collector worker steps one env.
        frames_per_batch: world steps per collected batch, over all workers.
        workers: collector workers (processes or Ray actors; 1 for the single collector).
        collector: "single" (this process), "multiprocess" (TorchRL MultiSyncCollector) or
            "ray" (TorchRL RayCollector).
        ray_address: Ray cluster address for collector=ray; none starts a local Ray.
        epochs: PPO epochs per batch.
        minibatch_size: world steps per minibatch (each with all its agents), at most
            frames_per_batch.
        lr: Adam learning rate (of the humans).
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
        env_overrides: other EnvConfig fields (JSON object), e.g. {"reward": {...}} for the robots; a
            nested config's object changes the fields it names, on top of max_humans and reward.
        stats_steps: random-action steps whose observations set the fixed input normalisation.
        checkpoint_every: frames between checkpoints.
        seed: seeds torch, the scenario streams and the minibatch order.
        threads: torch threads in this process (collector workers use one each).
        progress: show progress.
    """

    out: Path
    algo: Algo = "mappo"
    map: str = "gdc1"
    num_robots: int = 1
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
        owner = type(self).__name__
        check_choice(self, "algo", ALGOS)
        check_choice(self, "collector", COLLECTORS)
        check_int(self, "frames", "batch_size", "frames_per_batch", "workers", "epochs", low=1)
        check_int(self, "minibatch_size", "hidden", "depth", "stats_steps", "checkpoint_every", low=1)
        check_int(self, "num_robots", "max_steps", "threads", low=1)
        check_int(self, "max_humans", low=0)
        check_seed(self)
        check_number(self, "lr", "clip_epsilon", "max_grad_norm", low=0, low_open=True)
        check_number(self, "action_scale", "init_std", low=0, low_open=True)
        check_number(self, "gamma", "lmbda", low=0, high=1)
        check_number(self, "entropy_coef", low=0)
        check_number(self, "walk_prior", low=0, high=self.action_scale, high_open=True)
        if self.collector == "single" and self.workers != 1:
            raise ValueError(f"{owner}.workers must be 1 with collector='single', got {self.workers}")
        per_worker = self.workers * self.batch_size
        if self.frames_per_batch % per_worker:
            raise ValueError(
                f"{owner}.frames_per_batch ({self.frames_per_batch}) must be a multiple of workers x "
                f"batch_size ({per_worker})"
            )
        check_minibatch(self, "minibatch_size", self.frames_per_batch, "a collected batch, frames_per_batch")
        if self.ray_address is not None and self.collector != "ray":
            raise ValueError(f"{owner}.ray_address is for collector='ray', got collector={self.collector!r}")
        self.env_config()  # a bad map, reward weight or override fails here, naming it

    def env_config(self) -> Any:
        """The EnvConfig a multi-agent run trains on: its map, robots, human slots, time limit and
        human reward, human-frame actions, then its env_overrides (a nested config given there as a
        dict, such as "scenario" or "human_reward", changes those fields of the run's, not of the
        defaults: --max-humans and --reward stay)."""
        from socialzoo.env.config import EnvConfig

        overrides: dict[str, Any] = {
            "map": self.map,
            "num_robots": self.num_robots,
            "num_learned_humans": self.num_learned_humans,
            "max_steps": self.max_steps,
            "human_action_frame": "human",
            "human_action_scale": self.action_scale,
            "human_reward": dict(self.reward),
            # Fewer slots than the scenarios' least head count lower it to them, as the CrowdNav task's
            # walled cases do (socialzoo.env.crowd_source): --max-humans 3 trains among 3 people.
            "scenario": {
                "max_humans": self.max_humans,
                "min_humans": min(EnvConfig().scenario.min_humans, self.max_humans),
            },
        }
        for key, value in self.env_overrides.items():
            mine = overrides.get(key)
            overrides[key] = (
                {**mine, **value} if isinstance(mine, dict) and isinstance(value, dict) else value
            )
        return EnvConfig().replace(**overrides)
