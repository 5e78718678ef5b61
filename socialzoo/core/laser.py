"""A 2D laser scan from each robot against walls and human discs, vectorised over the batch."""

from __future__ import annotations

import numpy as np

from socialzoo.core.config import LaserConfig
from socialzoo.core.geometry import ray_circle_hit
from socialzoo.core.noise import normal
from socialzoo.core.state import WorldState
from socialzoo.core.walls import WallIndex


def ray_angles(cfg: LaserConfig) -> np.ndarray:
    """(M,) ray angles relative to the heading, rad, evenly spread over the field of view."""
    half = np.deg2rad(cfg.fov_deg) / 2.0
    if cfg.fov_deg >= 360.0:
        return np.linspace(-np.pi, np.pi, cfg.num_rays, endpoint=False)
    return np.linspace(-half, half, cfg.num_rays)


def laser_scan(state: WorldState, walls: WallIndex, cfg: LaserConfig, human_radius: float) -> np.ndarray:
    """Ranges seen by every robot.

    Args:
        state: the world.
        walls: the map's wall index.
        cfg: rays, range and noise.
        human_radius: radius of the human discs, m.

    Returns:
        (B, R, M) ranges in metres, in [0, max_range]; noise (if any) is a pure function of the
        row's noise key and step count, so a row scans the same in any batch.
    """
    b, r = state.robot_pose.shape[:2]
    pose = state.robot_pose.reshape(b * r, 3)
    angles = pose[:, 2:3] + ray_angles(cfg)[None, :]  # (B*R, M)
    ranges = walls.cast_rays(pose[:, :2], angles, cfg.max_range).reshape(b, r, -1)
    direction = np.stack((np.cos(angles), np.sin(angles)), axis=-1).reshape(b, r, -1, 1, 2)
    hits = ray_circle_hit(
        state.robot_pose[:, :, None, None, :2],
        direction,
        state.human_pos[:, None, None, :, :],
        human_radius,
    )  # (B, R, M, H)
    hits = np.where(state.human_mask[:, None, None, :], hits, np.inf)
    if hits.shape[-1]:
        ranges = np.minimum(ranges, hits.min(axis=-1))
    if cfg.noise_std > 0:
        noise = normal(state.noise_key, state.step_count, (r, cfg.num_rays))
        ranges = ranges + cfg.noise_std * noise
    return np.clip(ranges, 0.0, cfg.max_range)
