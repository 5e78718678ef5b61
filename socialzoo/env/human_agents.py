"""Observations, actions and rewards of learned humans (the optional human agents of the envs).

A learned human sees, in its own frame (x axis towards its current route waypoint): that waypoint,
its velocity and preferred speed, the nearest wall point, and its nearest neighbours (humans and
robots) with their relative velocity. Its action is a desired velocity in [-1, 1]^2 times its
preferred speed (and EnvConfig.human_action_scale), in the world frame or in its own frame
(EnvConfig.human_action_frame). Its
reward (HumanRewardConfig) adds up, per step: progress towards its waypoint, a bonus for each
waypoint reached, a penalty for walking off its preferred speed, and penalties for contact with
other humans, robots and walls.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from socialzoo.core.geometry import rotate
from socialzoo.core.state import WorldState
from socialzoo.core.validation import check_fields
from socialzoo.core.walls import WallIndex

# Per-neighbour entries: x, y, vx, vy (relative, human frame), is_robot.
NEIGHBOUR_SIZE = 5
# Own entries: waypoint x, y; velocity x, y; preferred speed; nearest wall x, y; wall in reach.
OWN_SIZE = 8
# Centre distance counted as contact between two agents, m (SPEC: 0.4 for robot-human).
CONTACT_DISTANCE = 0.4


@dataclass(frozen=True, kw_only=True)
class HumanRewardConfig:
    """The learned humans' reward per step: a weighted sum of the terms of `HumanStep`.

    reward = progress * metres gained towards the waypoint
             + waypoint_bonus * (a waypoint was reached this step)
             - speed * |speed - preferred speed| / preferred speed
             - human_contact * (another human within contact_distance)
             - robot_contact * (a robot within contact_distance)
             - wall_contact * (a wall within wall_distance, or a wall stopped the move)
             - wall_clearance * (how far inside wall_margin of a wall: 0 at wall_margin,
                                 1 at wall_distance and closer)

    The defaults are the reward of env version v1 (progress minus 1 per step in contact with a
    human or robot); the trainers of socialzoo.train set their own weights.

    Attributes:
        progress: weight of the distance gained towards the current waypoint, per metre.
        waypoint_bonus: paid on the step a waypoint is reached.
        speed: weight of the relative deviation from the preferred walking speed, per step.
        human_contact: penalty per step within contact_distance of another present human.
        robot_contact: penalty per step within contact_distance of a robot.
        wall_contact: penalty per step with the centre within wall_distance of a wall.
        wall_clearance: penalty per step for walking close to a wall, growing linearly from 0 at
            wall_margin to its full weight at wall_distance: a warning before the contact, which
            the contact penalty alone gives only once it is too late.
        contact_distance: centre distance counted as contact with a human or robot, m.
        wall_distance: centre-to-wall distance counted as contact, m (the human radius).
        wall_margin: centre-to-wall distance where the clearance penalty starts, m (above
            wall_distance).
    """

    progress: float = 1.0
    waypoint_bonus: float = 0.0
    speed: float = 0.0
    human_contact: float = 1.0
    robot_contact: float = 1.0
    wall_contact: float = 0.0
    wall_clearance: float = 0.0
    contact_distance: float = CONTACT_DISTANCE
    wall_distance: float = 0.2
    wall_margin: float = 0.4

    def __post_init__(self) -> None:
        check_fields(
            self,
            nonnegative=(
                "progress",
                "waypoint_bonus",
                "speed",
                "human_contact",
                "robot_contact",
                "wall_contact",
                "wall_clearance",
            ),
        )
        if not self.wall_margin > self.wall_distance:
            raise ValueError(
                f"HumanRewardConfig.wall_margin ({self.wall_margin}) must exceed wall_distance "
                f"({self.wall_distance})"
            )


@dataclass(frozen=True)
class HumanStep:
    """One step of the learned humans; every array is (B, L), zero or False for absent humans.

    Attributes:
        reward: the weighted reward (HumanRewardConfig).
        progress: distance gained towards the waypoint the human had before the step, m.
        waypoint_reached: the human reached its waypoint this step (it moved on to the next one).
        human_contact: another present human within the contact distance after the step.
        robot_contact: a robot within the contact distance after the step.
        wall_contact: a wall within the wall distance after the step, or a wall stopped the move.
        wall_clearance: how far inside the wall margin after the step, 0 (outside) to 1 (at the
            wall distance or closer).
        speed_error: |speed - preferred speed| / preferred speed after the step.
    """

    reward: np.ndarray
    progress: np.ndarray
    waypoint_reached: np.ndarray
    human_contact: np.ndarray
    robot_contact: np.ndarray
    wall_contact: np.ndarray
    wall_clearance: np.ndarray
    speed_error: np.ndarray

    @property
    def contact(self) -> np.ndarray:
        """(B, L) in contact with a human or a robot (the ParallelEnv's info["contact"])."""
        return self.human_contact | self.robot_contact


def action_velocities(
    state: WorldState, humans: np.ndarray, action: np.ndarray, frame: str, scale: float = 1.0
) -> np.ndarray:
    """(B, L, 2) world-frame desired velocities, m/s, of learned humans' actions.

    Args:
        state: the world before the step.
        humans: (L,) learned human slots.
        action: (B, L, 2) in [-1, 1], times scale times the preferred speed.
        frame: "world" (the action is a world-frame vector) or "human" (in the human's own frame,
            x towards its waypoint, the frame of its observation).
        scale: EnvConfig.human_action_scale.
    """
    scaled = action * (scale * state.human_pref_speed[:, humans, None])
    if frame == "human":
        return rotate(scaled, human_frames(state, humans))
    return scaled


def human_observation_size(num_neighbours: int) -> int:
    """Length of a learned human's observation."""
    return OWN_SIZE + NEIGHBOUR_SIZE * num_neighbours


def human_mirror_signs(num_neighbours: int) -> np.ndarray:
    """(D,) +1 / -1 per observation entry: the observation of the mirror image of a situation.

    Mirroring about the human's x axis (towards its waypoint) negates every y component: of the
    waypoint, the velocity, the nearest wall point and each neighbour's position and velocity.
    A policy with no handedness acts on the mirrored observation with the mirrored action
    (action y negated).
    """
    signs = np.ones(human_observation_size(num_neighbours), dtype=np.float32)
    signs[[1, 3, 6]] = -1.0  # waypoint y, velocity y, nearest wall y
    for k in range(num_neighbours):
        start = OWN_SIZE + NEIGHBOUR_SIZE * k
        signs[[start + 1, start + 3]] = -1.0  # relative position y, relative velocity y
    return signs


def human_frames(state: WorldState, humans: np.ndarray) -> np.ndarray:
    """(B, L) heading of each learned human's frame: towards its current waypoint, rad."""
    to_target = state.human_target[:, humans] - state.human_pos[:, humans]
    return np.arctan2(to_target[..., 1], to_target[..., 0])


def human_observations(
    state: WorldState, walls: WallIndex, humans: np.ndarray, num_neighbours: int
) -> np.ndarray:
    """Observations of the learned humans.

    Args:
        state: the world.
        walls: the map's wall index.
        humans: (L,) indices of the learned human slots.
        num_neighbours: K nearest agents listed (absent ones are zero rows).

    Returns:
        (B, L, 8 + 5K) float32, human frame (x towards its waypoint), SI units. Slots of absent
        humans are all zero.
    """
    b = state.batch_size
    pos = state.human_pos[:, humans]
    vel = state.human_vel[:, humans]
    heading = human_frames(state, humans)
    obs = np.zeros((b, len(humans), human_observation_size(num_neighbours)), dtype=np.float32)
    obs[..., 0:2] = rotate(state.human_target[:, humans] - pos, -heading)
    obs[..., 2:4] = rotate(vel, -heading)
    obs[..., 4] = state.human_pref_speed[:, humans]
    closest, dist = walls.nearest(pos)
    near = np.isfinite(dist)
    obs[..., 5:7] = np.where(near[..., None], rotate(closest - pos, -heading), 0.0)
    obs[..., 7] = near
    if num_neighbours:
        others = np.concatenate((state.human_pos, state.robot_pose[..., :2]), axis=1)
        robot_vel = state.robot_vel[..., :1] * np.stack(
            (np.cos(state.robot_pose[..., 2]), np.sin(state.robot_pose[..., 2])), axis=-1
        )
        others_vel = np.concatenate((state.human_vel, robot_vel), axis=1)
        present = np.concatenate((state.human_mask, np.ones(state.robot_pose.shape[:2], bool)), axis=1)
        is_robot = np.arange(others.shape[1]) >= state.max_humans
        rel = others[:, None, :, :] - pos[:, :, None, :]  # (B, L, N, 2)
        dist2 = (rel**2).sum(-1)
        self_slot = np.arange(others.shape[1])[None, None, :] == humans[None, :, None]
        dist2 = np.where(present[:, None, :] & ~self_slot, dist2, np.inf)
        k = min(num_neighbours, others.shape[1])
        order = np.argsort(dist2, axis=-1, kind="stable")[..., :k]
        valid = np.isfinite(np.take_along_axis(dist2, order, axis=-1))
        rel_pos = np.take_along_axis(rel, order[..., None], axis=2)
        rel_vel = np.take_along_axis(others_vel[:, None, :, :] - vel[:, :, None, :], order[..., None], axis=2)
        neighbours = np.concatenate(
            (
                rotate(rel_pos, -heading[..., None]),
                rotate(rel_vel, -heading[..., None]),
                is_robot[order][..., None].astype(np.float64),
            ),
            axis=-1,
        )
        neighbours = np.where(valid[..., None], neighbours, 0.0)
        obs[..., OWN_SIZE : OWN_SIZE + NEIGHBOUR_SIZE * k] = neighbours.reshape(b, len(humans), -1)
    return np.where(state.human_mask[:, humans, None], obs, 0.0).astype(np.float32)


def human_step(
    before: WorldState,
    after: WorldState,
    humans: np.ndarray,
    walls: WallIndex,
    blocked: np.ndarray,
    config: HumanRewardConfig,
) -> HumanStep:
    """Reward and its terms for the learned humans' step before -> after.

    Progress is measured towards the waypoint each human had before the step, so switching to
    the next waypoint does not make the reward jump.

    Args:
        before: the world before the step.
        after: the world after the step.
        humans: (L,) learned human slots.
        walls: the map's wall index.
        blocked: (B, H) humans whose move a wall stopped this step (StepEvents.human_blocked).
        config: the reward weights and contact distances.
    """
    present = after.human_mask[:, humans]
    target = before.human_target[:, humans]
    pos = after.human_pos[:, humans]
    gained = np.linalg.norm(target - before.human_pos[:, humans], axis=-1) - np.linalg.norm(
        target - pos, axis=-1
    )
    reached = after.human_waypoint[:, humans] != before.human_waypoint[:, humans]
    limit = config.contact_distance**2
    others = after.human_pos[:, None, :, :] - pos[:, :, None, :]  # (B, L, H, 2)
    self_slot = np.arange(after.max_humans)[None, None, :] == humans[None, :, None]
    near_human = ((others**2).sum(-1) < limit) & after.human_mask[:, None, :] & ~self_slot
    robots = after.robot_pose[:, None, :, :2] - pos[:, :, None, :]  # (B, L, R, 2)
    near_robot = (robots**2).sum(-1) < limit
    _, wall_dist = walls.nearest(pos)
    wall = (wall_dist < config.wall_distance) | blocked[:, humans]
    # Beyond the wall index's reach the distance is inf: no penalty.
    clearance = np.clip(
        (config.wall_margin - wall_dist) / (config.wall_margin - config.wall_distance), 0.0, 1.0
    )
    clearance = np.where(wall, 1.0, clearance)
    speed = np.linalg.norm(after.human_vel[:, humans], axis=-1)
    pref = after.human_pref_speed[:, humans]
    speed_error = np.abs(speed - pref) / np.maximum(pref, 1e-9)
    human_contact = near_human.any(-1) & present
    robot_contact = near_robot.any(-1) & present
    wall_contact = wall & present
    reward = (
        config.progress * gained
        + config.waypoint_bonus * reached
        - config.speed * speed_error
        - config.human_contact * human_contact
        - config.robot_contact * robot_contact
        - config.wall_contact * wall_contact
        - config.wall_clearance * np.where(present, clearance, 0.0)
    )
    return HumanStep(
        reward=np.where(present, reward, 0.0),
        progress=np.where(present, gained, 0.0),
        waypoint_reached=reached & present,
        human_contact=human_contact,
        robot_contact=robot_contact,
        wall_contact=wall_contact,
        wall_clearance=np.where(present, clearance, 0.0),
        speed_error=np.where(present, speed_error, 0.0),
    )
