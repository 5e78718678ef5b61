"""Generative adversarial imitation learning (GAIL) of the reference policy with TorchRL."""

from __future__ import annotations

import functools
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from socialzoo.train.checks import (
    Activation,
    check_choice,
    check_int,
    check_minibatch,
    check_number,
    check_sizes,
    check_whole_batches,
    coerce,
)
from socialzoo.train.imitation import INPUT_FILES, ImitationArgs, imitation_parts
from socialzoo.train.skeleton import Trainer, TrainingRun, run_training

TRAINER = Trainer("gail", policy_file="gail.safetensors", inputs=INPUT_FILES)
GailReward = Literal["logit", "positive", "negative"]
# The generator's reward is clipped to +-REWARD_CLIP (a saturated discriminator would give inf).
REWARD_CLIP = 10.0


@dataclass(frozen=True, kw_only=True)
class Args(ImitationArgs):
    """GAIL on Ref demonstrations: TorchRL GAILLoss discriminator, ClipPPOLoss generator.

    The arguments every imitation trainer takes are socialzoo.train.imitation.ImitationArgs; these
    are GAIL's own, and the defaults GAIL changes.

    Attributes:
        out: run folder: gail.safetensors, run.json, tensorboard/, checkpoints/.
        hidden: hidden sizes of the policy and value MLPs.
        activation: hidden activation of the policy and value MLPs.
        lr: Adam learning rate of the policy and value networks.
        seed: seed of the weights, minibatches, action sampling and training scenarios.
        checkpoint_every: write a checkpoint policy every this many env steps.
        total_steps: env steps of generator experience.
        num_envs: env rows stepped together (B).
        rollout_len: steps per row per iteration; B * rollout_len transitions per update.
        scenario_repeats: episodes on each training scenario before a new one is drawn (the
            original regenerated one every 20 resets for GAIL).
        max_episode_steps: episode time limit of the training env, steps (the benchmark's 3200).
        disc_hidden: hidden sizes of the discriminator MLP (tanh).
        reward: the generator's reward from D: "logit" log D - log(1 - D), "positive"
            -log(1 - D), "negative" log D.
        disc_lr: Adam learning rate of the discriminator.
        disc_epochs: passes of the discriminator over each iteration's transitions.
        grad_penalty: gradient-penalty weight of GAILLoss (0: none).
        ppo_epochs: PPO passes over each iteration's transitions.
        minibatch: transitions per gradient step (PPO and discriminator), at most an iteration's
            (num_envs * rollout_len).
        gamma: discount.
        gae_lambda: GAE lambda.
        clip_epsilon: PPO ratio clip.
        entropy_coeff: entropy bonus weight.
        critic_coeff: value loss weight.
        max_grad_norm: gradient-norm clip of the PPO update.
    """

    out: Path = Path("runs/gail")
    hidden: tuple[int, ...] = (64, 64)
    activation: Activation = "tanh"
    total_steps: int = 200_000
    num_envs: int = 40
    rollout_len: int = 50
    scenario_repeats: int = 20
    max_episode_steps: int = 3200
    disc_hidden: tuple[int, ...] = (64, 64)
    reward: GailReward = "logit"
    disc_lr: float = 1e-3
    disc_epochs: int = 2
    grad_penalty: float = 0.0
    ppo_epochs: int = 4
    minibatch: int = 500
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_epsilon: float = 0.2
    entropy_coeff: float = 0.01
    critic_coeff: float = 0.5
    max_grad_norm: float = 0.5

    def __post_init__(self) -> None:
        super().__post_init__()
        coerce(self, disc_hidden=tuple)
        check_int(self, "total_steps", "num_envs", "rollout_len", "scenario_repeats", low=1)
        check_int(self, "max_episode_steps", "disc_epochs", "ppo_epochs", "minibatch", low=1)
        check_sizes(self, "disc_hidden")
        check_choice(self, "reward", GailReward)
        check_number(self, "disc_lr", "clip_epsilon", "max_grad_norm", low=0.0, low_open=True)
        check_number(self, "grad_penalty", "entropy_coeff", "critic_coeff", low=0.0)
        check_number(self, "gamma", "gae_lambda", low=0.0, high=1.0)
        check_minibatch(
            self, "minibatch", self.frames_per_batch, "an iteration's transitions, num_envs * rollout_len"
        )
        check_whole_batches(
            self, "total_steps", self.frames_per_batch, "an iteration's transitions, num_envs * rollout_len"
        )

    @property
    def frames_per_batch(self) -> int:
        """Transitions per iteration: num_envs * rollout_len."""
        return self.num_envs * self.rollout_len


def discriminator_loss(discriminator: Any, grad_penalty: float = 0.0) -> Any:
    """TorchRL's GAILLoss over a Discriminator (expert transitions labelled 1, the generator's 0)."""
    from tensordict.nn import TensorDictModule
    from torchrl.objectives import GAILLoss

    module = TensorDictModule(discriminator, in_keys=["observation", "action"], out_keys=["d_logits"])
    return GAILLoss(module, use_grad_penalty=grad_penalty > 0, gp_lambda=grad_penalty)


def discriminator_step(
    loss_module: Any, optimizer: Any, expert: tuple[Any, Any], generated: tuple[Any, Any]
) -> float:
    """One gradient step of the discriminator on equal-sized batches of (observation, one-hot
    action) from the demonstrations and from the generator; returns the loss."""
    from tensordict import TensorDict

    pair = TensorDict(
        observation=expert[0],
        action=expert[1],
        collector_observation=generated[0],
        collector_action=generated[1],
        batch_size=[len(expert[0])],
    )
    loss = loss_module(pair)["loss"]
    optimizer.zero_grad()
    loss.backward()
    optimizer.step()
    return float(loss.item())


def gail_reward(logits: Any, kind: GailReward) -> Any:
    """The generator's reward from discriminator logits l = log D - log(1 - D), clipped to +-REWARD_CLIP."""
    import torch.nn.functional as F

    if kind == "logit":
        reward = logits
    elif kind == "positive":
        reward = F.softplus(logits)  # -log(1 - D)
    else:
        reward = -F.softplus(-logits)  # log D
    return reward.clamp(-REWARD_CLIP, REWARD_CLIP)


def train(args: Args) -> Path:
    """Run GAIL on the trainer skeleton, which seeds torch's global generator for the run (TorchRL's
    action sampling draws from it); returns gail.safetensors, or that of a finished run of the same
    arguments in args.out.

    `socialzoo train gail --demos FILE --steps N --out DIR`: a discriminator D(s, a) learns to tell the
    demonstrations (label 1) from the generator's own transitions (label 0) with TorchRL's GAILLoss; the
    generator is a PPO policy (ClipPPOLoss, GAE) trained on the reward log D - log(1 - D) only (the env's
    reward is logged, never learned from). Rollouts come from the batched TorchRL env
    (socialzoo.env.torchrl_single) on the training map's own seeded scenario stream, never a test set; by
    default each scenario runs 20 times before a new one is drawn (the original's GAIL set-up). Writes
    DIR/gail.safetensors (an MlpPolicy file: greedy actions), DIR/run.json, TensorBoard logs and a checkpoint
    policy every `checkpoint_every` env steps.
    """
    return run_training(TRAINER, args, lambda run: _fit(run, args))


def _fit(run: TrainingRun, args: Args) -> Mapping[str, Any]:
    import torch
    from torchrl.collectors import Collector
    from torchrl.modules import ValueOperator
    from torchrl.objectives import ClipPPOLoss
    from torchrl.objectives.value import GAE

    from socialzoo.env.config import EnvConfig
    from socialzoo.env.torchrl_single import ActionSelectionTorchEnv
    from socialzoo.train.policy_net import Discriminator, init_linear, make_actor, mlp

    parts = imitation_parts(run, args, max_steps=args.max_episode_steps)
    data, stats, generator, policy_net = parts.data, parts.stats, parts.generator, parts.net
    obs_size = data.obs.shape[1]

    actor = make_actor(policy_net)
    value_net = mlp(obs_size, args.hidden, 1, args.activation, stats)
    init_linear(value_net, generator, last_gain=1.0)
    critic = ValueOperator(value_net, in_keys=["observation"])
    discriminator = Discriminator(obs_size, args.disc_hidden, stats, generator)
    gail_loss = discriminator_loss(discriminator, args.grad_penalty)
    ppo_loss = ClipPPOLoss(
        actor,
        critic,
        clip_epsilon=args.clip_epsilon,
        entropy_bonus=args.entropy_coeff > 0,
        entropy_coeff=args.entropy_coeff,
        critic_coeff=args.critic_coeff,
        loss_critic_type="smooth_l1",
        normalize_advantage=True,
    )
    advantage = GAE(gamma=args.gamma, lmbda=args.gae_lambda, value_network=critic, average_gae=False)
    ppo_optim = torch.optim.Adam(ppo_loss.parameters(), lr=args.lr)
    disc_optim = torch.optim.Adam(gail_loss.parameters(), lr=args.disc_lr)

    config = EnvConfig(map=data.map).replace(
        observation=data.observation,
        scenario={"repeats": args.scenario_repeats},
        max_steps=args.max_episode_steps,
    )
    env = ActionSelectionTorchEnv(args.num_envs, config)
    env.set_seed(args.seed)
    collector = Collector(
        env,
        actor,
        frames_per_batch=args.frames_per_batch,
        total_frames=args.total_steps,
        split_trajs=False,
        # The actor needs no env transform (no recurrent state to initialise).
        auto_register_policy_transforms=False,
    )
    expert_obs = torch.as_tensor(data.obs)
    expert_act = torch.as_tensor(data.one_hot())
    frames = 0
    schedule = run.schedule(args.total_steps, args.checkpoint_every)
    outcomes: deque[float] = deque(maxlen=100)  # success of the latest finished episodes
    stats_log: dict[str, float] = {}

    def minibatches(n: int) -> list[Any]:
        order = torch.randperm(n, generator=generator)
        return [order[lo : lo + args.minibatch] for lo in range(0, n, args.minibatch)]

    bar = run.progress(args.total_steps, unit="step")
    writer = run.writer
    for batch in collector:
        flat = batch.reshape(-1)
        n = flat.numel()
        frames += n
        collector_act = flat["action"].to(torch.float32)
        # 1. The discriminator: demonstrations (label 1) against this iteration's transitions (0).
        for _ in range(args.disc_epochs):
            for idx in minibatches(n):
                pick = torch.randint(len(expert_obs), (len(idx),), generator=generator)
                disc_loss = discriminator_step(
                    gail_loss,
                    disc_optim,
                    (expert_obs[pick], expert_act[pick]),
                    (flat["observation"][idx], collector_act[idx]),
                )
        # 2. The generator's reward from the updated discriminator.
        with torch.no_grad():
            logits = discriminator.logits(batch["observation"], batch["action"])
            expert_logits = discriminator.logits(expert_obs[pick], expert_act[pick])
            env_reward = batch["next", "reward"].clone()
            batch["next", "reward"] = gail_reward(logits, args.reward)
            advantage(batch)
        # 3. PPO on that reward.
        flat = batch.reshape(-1)
        for _ in range(args.ppo_epochs):
            for idx in minibatches(n):
                losses = ppo_loss(flat[idx])
                loss = losses["loss_objective"] + losses["loss_critic"]
                if "loss_entropy" in losses.keys():
                    loss = loss + losses["loss_entropy"]
                ppo_optim.zero_grad()
                loss.backward()
                torch.nn.utils.clip_grad_norm_(ppo_loss.parameters(), args.max_grad_norm)
                ppo_optim.step()
        collector.update_policy_weights_()

        done = batch["next", "done"].reshape(-1)
        outcomes.extend(batch["next", "success"].reshape(-1)[done].to(torch.float32).tolist())
        actions = flat["action"].to(torch.float32).mean(0)
        stats_log = {
            "gail/disc_loss": disc_loss,
            "gail/disc_expert_prob": torch.sigmoid(expert_logits).mean().item(),
            "gail/disc_generator_prob": torch.sigmoid(logits).mean().item(),
            "gail/reward": batch["next", "reward"].mean().item(),
            "gail/env_reward": env_reward.mean().item(),
            "ppo/loss_objective": losses["loss_objective"].item(),
            "ppo/loss_critic": losses["loss_critic"].item(),
            "ppo/entropy": losses["entropy"].item() if "entropy" in losses.keys() else float("nan"),
            **{f"actions/{i}": actions[i].item() for i in range(len(actions))},
        }
        if outcomes:
            stats_log["episodes/success_rate_last100"] = float(np.mean(outcomes))
        for key, value in stats_log.items():
            writer.add_scalar(key, value, frames)
        bar.update(n)
        bar.set_postfix(
            D=f"{stats_log['gail/disc_expert_prob']:.2f}/{stats_log['gail/disc_generator_prob']:.2f}",
            success=f"{np.mean(outcomes):.2f}" if outcomes else "-",
        )
        if schedule.due(frames):
            # One checkpoint per batch, at the frames collected (a batch may pass several steps).
            run.checkpoint(frames, functools.partial(parts.save, env_steps=frames))
    collector.shutdown()
    parts.save(run.policy, env_steps=frames)
    return {
        "env_steps": frames,
        "demonstration_steps": len(data),
        "training_success_last100": float(np.mean(outcomes)) if outcomes else None,
        "final_stats": stats_log,
    }
