"""The single-robot benchmark as a batched TorchRL environment (EnvBase) over the core.

B rows of the Social Action Selection benchmark stepped by one SocialNavCore, with TorchRL's own
conventions: a (B,) batch, "observation", "action", ("next", "reward"), done / terminated /
truncated kept apart, and partial resets through the "_reset" mask (no auto-reset inside a step,
so ("next", "observation") is always the true last observation of an episode). Row i plays the
same scenarios as row i of the Gymnasium VectorEnv seeded alike.

Imported lazily: TorchRL and torch are optional dependencies (the "train" extra).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from tensordict import TensorDictBase
from torchrl.data import Categorical, Composite, OneHot, Unbounded
from torchrl.envs import EnvBase

from socialzoo.env.config import EnvConfig
from socialzoo.env.core import SocialNavCore
from socialzoo.env.scenario_source import ScenarioStream
from socialzoo.env.torchrl_common import step_tensordict
from socialzoo.nav.maps import Map
from socialzoo.nav.subpolicies import NUM_ACTIONS


def _num_learned_humans(config: EnvConfig) -> int:
    # The field is being renamed (learned_humans -> num_learned_humans); accept either spelling.
    return int(getattr(config, "num_learned_humans", getattr(config, "learned_humans", 0)))


class ActionSelectionTorchEnv(EnvBase):
    """Social Action Selection (one robot, Discrete(4) sub-policies) as a batched TorchRL env.

    ## Description
    B rows of the benchmark stepped by one `SocialNavCore`, with TorchRL's conventions: batch
    size (B,), partial resets through the "_reset" mask, no autoreset inside a step.

    ## Action Space
    "action": (B, 4) one-hot (or (B,) int64 with categorical_action_encoding=True), 0 GoAlone,
    1 Halt, 2 Follow, 3 Pass.

    ## Observation Space
    "observation": (B, D) float32, the env's observation layout (D = 107 for the paper layout;
    see `ActionSelectionEnv`).

    ## Rewards
    ("next", "reward"): (B, 1) float32, the benchmark reward (see `ActionSelectionEnv`).

    ## Starting State
    As `ActionSelectionEnv`: each row starts on the next scenario of its seeded stream.

    ## Episode End
    "done", "terminated" (goal reached or wall collision), "truncated" (time limit), each (B, 1)
    bool; "success" (B, 1) bool, True on the last step of an episode that the benchmark counts as
    a success (goal reached, no human or wall collision).

    Seeding: `set_seed(s)` seeds the rows' scenario streams as ActionSelectionVectorEnv.reset(seed=s)
    does; each row runs a scenario config.scenario.repeats times before drawing the next.

    ## Arguments
    Args:
        num_envs: B.
        config: an EnvConfig (default: the benchmark on gdc1); num_robots must be 1.
        map_data: an already loaded Map instead of config.map.
        categorical_action_encoding: actions as integer indices instead of one-hot vectors.
        device: torch device of the tensors (the simulation itself runs in numpy).
        **overrides: EnvConfig fields as plain values, e.g. map="ghc3", scenario={"repeats": 20}.

    Raises:
        ValueError: a config with several robots, learned humans or velocity actions.

    ## Version History
    - v1: force and blame no longer skip the passed human (only the followed one, SPEC 9); the
      robot's carrot stays in sight of its wall distance and its plans keep clear of walls;
      scenarios draw only feasible start/goal pairs (unchanged on GDC1/GHC3).
    - v0: initial release.
    """

    def __init__(
        self,
        num_envs: int,
        config: EnvConfig | None = None,
        map_data: Map | None = None,
        categorical_action_encoding: bool = False,
        device: str | torch.device = "cpu",
        **overrides: Any,
    ) -> None:
        if not isinstance(num_envs, int) or isinstance(num_envs, bool) or num_envs < 1:
            raise ValueError(f"ActionSelectionTorchEnv: num_envs must be an int >= 1, got {num_envs!r}")
        base = config if config is not None else EnvConfig()
        self.config = base.replace(**overrides) if overrides else base
        if self.config.num_robots != 1 or _num_learned_humans(self.config):
            raise ValueError("ActionSelectionTorchEnv needs num_robots=1 and no learned humans")
        if self.config.robot_action != "subpolicy":
            raise ValueError(
                f"ActionSelectionTorchEnv needs robot_action='subpolicy', got {self.config.robot_action!r}"
            )
        super().__init__(device=device, batch_size=torch.Size([num_envs]))
        self.num_envs = num_envs
        self.categorical_action_encoding = categorical_action_encoding
        self.core = SocialNavCore(self.config, num_envs, map_data=map_data)
        self.scenarios = ScenarioStream(self.core.map, num_envs, 1, self.config.scenario, self.config.family)
        self._started = False
        b, d = num_envs, self.config.observation.size
        flag = Categorical(2, shape=(b, 1), dtype=torch.bool, device=self.device)
        self.observation_spec = Composite(
            observation=Unbounded((b, d), dtype=torch.float32, device=self.device),
            success=flag.clone(),
            shape=(b,),
        )
        if categorical_action_encoding:
            self.action_spec = Categorical(NUM_ACTIONS, shape=(b,), device=self.device)
        else:
            self.action_spec = OneHot(NUM_ACTIONS, shape=(b, NUM_ACTIONS), device=self.device)
        self.reward_spec = Unbounded((b, 1), dtype=torch.float32, device=self.device)
        self.done_spec = Composite(
            done=flag.clone(), terminated=flag.clone(), truncated=flag.clone(), shape=(b,)
        )

    # ------------------------------------------------------------------ TorchRL hooks
    def _set_seed(self, seed: int | None) -> None:
        self.scenarios.seed(seed)
        self._started = False

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        rows = np.arange(self.num_envs)
        mask = tensordict.get("_reset", None) if tensordict is not None else None
        if mask is not None and self._started:
            rows = np.flatnonzero(mask.reshape(self.num_envs).cpu().numpy())
        self.core.reset_rows(rows, self.scenarios.next(rows))
        self._started = True
        return step_tensordict(self._obs(), self.batch_size, self.device)

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        action = tensordict.get("action")
        if not self.categorical_action_encoding:
            action = action.to(torch.float32).argmax(-1)
        actions = action.reshape(self.num_envs, 1).cpu().numpy().astype(np.int64)
        result = self.core.step(actions)
        terminated = result.terminated[:, 0]
        truncated = result.truncated[:, 0]
        ended = np.flatnonzero(terminated | truncated)
        success = np.zeros(self.num_envs, dtype=bool)
        if len(ended):
            success[ended] = [bool(s["success"]) for s in self.core.episode_summaries(ended)]
        return step_tensordict(
            self._obs(), self.batch_size, self.device, result.reward[:, 0], success, terminated, truncated
        )

    def _obs(self) -> torch.Tensor:
        return torch.as_tensor(self.core.obs[:, 0].copy(), device=self.device)
