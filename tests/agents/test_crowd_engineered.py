"""The CrowdNav task's engineered robots follow CrowdNav's own policies (crowd_sim/envs/policy/orca.py)."""

from __future__ import annotations

import numpy as np

from socialzoo.agents.crowd_engineered import CrowdOrcaRobot
from socialzoo.env.tasks.crowdnav import CrowdNavTask


def _head_on(radius: float) -> CrowdNavTask:
    """A robot of `radius` at (0, -4) for (0, 4) with one person of `radius` 1.2 m ahead walking at it."""
    task = CrowdNavTask(robot={"radius": radius}, cases={"num_humans": 1, "human_radius": radius})
    task.reset(np.arange(1), {"split": "val", "case": 0})
    s = task.world_state
    s.human_pos[0, 0] = (0.05, -2.8)
    s.human_vel[0, 0] = (0.0, -1.0)
    return task


def test_orca_safety_space_pads_every_agent_as_crowdnavs_does():
    # CrowdNav's ORCA pads the robot's radius and each person's by 0.01 m + safety_space, so a
    # safety space s is the same step as every radius grown by s (with no safety space).
    padded = CrowdOrcaRobot(safety_space=0.1).act(None, _head_on(0.3))
    grown = CrowdOrcaRobot().act(None, _head_on(0.4))
    np.testing.assert_allclose(padded, grown, atol=1e-9)
    assert not np.allclose(padded, CrowdOrcaRobot().act(None, _head_on(0.3)), atol=1e-3)
