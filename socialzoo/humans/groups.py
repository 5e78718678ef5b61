"""Walking groups: the forces that keep friends together (Moussaid, Perozo, Garnier, Helbing and Theraulaz,
PLoS ONE 2010), added to the social force of the people who walk in a group."""

from __future__ import annotations

import math

import numpy as np

from socialzoo.core.config import GroupConfig
from socialzoo.core.jit import kernel

_TINY = 1e-9


@kernel
def _group_forces(pos, vel, target, group, member, params, out):  # type: ignore[no-untyped-def]
    """Add every grouped person's group force to out (B, H, 2); see add_group_accelerations."""
    coherence, repulsion, threshold, gaze, vision = params
    batch, num = group.shape
    for b in range(batch):
        for i in range(num):
            g = group[b, i]
            if g < 0 or not member[b, i]:
                continue
            px, py = pos[b, i, 0], pos[b, i, 1]
            n = 0
            sx, sy = 0.0, 0.0
            rx, ry = 0.0, 0.0
            for j in range(num):
                if group[b, j] != g or not member[b, j]:
                    continue
                qx, qy = pos[b, j, 0], pos[b, j, 1]
                n += 1
                sx += qx
                sy += qy
                if j != i:
                    dx, dy = px - qx, py - qy
                    if math.sqrt(dx * dx + dy * dy) < threshold:
                        rx += dx
                        ry += dy
            if n < 2:
                continue
            cx, cy = sx / n - px, sy / n - py
            dist = math.sqrt(cx * cx + cy * cy)
            soft = 0.5 * (math.tanh(dist - 0.5 * (n - 1)) + 1.0)
            ax = coherence * soft * cx + repulsion * rx
            ay = coherence * soft * cy + repulsion * ry
            # Gaze: the others' centre seen from the walking direction.
            ox, oy = (sx - px) / (n - 1) - px, (sy - py) / (n - 1) - py
            olen = math.sqrt(ox * ox + oy * oy)
            ex, ey = target[b, i, 0] - px, target[b, i, 1] - py
            elen = math.sqrt(ex * ex + ey * ey)
            if olen > _TINY and elen > _TINY:
                ex, ey = ex / elen, ey / elen
                cosine = min(max((ox * ex + oy * ey) / olen, -1.0), 1.0)
                alpha = math.acos(cosine) - vision
                if alpha > 0.0:
                    ax -= gaze * alpha * vel[b, i, 0]
                    ay -= gaze * alpha * vel[b, i, 1]
            out[b, i, 0] += ax
            out[b, i, 1] += ay


def add_group_accelerations(
    pos: np.ndarray,
    vel: np.ndarray,
    target: np.ndarray,
    group: np.ndarray,
    member: np.ndarray,
    cfg: GroupConfig,
    accel: np.ndarray,
) -> None:
    """Add the group forces of every person who walks in a group to `accel`, in place.

    Moussaid, Perozo, Garnier, Helbing and Theraulaz, "The walking behaviour of pedestrian social groups
    and its impact on crowd dynamics", PLoS ONE 2010. For a person i of a group of n members
    (WorldState.human_group), with c the centre of mass of the group and c' that of the others:

    - coherence: coherence * s * (c - x_i), s = (1 + tanh(|c - x_i| - (n - 1) / 2)) / 2: Moussaid's
      attraction towards the centre beyond (n - 1) / 2 m, with PedSim's smooth step (PySocialForce's
      GroupCoherenceForceAlt);
    - repulsion: repulsion * (x_i - x_j) for each member j closer than repulsion_threshold
      (PySocialForce's GroupRepulsiveForce);
    - gaze: -gaze * alpha * v_i, v_i the person's velocity and alpha how far (rad) c' lies outside
      the field of view of half-width vision_deg around the walking direction (towards the
      waypoint): the person slows down to keep the others in sight (Moussaid's f_vis, with the
      velocity as in the paper; PySocialForce's GroupGazeForce uses the unit walking direction,
      which also pushes a person standing still backwards and stalls groups in single file).

    One compiled kernel over rows and people; a person's members are found by a loop over the row's
    slots (groups are small), in slot order, so a row steps the same alone or in any batch.

    Args:
        pos: (B, H, 2) positions, world frame, m.
        vel: (B, H, 2) velocities, world frame, m/s.
        target: (B, H, 2) each person's waypoint, world frame, m (its walking direction).
        group: (B, H) group of each person (the slot of its first member), -1 for none.
        member: (B, H) people the group forces act on and count as members (present people of
            the social-force models).
        cfg: the weights.
        accel: (B, H, 2) accelerations, m/s^2; people outside groups are left as they are.
    """
    params = (cfg.coherence, cfg.repulsion, cfg.repulsion_threshold, cfg.gaze, math.radians(cfg.vision_deg))
    _group_forces(pos, vel, target, group, member, params, accel)
