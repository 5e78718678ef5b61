"""The observation of the CrowdNav task: the robot-centred joint state of that line of work.

CrowdNav (Chen et al. 2019, `rotate` in crowd_nav/policy/cadrl.py) turns the world into a frame
centred on the robot with x pointing at the goal, and describes the robot by (goal distance,
preferred speed, heading, radius, vx, vy) and each person by (px, py, vx, vy, radius, distance,
radius sum). We keep those features and their order, with two additions that a fixed-size batch
needs: people slots beyond a case's head count are zeros, and a mask says which slots hold a
person. The heading is the robot's heading relative to the goal direction for a unicycle and 0
otherwise, as in CrowdNav (a holonomic robot's heading does not matter).

Two layouts of the same numbers: "dict" ({"robot": (6,), "humans": (H, 7), "mask": (H,)}) and
"flat" (one (6 + 8 H,) vector: robot, then the people row by row, then the mask as 0/1).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

ROBOT_FEATURES: tuple[str, ...] = ("goal_distance", "preferred_speed", "heading", "radius", "vx", "vy")
HUMAN_FEATURES: tuple[str, ...] = ("px", "py", "vx", "vy", "radius", "distance", "radius_sum")
ObservationKind = Literal["flat", "dict"]
OBSERVATION_KINDS: tuple[str, ...] = get_args(ObservationKind)


@dataclass(frozen=True)
class JointState:
    """The joint state of B rows, robot-centred (x towards the goal), metres and m/s.

    Attributes:
        robot: (B, 6) float32, ROBOT_FEATURES.
        humans: (B, H, 7) float32, HUMAN_FEATURES per person slot (zeros for an empty slot).
        mask: (B, H) bool, the slot holds a person.
    """

    robot: np.ndarray
    humans: np.ndarray
    mask: np.ndarray

    def flat(self) -> np.ndarray:
        """(B, 6 + 8 H) float32: robot, people row by row, then the mask as 0/1."""
        b = self.robot.shape[0]
        return np.concatenate(
            (self.robot, self.humans.reshape(b, -1), self.mask.astype(np.float32)), axis=1
        ).astype(np.float32, copy=False)

    def as_dict(self) -> dict[str, np.ndarray]:
        """{"robot", "humans", "mask"}; the mask as int8 (0/1)."""
        return {"robot": self.robot, "humans": self.humans, "mask": self.mask.astype(np.int8)}


def flat_size(max_humans: int) -> int:
    """The length of the flat layout with `max_humans` slots."""
    return len(ROBOT_FEATURES) + (len(HUMAN_FEATURES) + 1) * max_humans


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
    to_goal = robot_goal - robot_pos
    rot = np.arctan2(to_goal[:, 1], to_goal[:, 0])
    cos, sin = np.cos(rot), np.sin(rot)
    b = len(robot_pos)
    robot = np.empty((b, len(ROBOT_FEATURES)), dtype=np.float32)
    robot[:, 0] = np.hypot(to_goal[:, 0], to_goal[:, 1])
    robot[:, 1] = preferred_speed
    robot[:, 2] = _wrap(robot_heading - rot) if unicycle else 0.0
    robot[:, 3] = robot_radius
    robot[:, 4] = robot_vel[:, 0] * cos + robot_vel[:, 1] * sin
    robot[:, 5] = robot_vel[:, 1] * cos - robot_vel[:, 0] * sin
    c, s = cos[:, None], sin[:, None]
    rel = human_pos - robot_pos[:, None, :]
    radius = np.broadcast_to(np.asarray(human_radius, dtype=np.float64), human_mask.shape)
    humans = np.empty(human_mask.shape + (len(HUMAN_FEATURES),), dtype=np.float32)
    humans[..., 0] = rel[..., 0] * c + rel[..., 1] * s
    humans[..., 1] = rel[..., 1] * c - rel[..., 0] * s
    humans[..., 2] = human_vel[..., 0] * c + human_vel[..., 1] * s
    humans[..., 3] = human_vel[..., 1] * c - human_vel[..., 0] * s
    humans[..., 4] = radius
    humans[..., 5] = np.hypot(rel[..., 0], rel[..., 1])
    humans[..., 6] = radius + robot_radius
    humans[~human_mask] = 0.0
    return JointState(robot=robot, humans=humans, mask=human_mask.copy())


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi
