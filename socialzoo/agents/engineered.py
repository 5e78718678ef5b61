"""The engineered baselines of the benchmark (SPEC section 10): GoAlone, and the reference policy Ref
(GoAlone while the corridor ahead is clear, Follow a human walking our way, else Halt)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from socialzoo.agents.base import check_observations
from socialzoo.core.geometry import wrap_angle
from socialzoo.core.validation import check_fields, check_number
from socialzoo.env.observation import (
    PAPER_TARGET,
    SLOT_POS,
    observation_size,
    paper_human_velocity,
    paper_num_slots,
    paper_slot_seen,
    paper_slots,
)
from socialzoo.nav.subpolicies import FOLLOW, GO_ALONE, HALT

if TYPE_CHECKING:
    from socialzoo.env.core import BatchedCore
    from socialzoo.env.tasks.base import Task


class GoAlone:
    """Always action 0 (GoAlone): follow the global plan's carrot, ignoring everybody."""

    name = "goalone"

    def act(self, obs: np.ndarray, task: Task | None = None) -> np.ndarray:
        """Zeros of shape obs.shape[:-1] (see socialzoo.agents.base.Policy.act)."""
        obs = check_observations(obs, "GoAlone.act")
        return np.zeros(obs.shape[:-1], dtype=np.int64)

    def config(self) -> dict[str, Any]:
        """GoAlone has no parameters: {}."""
        return {}


@dataclass(frozen=True, kw_only=True)
class RefConfig:
    """Parameters of the reference policy (SPEC section 10).

    Attributes:
        corridor_half_width: a human blocks the way when |y| (robot frame) is at most this, m.
        lookahead_margin: ... and when it is closer than |local target| + this margin, m.
        heading_tolerance: Follow when the blocking human walks within this angle of the
            direction to the local target, rad.
        sector_deg: half-angle of the front sector, degrees: only humans with x > 0 and a
            bearing within +-sector_deg count. The default 90 is the whole half-plane x > 0 (the
            SPEC's "ahead"); the corridor test then does the narrowing.
        still_speed: a human slower than this has no walking direction (never followed), m/s.
    """

    corridor_half_width: float = 0.62
    lookahead_margin: float = 0.9
    heading_tolerance: float = 0.8
    sector_deg: float = 90.0
    still_speed: float = 0.1

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("lookahead_margin", "still_speed"))
        check_number("RefConfig", "sector_deg", self.sector_deg, high=90)  # humans ahead only


def ref_actions(
    human_xy: np.ndarray,
    human_vel: np.ndarray,
    seen: np.ndarray,
    target_xy: np.ndarray,
    cfg: RefConfig | None = None,
) -> np.ndarray:
    """Ref's action for each of N robots, from what each sees in its own frame.

    A human blocks the way when it is seen, ahead (x > 0, bearing within the front sector),
    inside the corridor |y| <= corridor_half_width and closer than |local target| +
    lookahead_margin. No blocker: GoAlone. Otherwise the nearest blocker decides: if it walks
    (speed >= still_speed) in a direction within heading_tolerance of the direction to the
    local target, Follow; else Halt. Ref never passes.

    A pure, batched function of what the robot sees in its own frame.

    Args:
        human_xy: (N, H, 2) human centres relative to the robot, robot frame, m.
        human_vel: (N, H, 2) the humans' own (world) velocities expressed in robot axes, m/s
            (not relative to the robot: a human standing still has zero velocity).
        seen: (N, H) bool, the humans the robot sees (present and not occluded).
        target_xy: (N, 2) the local target (carrot), robot frame, m.
        cfg: parameters (defaults if None).

    Returns:
        (N,) int64 actions in {0 GoAlone, 1 Halt, 2 Follow}.
    """
    cfg = cfg or RefConfig()
    x, y = human_xy[..., 0], human_xy[..., 1]
    dist = np.sqrt(x**2 + y**2)
    ahead = (x > 0.0) & (np.abs(np.arctan2(y, x)) <= math.radians(cfg.sector_deg))
    reach = np.sqrt((target_xy**2).sum(-1)) + cfg.lookahead_margin
    blocking = np.asarray(seen, dtype=bool) & ahead & (np.abs(y) <= cfg.corridor_half_width)
    blocking &= dist < reach[:, None]
    n = len(target_xy)
    if human_xy.shape[1] == 0:
        return np.full(n, GO_ALONE, dtype=np.int64)
    nearest = np.argmin(np.where(blocking, dist, np.inf), axis=1)
    vel = human_vel[np.arange(n), nearest]
    moving = vel[:, 0] ** 2 + vel[:, 1] ** 2 >= cfg.still_speed**2
    target_dir = np.arctan2(target_xy[:, 1], target_xy[:, 0])
    mismatch = np.abs(wrap_angle(np.arctan2(vel[:, 1], vel[:, 0]) - target_dir))
    follow = moving & (mismatch <= cfg.heading_tolerance)
    action = np.where(blocking.any(axis=1), np.where(follow, FOLLOW, HALT), GO_ALONE)
    return action.astype(np.int64)


def ref_inputs_from_paper_obs(obs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`ref_actions`' inputs from paper-layout observations (N, 7 + 4K).

    The layout is read through socialzoo.env.observation's named pieces: positions are the
    slots' SLOT_POS, velocities the humans' own (`paper_human_velocity`), seen slots those with a
    non-zero position (`paper_slot_seen`), the target PAPER_TARGET.

    Raises:
        ValueError: the width is not 7 + 4K.
    """
    try:
        paper_num_slots(obs.shape[-1])
    except ValueError as err:
        raise ValueError(f"Ref: {err}; for another layout pass the task (Ref.act(obs, task))") from None
    obs = obs.astype(np.float64)
    xy = paper_slots(obs)[..., SLOT_POS]
    return xy, paper_human_velocity(obs), paper_slot_seen(obs), obs[:, PAPER_TARGET]


def ref_inputs_from_core(core: BatchedCore) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`ref_actions`' inputs for all B*R robots of a task's core, from its world state and carrots.

    Visibility is the one the core computed for the task's latest observation.
    """
    state = core.state
    if state is None:
        raise RuntimeError("Ref: the core has no state yet (reset_rows first)")
    b, r = state.robot_pose.shape[:2]
    pose = state.robot_pose.reshape(b * r, 3)
    human_pos = np.repeat(state.human_pos, r, axis=0)
    human_vel = np.repeat(state.human_vel, r, axis=0)
    seen = core.visible
    c, s = np.cos(pose[:, 2])[:, None], np.sin(pose[:, 2])[:, None]

    def to_robot_axes(vec: np.ndarray) -> np.ndarray:
        return np.stack((c * vec[..., 0] + s * vec[..., 1], c * vec[..., 1] - s * vec[..., 0]), axis=-1)

    rel = human_pos - pose[:, None, :2]
    carrot = core.carrot.reshape(b * r, 1, 2) - pose[:, None, :2]
    return to_robot_axes(rel), to_robot_axes(human_vel), seen, to_robot_axes(carrot)[:, 0]


class Ref:
    """The engineered reference policy (SPEC section 10); see `ref_actions`.

    With the paper observation layout Ref acts on the observation alone (so its demonstrations
    are a function of what a learner sees); with another layout it needs the task.

    The Ref policy feeds `ref_actions` from the paper observation, or from the task's core (world state, sight
    and carrots) for layouts that lack the robot's velocity.

    Args:
        config: Ref's parameters; keyword arguments build one when config is None.
    """

    name = "ref"

    def __init__(self, config: RefConfig | None = None, **kwargs: Any) -> None:
        if config is not None and kwargs:
            raise ValueError("Ref: give either config or keyword parameters, not both")
        self.cfg = config if config is not None else RefConfig(**kwargs)

    def act(self, obs: np.ndarray, task: Task | None = None) -> np.ndarray:
        """Actions of shape obs.shape[:-1] (see socialzoo.agents.base.Policy.act)."""
        obs = check_observations(obs, "Ref.act")
        lead = obs.shape[:-1]
        layout = "paper" if task is None else task.config.observation.layout
        if task is not None and getattr(task.config, "signals", False):
            # Ref reads no signals: the layout's own numbers, before the signal block.
            obs = obs[..., : observation_size(task.config.observation)]
        if layout == "paper":
            inputs = ref_inputs_from_paper_obs(obs.reshape(-1, obs.shape[-1]))
        else:
            inputs = ref_inputs_from_core(task.core)  # type: ignore[union-attr, attr-defined]
            if inputs[0].shape[0] != math.prod(lead):
                raise ValueError(f"Ref.act: observations of shape {obs.shape} do not match the core's batch")
        return ref_actions(*inputs, self.cfg).reshape(lead)

    def config(self) -> dict[str, Any]:
        """Ref's parameters (RefConfig) as plain JSON."""
        return asdict(self.cfg)
