"""Robot-centric observations of the Social Action Selection benchmark (SPEC section 8)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from gymnasium import spaces

from socialzoo.core.jit import kernel
from socialzoo.core.validation import check_choice, check_int

ObservationLayout = Literal["paper", "socialgym1"]

# The paper layout (SPEC section 8), defined here once. Everything that reads a paper observation
# (Ref, program-synthesis features, tests) indexes it through these names, never through numbers.
# Header: robot-frame goal and local target, the robot's own velocity, the previous action.
PAPER_GOAL = slice(0, 2)
"""Global goal (x, y) in the robot frame, m."""
PAPER_TARGET = slice(2, 4)
"""Local target (the carrot on the global plan) (x, y) in the robot frame, m."""
PAPER_ROBOT_VEL = slice(4, 6)
"""The robot's (v, omega), m/s and rad/s."""
PAPER_ROBOT_V = 4
"""The robot's linear speed v along its heading, m/s (first entry of PAPER_ROBOT_VEL)."""
PAPER_ROBOT_OMEGA = 5
"""The robot's angular speed omega, rad/s."""
PAPER_PREV_ACTION = 6
"""The previous sub-policy index (SPEC section 7) as a float; 0 before the first step."""
PAPER_HEADER_SIZE = 7
"""Entries before the human slots; slot i is [PAPER_HEADER_SIZE + 4i : PAPER_HEADER_SIZE + 4i + 4]."""
PAPER_SLOT_SIZE = 4
"""Numbers per human slot: x, y, vx, vy (fields below)."""
# Fields of one human slot: the last axis of `paper_slots(obs)`.
SLOT_POS = slice(0, 2)
"""The human's centre minus the robot's, robot axes, m."""
SLOT_VEL = slice(2, 4)
"""The human's world velocity minus the robot's, robot axes, m/s (build_observation)."""
SLOT_X, SLOT_Y, SLOT_VX, SLOT_VY = 0, 1, 2, 3
# The reference layout: 40 poses (x, y, theta), 40 velocities (vx, vy, omega), local target
# (x, y, 0), previous action.
SOCIALGYM1_NUM_SLOTS = 40
SOCIALGYM1_SIZE = 6 * SOCIALGYM1_NUM_SLOTS + 4
# Largest sub-policy index (SPEC section 7: Discrete(4)).
MAX_ACTION_INDEX = 3
# The signal block's tail after its K slot signals: the nearest door's point and closed flag.
DOOR_FEATURES: tuple[str, ...] = ("door_x", "door_y", "door_closed")
"""The nearest door in the signal block: its point nearest the robot (x, y), m, and closed (0/1)."""
# Largest gesture index (socialzoo.scenarios.script: NO_GESTURE 0, WAIT 1, PROCEED 2).
MAX_GESTURE = 2


@dataclass(frozen=True, kw_only=True)
class ObservationConfig:
    """Which observation the robot gets.

    Attributes:
        layout: "paper" (SPEC section 8: goal, local target, robot velocity, previous action,
            human slots of (x, y, vx, vy)) or "socialgym1" (the reference code's 244 numbers).
        num_human_slots: human slots of the paper layout. The socialgym1 layout always has 40
            and ignores this field.
    """

    layout: ObservationLayout = "paper"
    num_human_slots: int = 25

    def __post_init__(self) -> None:
        check_choice("ObservationConfig", "layout", self.layout, get_args(ObservationLayout))
        check_int("ObservationConfig", "num_human_slots", self.num_human_slots, low=0)

    @property
    def num_slots(self) -> int:
        """Human slots of the chosen layout."""
        return SOCIALGYM1_NUM_SLOTS if self.layout == "socialgym1" else self.num_human_slots

    @property
    def size(self) -> int:
        """Length of one observation vector."""
        return observation_size(self)


def _robot_frame_slots(
    robot_pose: np.ndarray,
    robot_vel: np.ndarray,
    points: np.ndarray,
    human_pos: np.ndarray,
    human_vel: np.ndarray,
    visible: np.ndarray,
    num_slots: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World points and the visible humans, nearest first, in the robot frame.

    Args:
        robot_pose: (B, 3) world frame.
        robot_vel: (B, 2) linear v (m/s) and angular omega (rad/s).
        points: (B, P, 2) world points to express in the robot frame, m.
        human_pos: (B, H, 2) human positions, world frame, m.
        human_vel: (B, H, 2) human velocities, world frame, m/s.
        visible: (B, H) bool.
        num_slots: K, the number of human slots.

    Returns:
        (points_r, slots, people): points_r (B, P, 2) in the robot frame; slots (B, min(K, H), 4)
        of (x, y, vx, vy) relative to the robot in robot axes, zero past the last visible human;
        people (B, min(K, H)) the human index in each slot, -1 past the last visible human.
    """
    batch, num_humans = visible.shape
    points_r = np.empty(points.shape)
    slots = np.zeros((batch, min(num_slots, num_humans), 4))
    people = np.full(slots.shape[:2], -1, dtype=np.intp)
    _fill_robot_frame(robot_pose, robot_vel, points, human_pos, human_vel, visible, points_r, slots, people)
    return points_r, slots, people


@kernel
def _fill_robot_frame(robot_pose, robot_vel, points, human_pos, human_vel, visible, points_r, slots, people):  # type: ignore[no-untyped-def]
    """_robot_frame_slots into points_r (B, P, 2), zeroed slots (B, K, 4) and people (B, K) of -1."""
    batch, num_humans = visible.shape
    taken = np.zeros(num_humans, dtype=np.bool_)
    for b in range(batch):
        x0, y0 = robot_pose[b, 0], robot_pose[b, 1]
        c, s = math.cos(robot_pose[b, 2]), math.sin(robot_pose[b, 2])
        for p in range(points.shape[1]):
            x, y = points[b, p, 0] - x0, points[b, p, 1] - y0
            points_r[b, p, 0] = c * x + s * y
            points_r[b, p, 1] = c * y - s * x
        # Visible humans nearest first (ties by index), one slot each.
        taken[:] = False
        for k in range(slots.shape[1]):
            best, pick = np.inf, -1
            for h in range(num_humans):
                if visible[b, h] and not taken[h]:
                    d2 = (human_pos[b, h, 0] - x0) ** 2 + (human_pos[b, h, 1] - y0) ** 2
                    if d2 < best:
                        best, pick = d2, h
            if pick < 0:
                break
            taken[pick] = True
            people[b, k] = pick
            x, y = human_pos[b, pick, 0] - x0, human_pos[b, pick, 1] - y0
            vx, vy = human_vel[b, pick, 0], human_vel[b, pick, 1]
            slots[b, k, 0] = c * x + s * y
            slots[b, k, 1] = c * y - s * x
            # The robot's own velocity in its frame is (v, 0).
            slots[b, k, 2] = c * vx + s * vy - robot_vel[b, 0]
            slots[b, k, 3] = c * vy - s * vx


def _paper(
    points_r: np.ndarray, slots: np.ndarray, robot_vel: np.ndarray, prev_action: np.ndarray, num_slots: int
) -> np.ndarray:
    """The paper layout from the robot-frame goal and carrot (points_r) and the human slots.

    Layout (K = num_slots; the named pieces PAPER_* and SLOT_* of this module): [0:2] goal
    (x, y), m; [2:4] local target, m; [4:6] robot (v, omega), m/s and rad/s; [6] previous action
    index; then K slots [7 + 4i : 11 + 4i] of (x, y, vx, vy) of the i-th nearest visible human
    relative to the robot (build_observation).
    """
    out = np.zeros((len(points_r), PAPER_HEADER_SIZE + PAPER_SLOT_SIZE * num_slots), dtype=np.float32)
    out[:, PAPER_GOAL] = points_r[:, 0]
    out[:, PAPER_TARGET] = points_r[:, 1]
    out[:, PAPER_ROBOT_VEL] = robot_vel
    out[:, PAPER_PREV_ACTION] = prev_action
    paper_slots(out)[:, : slots.shape[1]] = slots
    return out


def _socialgym1(
    points_r: np.ndarray, slots: np.ndarray, people: np.ndarray, prev_action: np.ndarray, theta_index: bool
) -> np.ndarray:
    """The reference code's 244 numbers from the robot-frame carrot (points_r) and the human slots.

    Layout: [3i : 3i + 3] for i < 40, human i's (x, y, theta); [120 + 3i : 123 + 3i] its
    (vx, vy, omega); [240:243] local target (x, y, 0); [243] previous action index. theta and
    omega are 0 (the reference stored a constant index in theta, SPEC section 11; `theta_index`
    writes each filled slot's person index there: ReferenceQuirks.human_theta_index). Human
    slots follow the module's conventions, the same values as the paper layout. The goal and the
    robot's velocity (but for the relative human velocities) are not part of this layout.
    """
    n, k = SOCIALGYM1_NUM_SLOTS, slots.shape[1]
    out = np.zeros((len(points_r), SOCIALGYM1_SIZE), dtype=np.float32)
    out[:, 0 : 3 * k : 3] = slots[..., 0]
    out[:, 1 : 3 * k : 3] = slots[..., 1]
    if theta_index:
        out[:, 2 : 3 * k : 3] = np.maximum(people, 0)
    out[:, 3 * n : 3 * n + 3 * k : 3] = slots[..., 2]
    out[:, 3 * n + 1 : 3 * n + 3 * k : 3] = slots[..., 3]
    out[:, 6 * n : 6 * n + 2] = points_r[:, 0]
    out[:, 6 * n + 3] = prev_action
    return out


@dataclass(frozen=True)
class Signals:
    """What the robots observe of their scenario's script (socialzoo.env.script), for B robots.

    Attributes:
        gesture: (B, H) int, the gesture each person shows now (0 none, 1 wait, 2 proceed).
        door_offset: (B, 2) the nearest door's point nearest the robot minus the robot's centre,
            world axes, m; zeros where there is no door (`nearest_door`).
        door_closed: (B,) bool, that door is closed now (False where there is none).
    """

    gesture: np.ndarray
    door_offset: np.ndarray
    door_closed: np.ndarray


def nearest_door(pos: np.ndarray, doors: np.ndarray, closed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The door nearest each robot: (offset (N, 2), closed (N,) bool).

    The offset is the door segment's point nearest the robot minus the robot's centre, world axes,
    m; a robot without doors gets zeros and False. Padding door slots (a zero segment open from
    -inf to inf, socialzoo.env.script.ScriptRunner) never count.

    Args:
        pos: (N, 2) robot centres, world frame, m.
        doors: (N, D, 6) x1, y1, x2, y2, t_open, t_close per door, m and s.
        closed: (N, D) bool, each door closed now.
    """
    n = len(pos)
    offset, shut = np.zeros((n, 2)), np.zeros(n, dtype=bool)
    if doors.shape[1] == 0:
        return offset, shut
    a, ab = doors[..., 0:2], doors[..., 2:4] - doors[..., 0:2]  # (N, D, 2)
    along = ((pos[:, None, :] - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12)
    rel = a + np.clip(along, 0.0, 1.0)[..., None] * ab - pos[:, None, :]
    padding = (doors[..., :4] == 0.0).all(-1) & (doors[..., 4] == -np.inf) & (doors[..., 5] == np.inf)
    dist2 = np.where(padding, np.inf, (rel * rel).sum(-1))
    k = np.argmin(dist2, axis=1)
    rows = np.arange(n)
    found = np.isfinite(dist2[rows, k])
    offset[found] = rel[rows, k][found]
    shut[found] = closed[rows, k][found]
    return offset, shut


def build_observation(
    cfg: ObservationConfig,
    robot_pose: np.ndarray,
    robot_vel: np.ndarray,
    goal: np.ndarray,
    carrot: np.ndarray,
    prev_action: np.ndarray,
    human_pos: np.ndarray,
    human_vel: np.ndarray,
    visible: np.ndarray,
    signals: Signals | None = None,
    theta_index: bool = False,
) -> np.ndarray:
    """The observation of `cfg.layout` (laid out by `_paper`, `_socialgym1`), robot frame.

    Conventions shared by both layouts:

    - Robot frame: origin at the robot centre, x along its heading, y to its left (metres).
    - Human slots hold the humans the robot sees (present, line of sight clear of walls), nearest
      first (stable order on ties: lower human index first). Slots past the last visible human are
      all zero, so an occluded or absent human never takes a slot; when more humans are visible
      than there are slots, the farthest are dropped.
    - A human's position is its centre minus the robot's centre, in robot axes. Its velocity is
      relative too: the human's world velocity minus the robot's world velocity (v along the
      heading), in robot axes. The frame's own rotation (omega x r) is not added: this is the
      velocity difference seen from a non-rotating frame aligned with the robot.
    - The previous action is the sub-policy index (SPEC section 7) as a float; adapters pass 0
      (GoAlone) before the first step, as the reference code did.

    With signals (EnvConfig.signals, off by default: the layouts above are then exactly as they
    are), a signal block follows the layout: the gesture of each human slot's person (0 none,
    1 wait, 2 proceed; socialzoo.scenarios.script; 0 for an empty slot), then the nearest door's
    point (x, y) in the robot frame and whether it is closed (0/1) (`nearest_door`; all zero
    without doors). `signal_block` reads it; `observation_size`, `observation_space` and
    `describe_observation` take `signals` and count it.

    Args:
        cfg: the layout and its human slots.
        robot_pose: (B, 3) x, y (m), heading (rad), world frame.
        robot_vel: (B, 2) v (m/s) and omega (rad/s).
        goal: (B, 2) global goal, m, world frame (not in the socialgym1 layout).
        carrot: (B, 2) local target on the global plan, m, world frame.
        prev_action: (B,) int sub-policy index of the previous step (0 before the first).
        human_pos: (B, H, 2) m, world frame.
        human_vel: (B, H, 2) m/s, world frame.
        visible: (B, H) bool, from socialzoo.nav.visibility.visible_humans.
        signals: the signal block that follows (build_observation): each slot's person's gesture,
            then the nearest door.
        theta_index: the socialgym1 layout's theta holds each person's index (the reference
            code's quirk, socialzoo.env.quirks); the paper layout has no theta and ignores it.

    Returns:
        (B, observation_size(cfg, signals is not None)) float32.
    """
    paper = cfg.layout == "paper"
    points = np.stack((goal, carrot), axis=1) if paper else carrot[:, None, :]
    points_r, slots, people = _robot_frame_slots(
        robot_pose, robot_vel, points, human_pos, human_vel, visible, cfg.num_slots
    )
    if paper:
        out = _paper(points_r, slots, robot_vel, prev_action, cfg.num_slots)
    else:
        out = _socialgym1(points_r, slots, people, prev_action, theta_index)
    if signals is None:
        return out
    k = cfg.num_slots
    block = np.zeros((len(out), k + len(DOOR_FEATURES)), dtype=np.float32)
    shown = np.take_along_axis(np.asarray(signals.gesture), np.maximum(people, 0), axis=1)
    block[:, : people.shape[1]] = np.where(people >= 0, shown, 0)
    c, s = np.cos(robot_pose[:, 2]), np.sin(robot_pose[:, 2])
    dx, dy = signals.door_offset[:, 0], signals.door_offset[:, 1]
    block[:, k] = c * dx + s * dy
    block[:, k + 1] = c * dy - s * dx
    block[:, k + 2] = signals.door_closed
    return np.concatenate((out, block), axis=1)


def observation_size(cfg: ObservationConfig, signals: bool = False) -> int:
    """Length of one observation vector of `cfg`'s layout (with the signal block, if `signals`)."""
    size = (
        SOCIALGYM1_SIZE
        if cfg.layout == "socialgym1"
        else PAPER_HEADER_SIZE + PAPER_SLOT_SIZE * cfg.num_human_slots
    )
    return size + (cfg.num_slots + len(DOOR_FEATURES) if signals else 0)


def signal_block(obs: np.ndarray, cfg: ObservationConfig) -> tuple[np.ndarray, np.ndarray]:
    """The signal block of observations with signals: ((..., K) each human slot's gesture,
    (..., 3) the nearest door's DOOR_FEATURES), views of `obs`.

    Raises:
        ValueError: the last axis is not observation_size(cfg, signals=True) long.
    """
    width, base = obs.shape[-1], observation_size(cfg)
    if width != observation_size(cfg, signals=True):
        raise ValueError(
            f"an observation with signals of this layout has {observation_size(cfg, signals=True)} numbers, "
            f"got {width}"
        )
    return obs[..., base : base + cfg.num_slots], obs[..., base + cfg.num_slots :]


def paper_num_slots(width: int) -> int:
    """K, the human slots of a paper observation of `width` numbers (PAPER_HEADER_SIZE + 4K).

    Raises:
        ValueError: `width` is not 7 + 4K for some K >= 0 (naming the width).
    """
    if width < PAPER_HEADER_SIZE or (width - PAPER_HEADER_SIZE) % PAPER_SLOT_SIZE:
        raise ValueError(
            f"a paper-layout observation has {PAPER_HEADER_SIZE} + {PAPER_SLOT_SIZE}K numbers, got {width}"
        )
    return (width - PAPER_HEADER_SIZE) // PAPER_SLOT_SIZE


def paper_slots(obs: np.ndarray) -> np.ndarray:
    """The human slots of paper observations as (..., K, 4), fields SLOT_X .. SLOT_VY.

    A view of `obs` (no copy) when its last axis is contiguous, as every observation the envs
    return is; index it with SLOT_POS and SLOT_VEL.

    Args:
        obs: (..., 7 + 4K) paper-layout observations.

    Raises:
        ValueError: the last axis is not 7 + 4K long.
    """
    k = paper_num_slots(obs.shape[-1])
    return obs[..., PAPER_HEADER_SIZE:].reshape(*obs.shape[:-1], k, PAPER_SLOT_SIZE)


def paper_slot_seen(obs: np.ndarray) -> np.ndarray:
    """(..., K) bool: the slot holds a visible human (its position is not zero).

    Empty slots are all zero; a visible human exactly at the robot's centre cannot happen (the
    two would be in collision long before), so a zero position means an empty slot.
    """
    return (paper_slots(obs)[..., SLOT_POS] != 0.0).any(axis=-1)


def paper_human_velocity(obs: np.ndarray) -> np.ndarray:
    """(..., K, 2) each slot's human's own (world) velocity, in robot axes, m/s.

    A slot stores the human's velocity minus the robot's; the robot's own velocity in its frame
    is (v, 0), so the human's is the slot's (vx + v, vy). Empty slots give (v, 0).
    """
    vel = np.array(paper_slots(obs)[..., SLOT_VEL], dtype=np.float64)
    vel[..., 0] += np.asarray(obs[..., PAPER_ROBOT_V], dtype=np.float64)[..., None]
    return vel


def observation_space(cfg: ObservationConfig, signals: bool = False) -> spaces.Box:
    """The float32 Box of one observation (no batch axis), with the signal block if `signals`.

    Positions and velocities are unbounded (maps have no fixed size, and the robot's limits are
    configuration); the previous action lies in [0, 3], a gesture in [0, 2], a door's closed flag
    in [0, 1]. A fresh Box each call: an env caches its own, so that seeding one env's space does
    not seed another's.
    """
    size = observation_size(cfg, signals)
    low = np.full(size, -np.inf, dtype=np.float32)
    high = np.full(size, np.inf, dtype=np.float32)
    action = PAPER_PREV_ACTION if cfg.layout == "paper" else SOCIALGYM1_SIZE - 1
    low[action] = 0.0
    high[action] = MAX_ACTION_INDEX
    if signals:
        base, k = observation_size(cfg), cfg.num_slots
        low[base : base + k], high[base : base + k] = 0.0, MAX_GESTURE
        low[size - 1], high[size - 1] = 0.0, 1.0
    return spaces.Box(low=low, high=high, dtype=np.float32)


def describe_observation(cfg: ObservationConfig, signals: bool = False) -> list[str]:
    """Name of every entry of an observation, in order (e.g. "goal_x", "human_3_vy"); with
    `signals`, then "human_i_signal" per slot and DOOR_FEATURES."""
    extra = [f"human_{i}_signal" for i in range(cfg.num_slots)] + list(DOOR_FEATURES) if signals else []
    if cfg.layout == "paper":
        names = ["goal_x", "goal_y", "target_x", "target_y", "robot_v", "robot_omega", "prev_action"]
        for i in range(cfg.num_human_slots):
            names += [f"human_{i}_x", f"human_{i}_y", f"human_{i}_vx", f"human_{i}_vy"]
        return names + extra
    n = SOCIALGYM1_NUM_SLOTS
    names = [f"human_{i}_{c}" for i in range(n) for c in ("x", "y", "theta")]
    names += [f"human_{i}_{c}" for i in range(n) for c in ("vx", "vy", "omega")]
    return [*names, "target_x", "target_y", "target_theta", "prev_action", *extra]
