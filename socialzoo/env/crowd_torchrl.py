"""The CrowdNav task as a batched TorchRL environment (EnvBase) over CrowdNavCore.

TorchRL's conventions: batch size (B,), "observation" (the flat joint state), "action" (B, 2) in
[-1, 1] or (B, 81) one-hot (or integer indices with categorical_action_encoding=True),
("next", "reward"), done / terminated / truncated kept apart, a "success" flag on the last step of
a successful episode, and partial resets through the "_reset" mask (no autoreset inside a step).
Row i plays the same cases as row i of CrowdNavVectorEnv seeded alike. Observations are copied
into their tensors (the core rewrites reset rows of its arrays in place).

Imported lazily: TorchRL and torch are optional dependencies (the "train" extra).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from tensordict import TensorDictBase
from torchrl.data import Bounded, Categorical, Composite, OneHot, Unbounded
from torchrl.envs import EnvBase

from socialzoo.env.crowd_config import CrowdNavConfig, discrete_actions
from socialzoo.env.crowd_core import CrowdNavCore
from socialzoo.env.crowd_env import _one_robot, _resolve
from socialzoo.env.crowd_observation import flat_size
from socialzoo.env.crowd_source import CrowdCaseSource
from socialzoo.env.torchrl_common import step_tensordict


class CrowdNavTorchEnv(EnvBase):
    """B rows of the CrowdNav task stepped by one CrowdNavCore (see socialzoo.env.crowd_env for the
    task); the observation is always the flat layout.

    Args:
        num_envs: B.
        config: a CrowdNavConfig (default CrowdNav's task).
        categorical_action_encoding: discrete actions as integer indices instead of one-hot.
        device: torch device of the tensors (the simulation itself runs in numpy).
        **overrides: CrowdNavConfig fields as plain values, or variant=NAME.

    ## Version History
    - v1: initial release.
    """

    def __init__(
        self,
        num_envs: int,
        config: CrowdNavConfig | None = None,
        categorical_action_encoding: bool = False,
        device: str | torch.device = "cpu",
        **overrides: Any,
    ) -> None:
        if not isinstance(num_envs, int) or isinstance(num_envs, bool) or num_envs < 1:
            raise ValueError(f"CrowdNavTorchEnv: num_envs must be an int >= 1, got {num_envs!r}")
        self.config = _one_robot(
            _resolve(config, dict(overrides)).replace(observation="flat"), "CrowdNavTorchEnv"
        )
        super().__init__(device=device, batch_size=torch.Size([num_envs]))
        self.num_envs = num_envs
        self.categorical_action_encoding = categorical_action_encoding
        self.core = CrowdNavCore(self.config, num_envs)
        self.source = CrowdCaseSource(self.config, num_envs)
        self._started = False
        b = num_envs
        flag = Categorical(2, shape=(b, 1), dtype=torch.bool, device=self.device)
        self.observation_spec = Composite(
            observation=Unbounded((b, flat_size(self.config.observed_slots)), dtype=torch.float32, device=self.device),
            success=flag.clone(),
            shape=(b,),
        )
        if self.config.action == "discrete":
            n = len(discrete_actions(self.config.robot))
            self.action_spec = (
                Categorical(n, shape=(b,), device=self.device)
                if categorical_action_encoding
                else OneHot(n, shape=(b, n), device=self.device)
            )
        else:
            self.action_spec = Bounded(-1.0, 1.0, shape=(b, 2), dtype=torch.float32, device=self.device)
        self.reward_spec = Unbounded((b, 1), dtype=torch.float32, device=self.device)
        self.done_spec = Composite(
            done=flag.clone(), terminated=flag.clone(), truncated=flag.clone(), shape=(b,)
        )

    def _set_seed(self, seed: int | None) -> None:
        self.source.seed(seed)
        self._started = False

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        rows = np.arange(self.num_envs)
        mask = tensordict.get("_reset", None) if tensordict is not None else None
        if mask is not None and self._started:
            rows = np.flatnonzero(mask.reshape(self.num_envs).cpu().numpy())
        observation = self.core.reset_rows(rows, self.source.next(rows))
        self._started = True
        return step_tensordict(observation.flat(), self.batch_size, self.device)

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        action = tensordict.get("action")
        if self.config.action == "discrete":
            if not self.categorical_action_encoding:
                action = action.to(torch.float32).argmax(-1)
            actions = action.reshape(self.num_envs).cpu().numpy().astype(np.int64)
        else:
            actions = action.reshape(self.num_envs, 2).cpu().numpy().astype(np.float64)
        result = self.core.step(actions)
        o = result.outcome
        return step_tensordict(
            result.observation.flat(),
            self.batch_size,
            self.device,
            o.reward,
            o.success,
            o.terminated,
            o.truncated,
        )
