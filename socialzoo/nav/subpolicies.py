"""The benchmark's discrete actions (SPEC section 7): GoAlone, Halt, Follow, Pass."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal

import numpy as np

from socialzoo.core.config import RobotConfig
from socialzoo.core.geometry import wrap_angle
from socialzoo.core.jit import kernel
from socialzoo.core.validation import check_choice, check_fields
from socialzoo.core.walls import WallIndex
from socialzoo.nav.distance_field import distance_field
from socialzoo.nav.local_planner import LocalPlannerConfig, plan_commands
from socialzoo.nav.visibility import nearest_visible_ahead

GO_ALONE = 0
HALT = 1
FOLLOW = 2
PASS = 3
ACTION_NAMES = ("GoAlone", "Halt", "Follow", "Pass")
NUM_ACTIONS = len(ACTION_NAMES)


@dataclass(frozen=True, kw_only=True)
class SubPolicyConfig:
    """Parameters of the four sub-policies (SPEC section 7).

    Attributes:
        go_alone_speed, follow_speed, pass_speed: speed limits, m/s.
        follow_distance: Follow drives to the point this far short of the human on the
            robot-human ray, m.
        pass_distance: Pass drives to the point this far beyond the human, m.
        pass_direction: the direction "beyond" is measured in. "heading" (default, SPEC
            section 7): the robot's current heading; the target turns with the robot while it
            swerves round the human. "carrot": from the robot towards its local target, the way
            it means to travel (steadier when the human is off to one side).
        go_alone_clearance_weight, follow_clearance_weight, pass_clearance_weight: the local
            planner's clearance weight (cost sign: negative rewards clearance).
        num_candidates: Follow and Pass choose among this many nearest visible humans ahead.
        heading_match_deg: a farther candidate is preferred only when its heading matches the
            direction to the local target better by more than this, degrees.
        still_speed: humans slower than this have no heading, m/s.
    """

    go_alone_speed: float = 1.5
    follow_speed: float = 1.5
    pass_speed: float = 2.25
    follow_distance: float = 1.0
    pass_distance: float = 1.5
    pass_direction: Literal["carrot", "heading"] = "heading"
    go_alone_clearance_weight: float = -0.5
    follow_clearance_weight: float = 0.0
    pass_clearance_weight: float = 0.5
    num_candidates: int = 3
    heading_match_deg: float = 30.0
    still_speed: float = 0.1

    def __post_init__(self) -> None:
        check_choice("SubPolicyConfig", "pass_direction", self.pass_direction, ("carrot", "heading"))
        signed = [f.name for f in fields(self) if f.name.endswith("clearance_weight")]
        check_fields(self, nonnegative=("heading_match_deg", "still_speed"), signed=signed)


def check_actions(action: np.ndarray, num_rows: int) -> np.ndarray:
    """Validate a batch of actions: (N,) integers in {0, 1, 2, 3}; returns them as intp.

    Raises:
        ValueError: naming the first bad value and its row, or the bad shape.
    """
    action = np.asarray(action)
    if action.shape != (num_rows,):
        raise ValueError(f"actions must have shape ({num_rows},), got {action.shape}")
    if action.dtype.kind == "b" or action.dtype.kind not in "iuf":
        raise ValueError(f"actions must be integers in 0..{NUM_ACTIONS - 1}, got dtype {action.dtype}")
    if action.dtype.kind == "f":
        bad = ~((action >= 0) & (action < NUM_ACTIONS) & (action == np.floor(action)))  # NaN: bad
    else:
        bad = (action < 0) | (action >= NUM_ACTIONS)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"action {action[row].item()!r} in row {row} is not one of "
            + ", ".join(f"{i} ({name})" for i, name in enumerate(ACTION_NAMES))
        )
    return action.astype(np.intp)


def select_target_human(
    robot_pose: np.ndarray,
    human_pos: np.ndarray,
    human_vel: np.ndarray,
    visible: np.ndarray,
    carrot: np.ndarray,
    cfg: SubPolicyConfig | None = None,
) -> np.ndarray:
    """The human Follow and Pass act on, for every row.

    Candidates are the `num_candidates` nearest visible humans ahead of the robot (x > 0 in the
    robot frame), a, b, c by distance. Each has a heading mismatch: the angle between its walking
    direction and the direction from the robot to the local target. As in the reference, a is
    kept unless b or c matches better by more than the threshold; then b, unless c beats b by
    the threshold too; else c (with another number of candidates: the nearest one that no
    farther one beats). A human slower than `still_speed` has no walking direction: its
    mismatch counts as 180 degrees, so it is kept only when it is the nearest and no moving
    candidate beats it by the threshold.

    Args:
        robot_pose: (N, 3) x, y (m), theta (rad), world frame.
        human_pos: (N, H, 2) world frame, m.
        human_vel: (N, H, 2) world frame, m/s.
        visible: (N, H) humans the robot sees (present and not occluded).
        carrot: (N, 2) local target, world frame, m.
        cfg: sub-policy parameters (defaults if None).

    Returns:
        (N,) int index of the chosen human, -1 where there is none.
    """
    cfg = cfg or SubPolicyConfig()
    n, num_humans = visible.shape
    count = min(cfg.num_candidates, num_humans)
    if count == 0:
        return np.full(n, -1, dtype=np.intp)
    # numpy's atan2, cos and sin and the angle wrap, on every human (their values do not depend
    # on which are candidates); the choice is one compiled pass (_choose_target_human).
    to_target = carrot - robot_pose[:, :2]
    target_dir = np.arctan2(to_target[:, 1], to_target[:, 0])
    mismatch = np.abs(wrap_angle(np.arctan2(human_vel[..., 1], human_vel[..., 0]) - target_dir[:, None]))
    chosen = np.empty(n, dtype=np.intp)
    _choose_target_human(
        robot_pose, np.cos(robot_pose[:, 2]), np.sin(robot_pose[:, 2]), human_pos, human_vel, visible,
        mismatch, count, cfg.still_speed**2, math.radians(cfg.heading_match_deg), chosen,
    )  # fmt: skip
    return chosen


@kernel
def _choose_target_human(
    robot_pose, cos, sin, human_pos, human_vel, visible, mismatch_all, count, still2, threshold, chosen
):  # fmt: skip
    """`select_target_human`'s choice per row, numpy's operations in its order: the `count`
    nearest visible humans ahead (ties to the lower slot, as a stable argsort), their mismatches
    (pi for a human slower than the still speed), and the first candidate that no farther one
    beats by `threshold`; -1 where no human is ahead."""
    num = human_pos.shape[1]
    dist2 = np.empty(num)
    taken = np.empty(num, dtype=np.bool_)
    order = np.empty(count, dtype=np.intp)
    mismatch = np.empty(count)
    for b in range(human_pos.shape[0]):
        c, s = cos[b], sin[b]
        for h in range(num):
            rx, ry = human_pos[b, h, 0] - robot_pose[b, 0], human_pos[b, h, 1] - robot_pose[b, 1]
            ahead = c * rx + s * ry > 0.0
            dist2[h] = rx * rx + ry * ry if visible[b, h] and ahead else math.inf
            taken[h] = False
        for k in range(count):
            best = -1
            for h in range(num):
                if taken[h]:
                    continue
                d = dist2[h]
                if best < 0 or d < dist2[best] or (math.isnan(dist2[best]) and not math.isnan(d)):
                    best = h
            taken[best] = True
            order[k] = best
            if not math.isfinite(dist2[best]):
                mismatch[k] = math.inf
            else:
                vx, vy = human_vel[b, best, 0], human_vel[b, best, 1]
                mismatch[k] = mismatch_all[b, best] if vx * vx + vy * vy > still2 else math.pi
        if not math.isfinite(dist2[order[0]]):
            chosen[b] = -1
            continue
        pick = 0
        for i in range(count):
            beaten = False
            for j in range(i + 1, count):
                if mismatch[i] - mismatch[j] >= threshold:  # False for inf - inf (NaN)
                    beaten = True
                    break
            if not beaten:
                pick = i
                break
        chosen[b] = order[pick]


def subpolicy_targets(
    action: np.ndarray,
    robot_pose: np.ndarray,
    carrot: np.ndarray,
    human_pos: np.ndarray,
    target_human: np.ndarray,
    cfg: SubPolicyConfig,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The local planner's inputs for each row's action.

    Args:
        action: (N,) int valid actions.
        robot_pose: (N, 3) x, y (m), theta (rad), world frame.
        carrot: (N, 2) local target of the global plan, world frame, m.
        human_pos: (N, H, 2) world frame, m.
        target_human: (N,) index of the human Follow or Pass act on (-1: none; any value for
            other actions).
        cfg: sub-policy parameters.

    Returns:
        (target (N, 2) world frame m, max_speed (N,) m/s, clearance_weight (N,)). Halt rows (and
        Follow or Pass rows without a human) get the carrot and a zero speed limit.
    """
    n = len(robot_pose)
    speeds = np.array([cfg.go_alone_speed, 0.0, cfg.follow_speed, cfg.pass_speed])
    weights = np.array(
        [cfg.go_alone_clearance_weight, 0.0, cfg.follow_clearance_weight, cfg.pass_clearance_weight]
    )
    social = (action == FOLLOW) | (action == PASS)
    if not social.any():
        return carrot, speeds[action], weights[action]
    pos = robot_pose[:, :2]
    human = human_pos[np.arange(n), np.maximum(target_human, 0)] if human_pos.shape[1] else pos
    to_human = human - pos
    dist = np.sqrt(to_human[:, 0] ** 2 + to_human[:, 1] ** 2)
    unit = to_human / np.maximum(dist, 1e-9)[:, None]
    follow_point = pos + np.maximum(dist - cfg.follow_distance, 0.0)[:, None] * unit
    if cfg.pass_direction == "heading":
        direction = np.stack((np.cos(robot_pose[:, 2]), np.sin(robot_pose[:, 2])), axis=-1)
    else:
        to_carrot = carrot - pos
        direction = to_carrot / np.maximum(np.sqrt((to_carrot**2).sum(-1)), 1e-9)[:, None]
    pass_point = human + cfg.pass_distance * direction
    has_human = (target_human >= 0)[:, None]
    is_follow = ((action == FOLLOW)[:, None]) & has_human
    is_pass = ((action == PASS)[:, None]) & has_human
    target = np.where(is_follow, follow_point, np.where(is_pass, pass_point, carrot))
    max_speed = np.where(social & (target_human < 0), 0.0, speeds[action])
    return target, max_speed, weights[action]


def subpolicy_commands(
    action: np.ndarray,
    robot_pose: np.ndarray,
    robot_vel: np.ndarray,
    carrot: np.ndarray,
    human_pos: np.ndarray,
    human_vel: np.ndarray,
    human_mask: np.ndarray,
    walls: WallIndex,
    cfg: SubPolicyConfig,
    planner_cfg: LocalPlannerConfig,
    robot_cfg: RobotConfig,
    dt: float,
    visible: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Robot commands for a batch of sub-policy actions, planned in one local-planner call.

    GoAlone drives to the carrot. Halt stops at once. Follow drives to the point
    `follow_distance` short of the target human on the robot-human ray (the robot itself when the
    human is nearer than that: it waits). Pass drives to the point `pass_distance` beyond the
    target human in the direction of travel (see `SubPolicyConfig.pass_direction`). Follow or
    Pass without a target human halt. Every present human, the followed one included, is an
    obstacle to the planner.

    Each action sets the local planner's target, speed limit and clearance weight (`subpolicy_targets`);
    one call plans every row of the batch, whatever its action.

    Args:
        action: (N,) int in {0 GoAlone, 1 Halt, 2 Follow, 3 Pass}.
        robot_pose: (N, 3) x, y (m), theta (rad), world frame.
        robot_vel: (N, 2) (v, omega), m/s and rad/s.
        carrot: (N, 2) local target of the global plan, world frame, m.
        human_pos: (N, H, 2) world frame, m.
        human_vel: (N, H, 2) world frame, m/s.
        human_mask: (N, H) present humans.
        walls: the map's wall index.
        cfg: sub-policy parameters.
        planner_cfg: local planner parameters.
        robot_cfg: robot limits.
        dt: control period, s.
        visible: (N, H) which humans each robot sees, when the caller already knows it (an env
            core computes it for the observation of this very state); else it is computed here
            for the few humans that target selection needs.

    Returns:
        (command, halt, target_human): command (N, 2) (v, omega) (zero where halting), halt (N,)
        bool (velocity to be zeroed at once), target_human (N,) int index of the human followed or
        passed, -1 for other rows and where no human qualifies.

    Raises:
        ValueError: an action outside {0, 1, 2, 3} (naming the value and its row), before anything
            is computed.
    """
    n = len(robot_pose)
    action = check_actions(action, n)
    social = (action == FOLLOW) | (action == PASS)
    target_human = np.full(n, -1, dtype=np.intp)
    if social.any():
        rows = np.flatnonzero(social)
        pose = robot_pose[rows]
        if visible is not None:
            seen = visible[rows] & human_mask[rows]
        else:
            field = distance_field(
                walls, planner_cfg.field_resolution, planner_cfg.field_range, planner_cfg.field_pad
            )
            seen = nearest_visible_ahead(
                pose, human_pos[rows], human_mask[rows], walls, cfg.num_candidates, field
            )
        target_human[rows] = select_target_human(
            pose, human_pos[rows], human_vel[rows], seen, carrot[rows], cfg
        )
    halt = (action == HALT) | (social & (target_human < 0))

    target, max_speed, weight = subpolicy_targets(action, robot_pose, carrot, human_pos, target_human, cfg)
    command = plan_commands(
        robot_pose,
        robot_vel,
        target,
        max_speed,
        weight,
        walls,
        human_pos,
        human_mask,
        planner_cfg,
        robot_cfg,
        dt,
        active=~halt,
        human_vel=human_vel,
    )
    return command, halt, target_human
