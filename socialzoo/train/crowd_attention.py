"""Attention over people for the CrowdNav task (in the spirit of SARL's pooling, Chen et al. 2019),
as a Stable-Baselines3 features extractor.

Each person's row of the joint state is paired with the robot's (a (6 + 7,) vector, SARL's rotated
joint state), embedded by `embed` (an MLP), turned into a feature by `value`; an attention score
comes from the embedding and the mean embedding of the crowd (SARL's global state); the scores are
softmaxed over the present people only (the observation's mask) and weigh the features into one
crowd feature; the extractor outputs [robot state, crowd feature]. With nobody present the crowd
feature is 0. The network is permutation-invariant over the people and takes any head count up to
the observation's slots.

socialzoo.agents.crowd_policy runs the same network in numpy from the exported weights.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import torch
from gymnasium import spaces
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from socialzoo.env.crowd_observation import HUMAN_FEATURES, ROBOT_FEATURES

ROBOT_DIM = len(ROBOT_FEATURES)
HUMAN_DIM = len(HUMAN_FEATURES)


def _mlp(sizes: Sequence[int], last_relu: bool) -> nn.Sequential:
    layers: list[nn.Module] = []
    for i in range(len(sizes) - 1):
        layers.append(nn.Linear(sizes[i], sizes[i + 1]))
        if i < len(sizes) - 2 or last_relu:
            layers.append(nn.ReLU())
    return nn.Sequential(*layers)


class CrowdAttention(nn.Module):
    """The attention pooling network.

    Args:
        slots: person slots H of the flat observation.
        embed: hidden sizes of the embedding MLP (ReLU after every layer).
        value: hidden sizes of the feature MLP on the embedding (ReLU between layers).
        attention: hidden sizes of the score MLP (ReLU between layers; one score out).
    """

    def __init__(
        self, slots: int, embed: Sequence[int], value: Sequence[int], attention: Sequence[int]
    ) -> None:
        super().__init__()
        self.slots = slots
        self.embed = _mlp([ROBOT_DIM + HUMAN_DIM, *embed], last_relu=True)
        self.value = _mlp([embed[-1], *value], last_relu=False)
        self.score = _mlp([2 * embed[-1], *attention, 1], last_relu=False)
        self.features_dim = ROBOT_DIM + value[-1]

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        """(N, 6 + 8 H) flat observations -> (N, 6 + value[-1]) features."""
        n, h = obs.shape[0], self.slots
        robot = obs[:, :ROBOT_DIM]
        humans = obs[:, ROBOT_DIM : ROBOT_DIM + h * HUMAN_DIM].reshape(n, h, HUMAN_DIM)
        mask = obs[:, ROBOT_DIM + h * HUMAN_DIM :] > 0.5
        pairs = torch.cat((robot[:, None, :].expand(n, h, ROBOT_DIM), humans), dim=-1)
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
    value, attention)."""

    def __init__(
        self,
        observation_space: spaces.Box,
        slots: int,
        embed: Sequence[int] = (64, 64),
        value: Sequence[int] = (64, 32),
        attention: Sequence[int] = (64,),
    ) -> None:
        expected = ROBOT_DIM + (HUMAN_DIM + 1) * slots
        if observation_space.shape != (expected,):
            raise ValueError(
                f"CrowdAttentionExtractor: {slots} slots need a flat ({expected},) observation, "
                f"got {observation_space.shape}"
            )
        net = CrowdAttention(slots, embed, value, attention)
        super().__init__(observation_space, net.features_dim)
        self.net = net

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        """Features of a batch of flat observations."""
        return self.net(observations)


def attention_state(net: CrowdAttention) -> dict[str, Any]:
    """The network's weights as numpy arrays by name, and its shape, for the numpy policy."""
    weights = {
        f"attention.{k}": v.detach().cpu().numpy().astype("float32") for k, v in net.state_dict().items()
    }
    return weights
