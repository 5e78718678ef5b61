"""The CrowdNav task's actions: one robot's action space (velocities in [-1, 1]^2 or CrowdNav's 81), and the
compiled loops that turn velocity actions into robot commands and carry them between frames (CrowdNavTask)."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from socialzoo.core.jit import kernel
from socialzoo.env.crowd_config import CrowdNavConfig, discrete_actions


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
