"""What the single-robot TorchRL envs (socialzoo.env.torchrl_single, crowd_torchrl) share: the
tensordict of a reset or a step, with TorchRL's done / terminated / truncated kept apart.
Imported lazily: TorchRL and torch are optional dependencies (the "train" extra).
"""

from __future__ import annotations

import numpy as np
import torch
from tensordict import TensorDict, TensorDictBase


def step_tensordict(
    observation: np.ndarray | torch.Tensor,
    batch_size: torch.Size,
    device: torch.device,
    reward: np.ndarray | None = None,
    success: np.ndarray | None = None,
    terminated: np.ndarray | None = None,
    truncated: np.ndarray | None = None,
) -> TensorDictBase:
    """The tensordict of B rows: "observation" (copied into a new tensor), "success", "done",
    "terminated", "truncated" as (B, 1) flags (all False when not given, as after a reset) and
    "reward" (B, 1) float32 when given."""
    b = batch_size[0]

    def column(values: np.ndarray | None, dtype: torch.dtype = torch.bool) -> torch.Tensor:
        if values is None:
            return torch.zeros((b, 1), dtype=dtype, device=device)
        return torch.tensor(np.ascontiguousarray(values), dtype=dtype, device=device).reshape(b, 1)

    no_end = np.zeros(b, dtype=bool)
    term = no_end if terminated is None else terminated
    trunc = no_end if truncated is None else truncated
    obs = (
        observation
        if isinstance(observation, torch.Tensor)
        else torch.tensor(np.asarray(observation), device=device)
    )
    data = {
        "observation": obs,
        "success": column(success),
        "done": column(term | trunc),
        "terminated": column(term),
        "truncated": column(trunc),
    }
    if reward is not None:
        data["reward"] = column(np.asarray(reward, dtype=np.float32), torch.float32)
    return TensorDict(data, batch_size=batch_size, device=device)
