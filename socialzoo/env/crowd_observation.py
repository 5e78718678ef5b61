"""The observation of the CrowdNav task: the robot-centred joint state of that line of work."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

import numpy as np
from gymnasium import spaces

from socialzoo.core.jit import kernel

if TYPE_CHECKING:
    from socialzoo.env.crowd_config import CrowdNavConfig

ROBOT_FEATURES: tuple[str, ...] = ("goal_distance", "preferred_speed", "heading", "radius", "vx", "vy")
HUMAN_FEATURES: tuple[str, ...] = ("px", "py", "vx", "vy", "radius", "distance", "radius_sum")
# With signals: the robot part gains the nearest door, each person slot its gesture.
SIGNAL_ROBOT_FEATURES: tuple[str, ...] = (*ROBOT_FEATURES, "door_x", "door_y", "door_closed")
SIGNAL_HUMAN_FEATURES: tuple[str, ...] = (*HUMAN_FEATURES, "signal")
ObservationKind = Literal["flat", "dict"]
OBSERVATION_KINDS: tuple[str, ...] = get_args(ObservationKind)


@dataclass(frozen=True)
class JointState:
    """The joint state of B rows, robot-centred (x towards the goal), metres and m/s.

    Two layouts of the same numbers: "dict" ({"robot": (6,), "humans": (H, 7), "mask": (H,)}) and
    "flat" (one (6 + 8 H,) vector: robot, then the people row by row, then the mask as 0/1).

    Attributes:
        robot: (B, 6) float32, ROBOT_FEATURES (with signals (B, 9), SIGNAL_ROBOT_FEATURES).
        humans: (B, H, 7) float32, HUMAN_FEATURES per person slot (zeros for an empty slot; with
            signals (B, H, 8), SIGNAL_HUMAN_FEATURES).
        mask: (B, H) bool, the slot holds a person.
        buffer: the flat layout that robot and humans are views of (`flat`).
    """

    robot: np.ndarray
    humans: np.ndarray
    mask: np.ndarray
    buffer: np.ndarray

    def flat(self) -> np.ndarray:
        """(B, robot + (features + 1) H) float32: robot, people row by row, then the mask as 0/1."""
        return self.buffer

    def as_dict(self) -> dict[str, np.ndarray]:
        """{"robot", "humans", "mask"}; the mask as int8 (0/1)."""
        return {"robot": self.robot, "humans": self.humans, "mask": self.mask.astype(np.int8)}


def robot_features(signals: bool = False) -> tuple[str, ...]:
    """The names of the robot part's features (with signals: and the nearest door's)."""
    return SIGNAL_ROBOT_FEATURES if signals else ROBOT_FEATURES


def human_features(signals: bool = False) -> tuple[str, ...]:
    """The names of a person slot's features (with signals: and its gesture)."""
    return SIGNAL_HUMAN_FEATURES if signals else HUMAN_FEATURES


def flat_size(max_humans: int, signals: bool = False) -> int:
    """The length of the flat layout with `max_humans` slots (with signals, if `signals`)."""
    return len(robot_features(signals)) + (len(human_features(signals)) + 1) * max_humans


def observation_space(config: CrowdNavConfig) -> spaces.Space:
    """One robot's observation space (flat Box or Dict, socialzoo.env.crowd_observation)."""
    h, signals = config.observed_slots, config.signals
    if config.observation == "flat":
        return spaces.Box(-np.inf, np.inf, (flat_size(h, signals),), np.float32)
    return spaces.Dict(
        {
            "robot": spaces.Box(-np.inf, np.inf, (len(robot_features(signals)),), np.float32),
            "humans": spaces.Box(-np.inf, np.inf, (h, len(human_features(signals))), np.float32),
            "mask": spaces.MultiBinary(h),
        }
    )


def with_signals(state: JointState, signal: np.ndarray, door: np.ndarray) -> JointState:
    """The joint state with signals: each slot's gesture and the nearest door.

    With signals (CrowdNavConfig.signals) each person slot also carries the gesture its person
    shows (SIGNAL_HUMAN_FEATURES: "signal", 0 none, 1 wait, 2 proceed; 0 for other robots, wall
    rays and empty slots) and the robot part the nearest door (SIGNAL_ROBOT_FEATURES: its point
    nearest the robot, x and y in the same frame, and closed 0/1; zeros without doors): "dict"
    {"robot": (9,), "humans": (H, 8), "mask": (H,)}, "flat" (9 + 9 H,) in the same order.

    Args:
        state: the joint state of N robots with H slots.
        signal: (N, H) the gesture each slot's person shows (0 none, 1 wait, 2 proceed).
        door: (N, 3) the nearest door's point nearest the robot (x, y, in the joint state's frame,
            m) and closed (0/1); zeros without a door.
    """
    n, h, f = state.humans.shape
    robot_dim = len(SIGNAL_ROBOT_FEATURES)
    flat = np.empty((n, flat_size(h, signals=True)), dtype=np.float32)
    flat[:, : state.robot.shape[1]] = state.robot
    flat[:, state.robot.shape[1] : robot_dim] = door
    humans = flat[:, robot_dim : robot_dim + (f + 1) * h].reshape(n, h, f + 1)
    humans[..., :f] = state.humans
    humans[..., f] = np.where(state.mask, signal, 0)
    flat[:, robot_dim + (f + 1) * h :] = state.mask
    return JointState(robot=flat[:, :robot_dim], humans=humans, mask=state.mask, buffer=flat)


def joint_state(
    robot_pos: np.ndarray,
    robot_goal: np.ndarray,
    robot_vel: np.ndarray,
    robot_heading: np.ndarray,
    robot_radius: float,
    preferred_speed: float,
    unicycle: bool,
    human_pos: np.ndarray,
    human_vel: np.ndarray,
    human_radius: np.ndarray | float,
    human_mask: np.ndarray,
) -> JointState:
    """The joint state of every row.

    CrowdNav (Chen et al. 2019, `rotate` in crowd_nav/policy/cadrl.py) turns the world into a frame
    centred on the robot with x pointing at the goal, and describes the robot by (goal distance,
    preferred speed, heading, radius, vx, vy) and each person by (px, py, vx, vy, radius, distance,
    radius sum). We keep those features and their order, with two additions that a fixed-size
    batch needs: people slots beyond a case's head count are zeros, and a mask says which slots
    hold a person. The heading is 0 for a holonomic robot, as in CrowdNav (its heading does not
    matter), and a unicycle's heading relative to the goal direction, wrapped to [-pi, pi)
    (CrowdNav's theta - rot is not wrapped: the same pose may read 2 pi more or less there).

    Args:
        robot_pos: (B, 2) world frame, m.
        robot_goal: (B, 2) world frame, m.
        robot_vel: (B, 2) world-frame velocity, m/s.
        robot_heading: (B,) rad.
        robot_radius: m.
        preferred_speed: the robot's v_pref, m/s.
        unicycle: report the heading relative to the goal direction (else 0).
        human_pos: (B, H, 2) world frame, m.
        human_vel: (B, H, 2) world frame, m/s.
        human_radius: (B, H) or one radius for all, m.
        human_mask: (B, H) bool.
    """
    n, h = human_mask.shape
    radius = np.asarray(human_radius, dtype=np.float64)
    if radius.shape != (n, h) or not radius.flags.c_contiguous:
        radius = np.ascontiguousarray(np.broadcast_to(radius, (n, h)))
    flat = np.empty((n, flat_size(h)), dtype=np.float32)
    _fill_joint_state(
        np.ascontiguousarray(robot_pos, dtype=np.float64),
        np.ascontiguousarray(robot_goal, dtype=np.float64),
        np.ascontiguousarray(robot_vel, dtype=np.float64),
        np.ascontiguousarray(robot_heading, dtype=np.float64),
        float(robot_radius),
        float(preferred_speed),
        bool(unicycle),
        np.ascontiguousarray(human_pos, dtype=np.float64),
        np.ascontiguousarray(human_vel, dtype=np.float64),
        radius,
        np.ascontiguousarray(human_mask, dtype=np.bool_),
        flat,
    )
    robot_dim, human_dim = len(ROBOT_FEATURES), len(HUMAN_FEATURES)
    humans = flat[:, robot_dim : robot_dim + human_dim * h].reshape(n, h, human_dim)
    return JointState(robot=flat[:, :robot_dim], humans=humans, mask=human_mask.copy(), buffer=flat)


def nearest_people(
    robot_pos: np.ndarray, human_pos: np.ndarray, human_mask: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray]:
    """The slots a robot observes when it sees `count` people (CrowdNavConfig.observed_people).

    Args:
        robot_pos: (N, 2) m.
        human_pos: (N, H, 2) m.
        human_mask: (N, H) bool.
        count: K, observed person slots.

    Returns:
        (N, K) int slot indices, the present people nearest each robot first (ties to the lower
        slot), and (N, K) bool, whether the observed slot holds a person (slot 0 pads a row with
        fewer than K present).
    """
    n, h = human_mask.shape
    gap = human_pos - robot_pos[:, None, :]
    distance2 = np.where(human_mask, (gap * gap).sum(-1), np.inf)
    order = np.argsort(distance2, axis=1, kind="stable")[:, :count]
    present = np.take_along_axis(human_mask, order, 1)
    if h < count:
        order = np.concatenate((order, np.zeros((n, count - h), dtype=order.dtype)), 1)
        present = np.concatenate((present, np.zeros((n, count - h), dtype=bool)), 1)
    return np.where(present, order, 0), present


@kernel
def _fill_joint_state(  # type: ignore[no-untyped-def]
    robot_pos,
    robot_goal,
    robot_vel,
    heading,
    robot_radius,
    v_pref,
    unicycle,
    human_pos,
    human_vel,
    radius,
    mask,
    out,
):
    """Write each row's flat joint state into `out` (N, 6 + 8 H): robot, people, mask."""
    n, h = mask.shape
    for i in range(n):
        gx = robot_goal[i, 0] - robot_pos[i, 0]
        gy = robot_goal[i, 1] - robot_pos[i, 1]
        rot = math.atan2(gy, gx)
        c, s = math.cos(rot), math.sin(rot)
        out[i, 0] = math.hypot(gx, gy)
        out[i, 1] = v_pref
        if unicycle:
            out[i, 2] = (heading[i] - rot + math.pi) % (2 * math.pi) - math.pi
        else:
            out[i, 2] = 0.0
        out[i, 3] = robot_radius
        out[i, 4] = robot_vel[i, 0] * c + robot_vel[i, 1] * s
        out[i, 5] = robot_vel[i, 1] * c - robot_vel[i, 0] * s
        for j in range(h):
            k = 6 + 7 * j
            if not mask[i, j]:
                for f in range(7):
                    out[i, k + f] = 0.0
                out[i, 6 + 7 * h + j] = 0.0
                continue
            rx = human_pos[i, j, 0] - robot_pos[i, 0]
            ry = human_pos[i, j, 1] - robot_pos[i, 1]
            out[i, k] = rx * c + ry * s
            out[i, k + 1] = ry * c - rx * s
            out[i, k + 2] = human_vel[i, j, 0] * c + human_vel[i, j, 1] * s
            out[i, k + 3] = human_vel[i, j, 1] * c - human_vel[i, j, 0] * s
            out[i, k + 4] = radius[i, j]
            out[i, k + 5] = math.hypot(rx, ry)
            out[i, k + 6] = radius[i, j] + robot_radius
            out[i, 6 + 7 * h + j] = 1.0
