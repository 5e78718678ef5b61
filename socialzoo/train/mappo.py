"""MAPPO and IPPO for the agent groups of the native TorchRL env (socialzoo.env.torchrl_env)."""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tensordict import TensorDictBase
from tensordict.nn import AddStateIndependentNormalScale, TensorDictModule, TensorDictSequential
from torch import nn
from torchrl.collectors import Collector, MultiSyncCollector
from torchrl.data import LazyTensorStorage, ReplayBuffer
from torchrl.data.replay_buffers.samplers import SamplerWithoutReplacement
from torchrl.modules import MultiAgentMLP, ProbabilisticActor, TanhNormal
from torchrl.objectives import IPPOLoss, MAPPOLoss

from socialzoo.agents import make_policy
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.config import EnvConfig
from socialzoo.env.human_policy import LearnedHumanPolicy
from socialzoo.env.torchrl_env import HUMAN, ROBOT, SocialNavTorchEnv
from socialzoo.train.marl_args import Algo, CollectorKind
from socialzoo.train.policy_net import linear_layers, mlp

logger = logging.getLogger(__name__)


# ---------------------------------------------------------------------------- envs
def make_env(
    config: dict[str, Any], batch_size: int, seed: int, robot_policy: str | None
) -> SocialNavTorchEnv:
    """A native env of `batch_size` worlds (module level, so that collector workers can build it).

    Args:
        config: EnvConfig.to_dict() form.
        batch_size: B.
        seed: the scenario streams' seed.
        robot_policy: a policy spec (socialzoo.agents.make_policy) that drives the robots inside
            the env, or None when the robots are learned too.
    """
    policy = None if robot_policy is None else make_policy(robot_policy)
    return SocialNavTorchEnv(
        EnvConfig.from_dict(config), batch_size=batch_size, robot_policy=policy, seed=seed
    )


def env_factories(
    config: EnvConfig, batch_size: int, seed: int, robot_policy: str | None, count: int
) -> list[Callable[[], SocialNavTorchEnv]]:
    """`count` picklable env constructors with seeds seed, seed + 1, ... (one per collector worker)."""
    data = config.to_dict()
    return [functools.partial(make_env, data, batch_size, seed + i, robot_policy) for i in range(count)]


# ---------------------------------------------------------------------------- networks
class Normalize(nn.Module):
    """(x - loc) / scale with fixed statistics (buffers: saved with the network, not trained)."""

    loc: torch.Tensor
    scale: torch.Tensor

    def __init__(self, loc: torch.Tensor, scale: torch.Tensor) -> None:
        super().__init__()
        self.register_buffer("loc", loc.detach().clone().float())
        self.register_buffer("scale", scale.detach().clone().float())

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Normalised observations (x - loc) / scale."""
        return (x - self.loc) / self.scale


class MirrorSymmetric(nn.Module):
    """(f(x) + m * f(s * x)) / 2: a network that acts on a situation and on its mirror image alike.

    `s` negates the observation's y components (socialzoo.env.human_agents.human_mirror_signs) and
    `m` the action's, so the output for a mirrored situation is the mirrored output: a learned
    human with no handedness. Without it, shared-parameter humans drift into a side convention
    (keep right, to pass each other), which pushes them against the walls of narrow corridors.
    """

    in_signs: torch.Tensor
    out_signs: torch.Tensor

    def __init__(self, net: nn.Module, in_signs: torch.Tensor, out_signs: torch.Tensor) -> None:
        super().__init__()
        self.net = net
        self.register_buffer("in_signs", in_signs.detach().clone().float())
        self.register_buffer("out_signs", out_signs.detach().clone().float())

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """The symmetrised output."""
        return 0.5 * (self.net(x) + self.out_signs * self.net(x * self.in_signs))


def observation_stats(env: SocialNavTorchEnv, group: str, steps: int) -> tuple[torch.Tensor, torch.Tensor]:
    """(loc, scale) of the group's observations over `steps` random-action steps, agents in the mask.

    Features that never vary get scale 1, so the normalisation never divides by zero.
    """
    td = env.reset()
    chunks = []
    for _ in range(steps):
        chunks.append(td[group, "observation"][td[group, "mask"]])
        _, td = env.step_and_maybe_reset(env.rand_action(td))
    obs = torch.cat(chunks) if chunks else torch.zeros(0)
    if obs.shape[0] < 2:
        size = td[group, "observation"].shape[-1]
        return torch.zeros(size), torch.ones(size)
    loc, std = obs.mean(0), obs.std(0)
    return loc, torch.where(std > 1e-3, std, torch.ones_like(std))


def human_actor(
    obs_size: int,
    hidden: int,
    depth: int,
    loc: torch.Tensor,
    scale: torch.Tensor,
    walk_prior: float = 0.0,
    init_std: float = 1.0,
    action_scale: float = 1.0,
    mirror: torch.Tensor | None = None,
) -> ProbabilisticActor:
    """The learned humans' shared policy: TanhNormal over (B, L, 2) velocities in [-1, 1].

    `walk_prior` sets where training starts: the untrained policy's desired velocity is straight
    towards the waypoint at that fraction of the preferred speed (1: what a social-force human
    wants; 0: standing still), i.e. a mean action of (walk_prior / action_scale, 0) in the human's
    frame, where `action_scale` is EnvConfig.human_action_scale. `init_std` is the initial
    exploration noise before the tanh. `mirror`: the observation's mirror signs
    (socialzoo.env.human_agents.human_mirror_signs) make the mean MirrorSymmetric.
    """
    if not 0 <= walk_prior < action_scale:
        raise ValueError(
            f"human_actor: walk_prior must be in [0, action_scale = {action_scale}), got {walk_prior}"
        )
    body = mlp(obs_size, [hidden] * depth, 2, "tanh", None)
    last = body[-1]
    assert isinstance(last, nn.Linear)
    with torch.no_grad():
        # Small output weights: the prior, not the random initialisation, decides the first moves.
        last.weight.mul_(0.1)
        last.bias.copy_(torch.tensor([math.atanh(walk_prior / action_scale), 0.0]))
    mean: nn.Module = nn.Sequential(Normalize(loc, scale), body)
    if mirror is not None:
        mean = MirrorSymmetric(mean, mirror, torch.tensor([1.0, -1.0]))
    net = nn.Sequential(mean, AddStateIndependentNormalScale(2, init_value=math.log(init_std)))
    module = TensorDictModule(
        net, in_keys=[(HUMAN, "observation")], out_keys=[(HUMAN, "loc"), (HUMAN, "scale")]
    )
    return ProbabilisticActor(
        module,
        in_keys=[(HUMAN, "loc"), (HUMAN, "scale")],
        out_keys=[(HUMAN, "action")],
        distribution_class=TanhNormal,
        distribution_kwargs={"low": -1.0, "high": 1.0},
        return_log_prob=True,
        log_prob_key=(HUMAN, "action_log_prob"),
    )


def robot_actor(
    obs_size: int, num_actions: int, hidden: int, depth: int, loc: torch.Tensor, scale: torch.Tensor
) -> ProbabilisticActor:
    """The robots' shared policy: a Categorical over the sub-policies, (B, R) int64 actions."""
    net = nn.Sequential(Normalize(loc, scale), mlp(obs_size, [hidden] * depth, num_actions, "tanh", None))
    module = TensorDictModule(net, in_keys=[(ROBOT, "observation")], out_keys=[(ROBOT, "logits")])
    return ProbabilisticActor(
        module,
        in_keys={"logits": (ROBOT, "logits")},
        out_keys=[(ROBOT, "action")],
        distribution_class=torch.distributions.Categorical,
        return_log_prob=True,
        log_prob_key=(ROBOT, "action_log_prob"),
    )


def critic(
    group: str,
    obs_size: int,
    num_agents: int,
    algo: Algo,
    hidden: int,
    depth: int,
    loc: torch.Tensor,
    scale: torch.Tensor,
) -> TensorDictModule:
    """The group's value network: centralised (MAPPO) or per agent (IPPO), shared parameters."""
    net = nn.Sequential(
        Normalize(loc, scale),
        MultiAgentMLP(
            n_agent_inputs=obs_size,
            n_agent_outputs=1,
            n_agents=num_agents,
            centralized=algo == "mappo",
            share_params=True,
            depth=depth,
            num_cells=hidden,
            activation_class=nn.Tanh,
        ),
    )
    return TensorDictModule(net, in_keys=[(group, "observation")], out_keys=[(group, "state_value")])


# ---------------------------------------------------------------------------- learning
@dataclass(frozen=True, kw_only=True)
class PPOSettings:
    """The PPO hyper-parameters of one group (see the trainers' Args for their meaning)."""

    algo: Algo
    lr: float
    gamma: float
    lmbda: float
    clip_epsilon: float
    entropy_coef: float
    epochs: int
    minibatch_size: int
    max_grad_norm: float


class GroupLearner:
    """One agent group's actor, critic, MAPPO/IPPO loss and optimiser.

    Args:
        group: "robot" or "human".
        actor: the group's ProbabilisticActor.
        value: the group's critic.
        settings: the PPO hyper-parameters.
    """

    def __init__(
        self, group: str, actor: ProbabilisticActor, value: TensorDictModule, settings: PPOSettings
    ) -> None:
        self.group = group
        self.actor = actor
        self.value = value
        self.settings = settings
        loss_class = MAPPOLoss if settings.algo == "mappo" else IPPOLoss
        # Advantages are standardised in `update` over the agents that acted only (the loss's own
        # standardisation would count empty human slots and robots that left).
        self.loss = loss_class(
            actor,
            value,
            clip_epsilon=settings.clip_epsilon,
            entropy_coeff=settings.entropy_coef,
            normalize_advantage=False,
        )
        self.loss.set_keys(
            reward=(group, "reward"),
            action=(group, "action"),
            sample_log_prob=(group, "action_log_prob"),
            value=(group, "state_value"),
            done=(group, "done"),
            terminated=(group, "terminated"),
            advantage=(group, "advantage"),
            value_target=(group, "value_target"),
        )
        # The agents that acted: present humans and robots still in their episode.
        self.loss.loss_mask_key = (group, "mask")
        self.loss.make_value_estimator(gamma=settings.gamma, lmbda=settings.lmbda)
        self.optimizer = torch.optim.Adam(self.loss.parameters(), lr=settings.lr)

    def update(self, data: TensorDictBase, generator: torch.Generator) -> dict[str, float]:
        """PPO epochs over one collected batch (B, T); returns the mean losses."""
        s = self.settings
        with torch.no_grad():
            self.loss.value_estimator(
                data,
                params=self.loss.critic_network_params,
                target_params=self.loss.target_critic_network_params,
            )
        advantage = data[self.group, "advantage"]
        mask = data[self.group, "mask"].unsqueeze(-1).expand_as(advantage)
        valid = advantage[mask]
        if valid.numel() > 1:
            data[self.group, "advantage"] = (advantage - valid.mean()) / valid.std().clamp_min(1e-6)
        flat = data.reshape(-1)
        size = flat.shape[0]
        buffer = ReplayBuffer(
            storage=LazyTensorStorage(size),
            sampler=SamplerWithoutReplacement(),
            batch_size=min(s.minibatch_size, size),
            generator=generator,
        )
        buffer.extend(flat)
        sums: dict[str, float] = {}
        count = 0
        for _ in range(s.epochs):
            for _ in range(max(1, size // s.minibatch_size)):
                values = self.loss(buffer.sample())
                total = values["loss_objective"] + values["loss_critic"] + values["loss_entropy"]
                self.optimizer.zero_grad()
                total.backward()
                nn.utils.clip_grad_norm_(self.loss.parameters(), s.max_grad_norm)
                self.optimizer.step()
                for key in ("loss_objective", "loss_critic", "loss_entropy"):
                    sums[key] = sums.get(key, 0.0) + float(values[key].detach())
                count += 1
        return {k: v / count for k, v in sums.items()}


def group_stats(data: TensorDictBase, group: str) -> dict[str, float]:
    """Per-step means over the agents that acted in a collected batch: reward and info terms."""
    mask = data[group, "mask"]
    n = max(int(mask.sum()), 1)
    out = {"reward": float(data["next", group, "reward"].squeeze(-1)[mask].sum()) / n}
    info = data["next", group, "info"]
    for key in info.keys():
        if key != "target_human":  # an index, not a quantity
            out[key] = float(info[key][mask].sum()) / n
    out["agents"] = float(mask.float().mean())
    return out


def make_collector(
    kind: CollectorKind,
    factories: Sequence[Callable[[], SocialNavTorchEnv]],
    policy: TensorDictSequential,
    frames_per_batch: int,
    total_frames: int,
    ray_address: str | None = None,
) -> Any:
    """A TorchRL collector of `kind` over the envs `factories` build (one per worker).

    frames_per_batch counts world steps over all workers; each worker's env is stepped
    frames_per_batch / (workers x B) times per batch. Ray: a local Ray instance with one CPU
    per worker, or the cluster at `ray_address`.
    """
    common = {"frames_per_batch": frames_per_batch, "total_frames": total_frames}
    if kind == "single":
        return Collector(factories[0], policy, **common)
    if kind == "multiprocess":
        return MultiSyncCollector(list(factories), policy, **common)
    from torchrl.collectors.distributed import RayCollector

    from socialzoo.bench.runner import check_ray_address

    check_ray_address(ray_address)  # seconds, not Ray's minutes, for an address nothing answers at
    init = (
        {"address": ray_address} if ray_address else {"num_cpus": len(factories), "include_dashboard": False}
    )
    return RayCollector(
        list(factories),
        policy,
        num_collectors=len(factories),
        ray_init_config=init,
        remote_configs={"num_cpus": 1},
        sync=True,
        **common,
    )


# ---------------------------------------------------------------------------- export
def export_humans(actor: ProbabilisticActor, config: EnvConfig) -> LearnedHumanPolicy:
    """The numpy policy of a human actor: deterministic tanh of its mean, same normalisation,
    mirror-symmetric when the actor is, and the training world's walk of learned people (forces on
    them or not, their relaxation time), which a world that walks the file takes."""
    mean = actor.module[0].module[0]
    symmetric = isinstance(mean, MirrorSymmetric)
    inner = mean.net if symmetric else mean
    norm, body = inner[0], inner[1]
    walk = config.world.human
    return LearnedHumanPolicy(
        linear_layers(body),
        "tanh",
        norm.loc.cpu().numpy(),
        norm.scale.cpu().numpy(),
        config.num_human_neighbours,
        config.human_action_frame,
        config.human_action_scale,
        mirror_symmetric=symmetric,
        learned_forces=walk.learned_forces,
        relaxation_time=walk.learned_tau,
    )


def export_robot(actor: ProbabilisticActor, name: str, config: EnvConfig) -> MlpPolicy:
    """The numpy policy of a robot actor: greedy sub-policy from its logits.

    The fixed normalisation is folded into the first layer (W (x - loc) / scale + b), so the file
    is a plain MlpPolicy file.
    """
    net = actor.module[0].module
    norm, body = net[0], net[1]
    layers = linear_layers(body)
    w, b = layers[0]
    loc = norm.loc.cpu().numpy()
    scale = norm.scale.cpu().numpy()
    folded_w = (w / scale[None, :]).astype(np.float32)
    layers[0] = (folded_w, (b - folded_w @ loc).astype(np.float32))
    return MlpPolicy(name, layers, "tanh", dataclasses.asdict(config.observation))


# ---------------------------------------------------------------------------- the loop
@dataclass
class LoopResult:
    """What a training loop did.

    Attributes:
        frames: world steps collected.
        seconds: wall time of the loop.
        history: one dict per collected batch (frames, seconds, per-group stats and losses).
        checkpoints: the policy files written on the way.
    """

    frames: int
    seconds: float
    history: list[dict[str, float]]
    checkpoints: list[Path]


def train_loop(
    collector: Any,
    learners: dict[str, GroupLearner],
    schedule: Callable[[int], Sequence[str]],
    groups: Sequence[str],
    total_frames: int,
    checkpoint_at: Sequence[int],
    write_checkpoint: Callable[[int], list[Path]],
    writer: Any,
    bar: Any,
    seed: int,
    on_batch: Callable[[list[dict[str, float]]], Any] | None = None,
) -> LoopResult:
    """Collect, update, log and checkpoint until the collector has given `total_frames` frames.

    One frame is one world step (B frames per batched step); agent-steps are frames times agents.

    Args:
        collector: a TorchRL collector over the native env.
        learners: the learned groups by name.
        schedule: batch index -> the groups updated on that batch (alternating or simultaneous).
        groups: every group whose statistics are logged (learned or not).
        total_frames: frames to collect.
        checkpoint_at: frame counts after which to write a checkpoint (after the first batch at or
            past each, one for all it passes).
        write_checkpoint: frames collected so far -> files written.
        writer: a TensorBoard SummaryWriter (add_scalar).
        bar: a progress bar (update(n), set_postfix).
        seed: seeds the minibatch sampling.
        on_batch: called with the history so far after every batch (e.g. to write it out).

    Returns:
        The LoopResult.
    """
    generator = torch.Generator().manual_seed(seed)
    pending = sorted(checkpoint_at)
    frames = 0
    history: list[dict[str, float]] = []
    checkpoints: list[Path] = []
    start = time.perf_counter()
    for index, data in enumerate(collector):
        batch_frames = int(data.numel())
        frames += batch_frames
        record: dict[str, float] = {"frames": frames}
        for group in groups:
            for key, value in group_stats(data, group).items():
                record[f"{group}/{key}"] = value
        for group in schedule(index):
            for key, value in learners[group].update(data, generator).items():
                record[f"{group}/{key}"] = value
        collector.update_policy_weights_()
        record["seconds"] = time.perf_counter() - start
        record["frames_per_s"] = frames / max(record["seconds"], 1e-9)
        history.append(record)
        for key, value in record.items():
            if key != "frames":
                writer.add_scalar(key, value, frames)
        bar.update(batch_frames)
        if HUMAN in groups:
            bar.set_postfix(reward=f"{record[f'{HUMAN}/reward']:.4f}", refresh=False)
        if on_batch is not None:
            on_batch(history)
        if pending and frames >= pending[0]:
            # Named by the frames trained on: a batch may end past a checkpoint's count (or several).
            while pending and frames >= pending[0]:
                pending.pop(0)
            checkpoints += write_checkpoint(frames)
        if frames >= total_frames:
            break
    return LoopResult(frames, time.perf_counter() - start, history, checkpoints)
