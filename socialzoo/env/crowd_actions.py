"""The CrowdNav task's actions: one robot's action space (velocities in [-1, 1]^2 or CrowdNav's 81), and the
compiled loops that turn velocity actions into robot commands and carry them between frames (CrowdNavTask)."""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from socialzoo.core.config import RobotConfig
from socialzoo.core.jit import kernel
from socialzoo.env.crowd_config import CrowdNavConfig

# CrowdNav's discrete action set: speeds exponentially spaced, headings evenly spread.
SPEED_SAMPLES = 5
ROTATION_SAMPLES = 16


def discrete_actions(robot: RobotConfig) -> list[tuple[float, float]]:
    """CrowdNav's 81 actions (build_action_space): stop, then 16 headings x 5 speeds exponentially
    spaced up to the preferred speed; headings over the full circle for a holonomic robot (as
    (vx, vy)), within +-pi/4 for a unicycle (as (speed, turn))."""
    v_pref = robot.max_speed
    speeds = [(math.exp((i + 1) / SPEED_SAMPLES) - 1) / (math.e - 1) * v_pref for i in range(SPEED_SAMPLES)]
    if robot.kinematics == "holonomic":
        rotations = [2 * math.pi * k / ROTATION_SAMPLES for k in range(ROTATION_SAMPLES)]
        return [(0.0, 0.0)] + [(s * math.cos(r), s * math.sin(r)) for r in rotations for s in speeds]
    rotations = [-math.pi / 4 + (math.pi / 2) * k / (ROTATION_SAMPLES - 1) for k in range(ROTATION_SAMPLES)]
    return [(0.0, 0.0)] + [(s, r) for r in rotations for s in speeds]


def action_space(config: CrowdNavConfig) -> spaces.Space:
    """One robot's action space: Box([-1, 1]^2) or Discrete(81)."""
    if config.action == "discrete":
        return spaces.Discrete(len(discrete_actions(config.robot)))
    return spaces.Box(-1.0, 1.0, (2,), np.float32)


@kernel
def velocity_commands(action, unicycle, v_pref, max_rotation, time_step, out):  # type: ignore[no-untyped-def]
    """The commands of velocity actions (N, 2) in [-1, 1] into out (N, 2), in the action frame
    (CrowdNavTask.commands): a holonomic robot's velocity at v_pref, a unicycle's (speed, omega).
    Returns the first robot whose action is not finite in [-1, 1] (out unwritten), -1 for none."""
    n = action.shape[0]
    for i in range(n):
        if not (abs(action[i, 0]) <= 1.0 and abs(action[i, 1]) <= 1.0):  # NaN fails too
            return i
    for i in range(n):
        if unicycle:
            out[i, 0] = (action[i, 0] + 1.0) * 0.5 * v_pref
            out[i, 1] = action[i, 1] * max_rotation / time_step
        else:
            out[i, 0] = action[i, 0] * v_pref
            out[i, 1] = action[i, 1] * v_pref
    return -1


@kernel
def turn_rows(velocity, cos, sin, sign, out):  # type: ignore[no-untyped-def]
    """Each velocity (N, 2) turned by the angle of cosine cos (N,) and sine sign * sin (N,), into out."""
    for i in range(velocity.shape[0]):
        c, s = cos[i], sign * sin[i]
        out[i, 0] = c * velocity[i, 0] - s * velocity[i, 1]
        out[i, 1] = s * velocity[i, 0] + c * velocity[i, 1]
