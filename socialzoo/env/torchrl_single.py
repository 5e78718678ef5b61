"""The TorchRL env of any one-robot task: B rows of a Task as one batched EnvBase."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from tensordict import TensorDict, TensorDictBase
from torchrl.data import Bounded, Categorical, Composite, MultiCategorical, OneHot, TensorSpec, Unbounded
from torchrl.envs import EnvBase

from socialzoo.core.validation import check_int, check_seed
from socialzoo.env.gym_env import TaskAdapter, one_robot
from socialzoo.env.tasks.base import Task, batch_actions


def box_observation(task: Task, adapter: str) -> Task:
    """`task`, refused when its robot observation is not one Box (a TorchRL adapter's observation
    entry is one tensor; CrowdNav's observation="dict" is three)."""
    if not isinstance(task.observation_space, spaces.Box):
        raise ValueError(
            f"{adapter}: the task's observation must be one Box, got {task.observation_space} "
            "(the TorchRL adapters read one observation tensor; CrowdNav offers observation='flat')"
        )
    return task


def vector_action_spec(space: spaces.Space, batch: tuple[int, ...], device: Any = "cpu") -> TensorSpec:
    """The TorchRL spec of a batch (leading shape `batch`) of one agent's actions that are not one
    Discrete index: a MultiDiscrete's indices (int64), or a Box's float32 values within its
    bounds, entry by entry (a Box of v in [0, 1] and omega in [-1, 1] keeps both ranges)."""
    shape = batch + tuple(space.shape or ())
    if isinstance(space, spaces.MultiDiscrete):
        return MultiCategorical(space.nvec.tolist(), shape=shape, dtype=torch.int64, device=device)
    if not isinstance(space, spaces.Box):
        raise ValueError(f"no TorchRL action spec for space {space}")

    def bound(values: np.ndarray) -> torch.Tensor:
        return torch.as_tensor(np.broadcast_to(values, shape).astype(np.float32))

    return Bounded(bound(space.low), bound(space.high), shape=shape, dtype=torch.float32, device=device)


def one_hot_indices(values: np.ndarray, n: int, rows: int, who: str) -> np.ndarray:
    """(rows,) indices of (rows, n) one-hot actions (TorchRL's OneHot spec).

    Raises:
        ValueError: naming `who`: another shape, or a row that is not one 1 among zeros (all
            zeros, NaN, scores or probabilities: argmax would pick an action the policy never chose).
    """
    if values.shape != (rows, n):
        raise ValueError(f"{who}: one-hot actions must have shape {(rows, n)}, got {values.shape}")
    ones = values == 1
    bad = np.flatnonzero((ones.sum(-1) != 1) | ((values != 0) & ~ones).any(-1))
    if len(bad):
        raise ValueError(
            f"{who}: the action of row {bad[0]} is not one-hot (one 1 among zeros), got {values[bad[0]].tolist()}; "
            "integer actions need categorical_action_encoding=True"
        )
    return ones.argmax(-1)


def reset_rows(mask: torch.Tensor, rows: int, who: str) -> np.ndarray:
    """The rows that a root "_reset" entry of shape (rows, 1) or (rows,) names.

    Raises:
        ValueError: naming `who`, for a mask of another shape (torch's reshape error before).
    """
    if tuple(mask.shape) not in ((rows,), (rows, 1)):
        raise ValueError(
            f"{who}: '_reset' must be ({rows}, 1) flags, one per row, got shape {tuple(mask.shape)}"
        )
    return np.flatnonzero(mask.reshape(rows).cpu().numpy())


class TaskTorchEnv(TaskAdapter, EnvBase):
    """B rows of a one-robot task as a batched TorchRL EnvBase (below).

    TorchRL's own conventions: a (B,) batch, "observation" (B, D) float32, "action" (one-hot
    (B, n) or integer indices (B,) for a discrete task with categorical_action_encoding=True;
    (B, k) indices for a MultiDiscrete; (B, ...) floats for a Box, each entry within its bounds),
    ("next", "reward") (B, 1) float32, done / terminated / truncated kept apart, a "success" flag
    on the last step of a successful episode, and partial resets through the "_reset" mask (no
    autoreset inside a step, so ("next", "observation") is always the true last observation of an
    episode). Row i plays the same episodes as row i of the task's TaskVectorEnv seeded alike.
    Observations are copied into their tensors (the core rewrites reset rows of its arrays in
    place). The multi-agent view (robots and learned humans in groups)
    is socialzoo.env.torchrl_env.

    Seeding: `set_seed(s)` seeds the rows' training streams as TaskVectorEnv.reset(seed=s) does;
    each row's next episode comes from its new stream (a reset right after set_seed starts the rows
    it resets on it; the others finish their episodes first).

    Args:
        num_envs: B.
        config: the task's config object (None: its defaults).
        task: the task's registry name, "module:Class" path or class (default: `default_task`).
        categorical_action_encoding: discrete actions as integer indices instead of one-hot.
        device: torch device of the tensors (the simulation itself runs in numpy).
        **kwargs: the task's keyword arguments (config fields as plain values, map_data=...).

    Raises:
        ValueError: a bad batch size, a task with several robots or learned humans, or an
            observation that is not one Box (CrowdNav: observation="flat").
    """

    def __init__(
        self,
        num_envs: int,
        config: Any = None,
        *,
        task: Any = None,
        categorical_action_encoding: bool = False,
        device: str | torch.device = "cpu",
        **kwargs: Any,
    ) -> None:
        name = type(self).__name__
        check_int(name, "num_envs", num_envs, low=1)
        self.task = box_observation(one_robot(self.task_class(task)(config, num_envs, **kwargs), name), name)
        self.config = self.task.config
        super().__init__(device=device, batch_size=torch.Size([num_envs]))
        self.num_envs = num_envs
        self.categorical_action_encoding = categorical_action_encoding
        self._started = False
        b = num_envs
        flag = Categorical(2, shape=(b, 1), dtype=torch.bool, device=self.device)
        assert self.task.observation_space.shape is not None  # a Box (box_observation)
        self.observation_spec = Composite(
            observation=Unbounded(
                (b, *self.task.observation_space.shape), dtype=torch.float32, device=self.device
            ),
            success=flag.clone(),
            shape=(b,),
        )
        space = self.task.action_space
        if isinstance(space, spaces.Discrete):
            n = int(space.n)
            self.action_spec = (
                Categorical(n, shape=(b,), device=self.device)
                if categorical_action_encoding
                else OneHot(n, shape=(b, n), device=self.device)
            )
        else:
            self.action_spec = vector_action_spec(space, (b,), self.device)
        self.reward_spec = Unbounded((b, 1), dtype=torch.float32, device=self.device)
        self.done_spec = Composite(
            done=flag.clone(), terminated=flag.clone(), truncated=flag.clone(), shape=(b,)
        )

    # ------------------------------------------------------------------ TorchRL hooks
    def _set_seed(self, seed: int | None) -> None:
        # Only the streams: the rows' episodes go on until a reset, which restarts the rows its
        # "_reset" names (TorchRL keeps the other rows' data, so their episodes must go on too).
        self.task.seed(check_seed(type(self).__name__ + ".set_seed", seed))

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        rows = np.arange(self.num_envs)
        mask = tensordict.get("_reset", None) if tensordict is not None else None
        if mask is not None and self._started:  # the first reset starts every row
            rows = reset_rows(mask, self.num_envs, type(self).__name__)
        self.task.reset(rows, {})
        self._started = True
        return self._tensordict()

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        space, who = self.task.action_space, type(self).__name__
        assert space.shape is not None  # Discrete, MultiDiscrete or Box (__init__ refused any other)
        values = tensordict.get("action").detach().cpu().numpy()
        if isinstance(space, spaces.Discrete) and not self.categorical_action_encoding:
            values = one_hot_indices(values, int(space.n), self.num_envs, who)
        shape = (self.num_envs, *space.shape)
        if values.shape != shape and values.size == math.prod(shape):
            values = values.reshape(shape)  # (B, 1) indices, as some policies write them
        # Checked as the task's other adapters check them: 1.5 or NaN is no index, 5 no velocity.
        actions = batch_actions(space, values, (self.num_envs,), who)
        step = self.task.step(actions.reshape((self.num_envs, 1) + tuple(space.shape or ())))
        terminated = step.terminated[:, 0]
        truncated = step.truncated[:, 0]
        ended = np.flatnonzero(terminated | truncated)
        success = np.zeros(self.num_envs, dtype=bool)
        if len(ended):
            # A task without a "success" metric reports no successes.
            success[ended] = [bool(s.get("success", False)) for s in self.task.episode_metrics(ended)]
        return self._tensordict(step.reward[:, 0], success, terminated, truncated)

    def _tensordict(
        self,
        reward: np.ndarray | None = None,
        success: np.ndarray | None = None,
        terminated: np.ndarray | None = None,
        truncated: np.ndarray | None = None,
    ) -> TensorDictBase:
        """The tensordict of the rows: "observation" (a copy), "success", "done", "terminated",
        "truncated" as (B, 1) flags (all False when not given, as after a reset) and "reward"
        (B, 1) float32 when given."""
        b, device = self.num_envs, self.device

        def column(values: np.ndarray | None, dtype: torch.dtype = torch.bool) -> torch.Tensor:
            if values is None:
                return torch.zeros((b, 1), dtype=dtype, device=device)
            return torch.tensor(np.ascontiguousarray(values), dtype=dtype, device=device).reshape(b, 1)

        no_end = np.zeros(b, dtype=bool)
        term = no_end if terminated is None else terminated
        trunc = no_end if truncated is None else truncated
        data = {
            "observation": torch.tensor(np.asarray(self.task.observations()[:, 0]), device=device),
            "success": column(success),
            "done": column(term | trunc),
            "terminated": column(term),
            "truncated": column(trunc),
        }
        if reward is not None:
            data["reward"] = column(np.asarray(reward, dtype=np.float32), torch.float32)
        return TensorDict(data, batch_size=self.batch_size, device=device)


class ActionSelectionTorchEnv(TaskTorchEnv):
    """The Social Action Selection task as a batched TorchRL env (socialzoo.env.tasks.action_selection)."""

    default_task = "action_selection"


class CrowdNavTorchEnv(TaskTorchEnv):
    """The CrowdNav task as a batched TorchRL env (socialzoo.env.tasks.crowdnav; flat observation)."""

    default_task = "crowdnav"
