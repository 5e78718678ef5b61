"""Attention over people for the CrowdNav task (in the spirit of SARL's pooling, Chen et al. 2019),
as a Stable-Baselines3 features extractor."""

from __future__ import annotations

from collections.abc import Sequence

import torch
from gymnasium import spaces
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from socialzoo.env.crowd_observation import human_features, robot_features
from socialzoo.train.policy_net import mlp


class CrowdAttention(nn.Module):
    """The attention pooling network.

    Each person's row of the joint state is paired with the robot's (a (6 + 7,) vector, SARL's rotated joint
    state; with the task's signals (9 + 8,): the nearest door in the robot part, the gesture in the person's,
    socialzoo.env.crowd_observation), embedded by `embed` (an MLP), turned into a feature by `value`; an
    attention score comes from the embedding and the mean embedding of the crowd (SARL's global state); the
    scores are softmaxed over the present people only (the observation's mask) and weigh the features into one
    crowd feature; the extractor outputs [robot state, crowd feature]. With nobody present the crowd feature
    is 0. The network is permutation-invariant over the people and takes any head count up to the
    observation's slots. socialzoo.agents.crowd_policy runs the same network in numpy from the exported
    weights.

    Args:
        slots: person slots H of the flat observation.
        embed: hidden sizes of the embedding MLP (ReLU after every layer).
        value: hidden sizes of the feature MLP on the embedding (ReLU between layers).
        attention: hidden sizes of the score MLP (ReLU between layers; one score out).
        signals: the observation's layout has the task's signals (CrowdNavConfig.signals: 9 robot
            and 8 person features), else CrowdNav's joint state (6 and 7).
    """

    def __init__(
        self,
        slots: int,
        embed: Sequence[int],
        value: Sequence[int],
        attention: Sequence[int],
        signals: bool = False,
    ) -> None:
        super().__init__()
        self.slots = slots
        self.signals = signals
        self.robot_dim = len(robot_features(signals))
        self.human_dim = len(human_features(signals))
        width = embed[-1]
        self.embed = nn.Sequential(
            *mlp(self.robot_dim + self.human_dim, embed[:-1], width, "relu", None), nn.ReLU()
        )
        self.value = mlp(width, value[:-1], value[-1], "relu", None)
        self.score = mlp(2 * width, attention, 1, "relu", None)
        self.features_dim = self.robot_dim + value[-1]

    @property
    def observation_size(self) -> int:
        """Length of the flat observation it reads: robot, people row by row, mask."""
        return self.robot_dim + (self.human_dim + 1) * self.slots

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        """(N, R + (P + 1) H) flat observations -> (N, R + value[-1]) features (R, P: the robot's and
        a person's features, 6 and 7, with signals 9 and 8)."""
        n, h, r, p = obs.shape[0], self.slots, self.robot_dim, self.human_dim
        robot = obs[:, :r]
        humans = obs[:, r : r + h * p].reshape(n, h, p)
        mask = obs[:, r + h * p :] > 0.5
        pairs = torch.cat((robot[:, None, :].expand(n, h, r), humans), dim=-1)
        emb = self.embed(pairs)
        present = mask.to(emb.dtype)[..., None]
        count = present.sum(1, keepdim=True)
        crowd = (emb * present).sum(1, keepdim=True) / count.clamp(min=1.0)
        scores = self.score(torch.cat((emb, crowd.expand_as(emb)), dim=-1))[..., 0]
        scores = scores.masked_fill(~mask, float("-inf"))
        weights = torch.softmax(scores, dim=1).nan_to_num(0.0)  # nobody present: all -inf -> 0
        pooled = (weights[..., None] * self.value(emb)).sum(1)
        return torch.cat((robot, pooled), dim=-1)


class CrowdAttentionExtractor(BaseFeaturesExtractor):
    """SB3 features extractor around CrowdAttention (features_extractor_kwargs: slots, embed,
    value, attention, signals)."""

    def __init__(
        self,
        observation_space: spaces.Box,
        slots: int,
        embed: Sequence[int] = (64, 64),
        value: Sequence[int] = (64, 32),
        attention: Sequence[int] = (64,),
        signals: bool = False,
    ) -> None:
        net = CrowdAttention(slots, embed, value, attention, signals)
        if observation_space.shape != (net.observation_size,):
            layout = "with signals" if signals else "without signals"
            raise ValueError(
                f"CrowdAttentionExtractor: {slots} slots {layout} need a flat ({net.observation_size},) "
                f"observation, got {observation_space.shape}"
            )
        super().__init__(observation_space, net.features_dim)
        self.net = net

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        """Features of a batch of flat observations."""
        return self.net(observations)
