"""Fixtures of the render tests: small hand-made episodes for the viewer (no simulation)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from socialzoo.render.replay_data import EpisodeTrace, ReplayScene


def _make_trace(steps: int = 9, humans: int = 2, rays: int = 8, **changes: Any) -> EpisodeTrace:
    """A robot driving along x at 1 m/s from (1, 1) with `humans` humans walking along y."""
    t = np.arange(steps + 1) * 0.025
    pose = np.stack((1.0 + t, np.ones_like(t), np.zeros_like(t)), axis=1)
    human_pos = np.stack(
        [np.stack((np.full_like(t, 3.0 + k), 0.5 + 0.8 * t), axis=1) for k in range(humans)], axis=1
    ).reshape(steps + 1, humans, 2)
    fields: dict[str, Any] = {
        "label": "ref",
        "dt": 0.025,
        "robot_pose": pose,
        "robot_vel": np.tile([1.0, 0.0], (steps + 1, 1)),
        "goal": np.array([4.0, 1.0, 0.0]),
        "human_pos": human_pos,
        "human_vel": np.tile([0.0, 0.8], (steps + 1, humans, 1)).reshape(steps + 1, humans, 2),
        "carrot": pose[:, :2] + [0.5, 0.0],
        "plans": (np.array([[1.0, 1.0], [4.0, 1.0]]), np.array([[1.1, 1.0], [2.0, 1.5], [4.0, 1.0]])),
        "plan_index": (np.arange(steps + 1) > steps // 2).astype(int),
        "laser_angles": np.linspace(-2.0, 2.0, rays),
        "laser_steps": np.arange(steps + 1),
        "laser_ranges": np.full((steps + 1, rays), 2.5),
        "laser_max_range": 10.0,
        "action": np.arange(steps) % 4,
        "target_human": np.where(np.arange(steps) % 4 >= 2, 0, -1),
        "reward": np.linspace(-0.1, 0.2, steps),
        "force": np.linspace(0.0, 1.0, steps),
        "blame": np.linspace(1.0, 0.0, steps),
        "human_collisions": np.zeros(steps, int),
        "wall_collision": np.zeros(steps, bool),
        "metrics": {"success": True, "steps": steps, "time_to_goal": float("nan"), "total_reward": 0.5},
        "outcome": "success",
    }
    fields.update(changes)
    return EpisodeTrace(**fields)


def _make_scene(**changes: Any) -> ReplayScene:
    """A 6 m x 3 m room."""
    fields: dict[str, Any] = {
        "title": "ref on room",
        "map_name": "room",
        "walls": np.array([[0, 0, 6, 0], [6, 0, 6, 3], [6, 3, 0, 3], [0, 3, 0, 0]], float),
        "bounds": (-0.5, -0.5, 6.5, 3.5),
        "robot_length": 0.5,
        "robot_width": 0.43,
        "human_radius": 0.2,
        "goal_radius": 0.5,
    }
    fields.update(changes)
    return ReplayScene(**fields)


@pytest.fixture
def make_trace():
    """Factory of EpisodeTraces: make_trace(steps=9, humans=2, rays=8, **field changes)."""
    return _make_trace


@pytest.fixture
def make_scene():
    """Factory of ReplayScenes: make_scene(**field changes)."""
    return _make_scene
