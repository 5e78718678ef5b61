"""Observations and rewards of learned humans (the optional human agents of the ParallelEnv).

A learned human sees, in its own frame (x axis towards its current route waypoint): that waypoint,
its velocity and preferred speed, the nearest wall point, and its nearest neighbours (humans and
robots) with their relative velocity. Its reward is progress towards its waypoint minus a
penalty for every step in contact with anyone.
"""

from __future__ import annotations

import numpy as np

from socialzoo.core.geometry import rotate
from socialzoo.core.state import WorldState
from socialzoo.core.walls import WallIndex

# Per-neighbour entries: x, y, vx, vy (relative, human frame), is_robot.
NEIGHBOUR_SIZE = 5
# Own entries: waypoint x, y; velocity x, y; preferred speed; nearest wall x, y; wall in reach.
OWN_SIZE = 8
# Centre distance counted as contact between two agents, m (SPEC: 0.4 for robot-human).
CONTACT_DISTANCE = 0.4


def human_observation_size(num_neighbours: int) -> int:
    """Length of a learned human's observation."""
    return OWN_SIZE + NEIGHBOUR_SIZE * num_neighbours


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


def human_rewards(
    before: WorldState, after: WorldState, humans: np.ndarray, collision_penalty: float
) -> np.ndarray:
    """(B, L) reward of the learned humans for one step.

    Progress is measured towards the waypoint each human had before the step, so switching to
    the next waypoint does not make the reward jump. Contact: centre distance below 0.4 m to any
    other present human or any robot.
    """
    target = before.human_target[:, humans]
    gained = np.linalg.norm(target - before.human_pos[:, humans], axis=-1) - np.linalg.norm(
        target - after.human_pos[:, humans], axis=-1
    )
    others = np.concatenate((after.human_pos, after.robot_pose[..., :2]), axis=1)
    present = np.concatenate((after.human_mask, np.ones(after.robot_pose.shape[:2], bool)), axis=1)
    dist2 = ((others[:, None, :, :] - after.human_pos[:, humans, None, :]) ** 2).sum(-1)
    self_slot = np.arange(others.shape[1])[None, None, :] == humans[None, :, None]
    contact = ((dist2 < CONTACT_DISTANCE**2) & present[:, None, :] & ~self_slot).any(-1)
    reward = gained - collision_penalty * contact
    return np.where(after.human_mask[:, humans], reward, 0.0)
