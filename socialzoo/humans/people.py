"""One step of every person of B worlds, whatever model drives each (WorldState.human_model): the social force
(with walking groups), ORCA, or a learned policy's desired velocity relaxed through the social force."""

from __future__ import annotations

import numpy as np

from socialzoo.core.config import WorldConfig
from socialzoo.core.jit import kernel
from socialzoo.core.walls import WallIndex
from socialzoo.humans.groups import add_group_accelerations
from socialzoo.humans.models import ORCA, REPLAY, SOCIAL_FORCE
from socialzoo.humans.motion import integrate_humans
from socialzoo.humans.orca import orca_velocities
from socialzoo.humans.social_force import human_acceleration

_TINY = 1e-9


def orca_people_velocities(
    pos: np.ndarray,
    vel: np.ndarray,
    target: np.ndarray,
    pref_speed: np.ndarray,
    mask: np.ndarray,
    drive: np.ndarray,
    robot_pos: np.ndarray,
    robot_vel: np.ndarray,
    walls: WallIndex,
    cfg: WorldConfig,
) -> np.ndarray:
    """(B, H, 2) ORCA velocities of the people `drive` marks (the others keep `vel`).

    Each walks at its preferred speed straight to its waypoint unless someone or a wall is in the
    way; every present person (radius cfg.orca.radius) and every robot given (its disc,
    OrcaConfig.robot_disc) is avoided, robots only with cfg.orca.robot_visible.
    """
    orca = cfg.orca
    batch, num = mask.shape
    num_robots = robot_pos.shape[1] if orca.robot_visible else 0
    agents = num + num_robots
    a_pos, a_vel, a_pref = (np.empty((batch, agents, 2)) for _ in range(3))
    a_radius, a_speed = np.empty((batch, agents)), np.empty((batch, agents))
    a_present, a_drive = np.empty((batch, agents), dtype=bool), np.empty((batch, agents), dtype=bool)
    _orca_agents(
        pos, vel, target, pref_speed, mask, drive, robot_pos[:, :num_robots], robot_vel[:, :num_robots],
        orca.radius, orca.robot_disc(cfg.robot) if num_robots else 0.0,
        orca.max_speed is None, 0.0 if orca.max_speed is None else orca.max_speed,
        a_pos, a_vel, a_pref, a_radius, a_speed, a_present, a_drive,
    )  # fmt: skip
    out = orca_velocities(
        a_pos, a_vel, a_pref, a_radius, a_speed, a_present, a_drive, a_present, walls, orca, cfg.dt
    )
    return out[:, :num]


@kernel
def _orca_agents(  # type: ignore[no-untyped-def]
    pos, vel, target, pref_speed, mask, drive, robot_pos, robot_vel, radius, robot_radius, own_speed, max_speed,
    a_pos, a_vel, a_pref, a_radius, a_speed, a_present, a_drive,
):  # fmt: skip
    """orca_people_velocities' agents (B, H + R): the people, each preferring its preferred speed
    straight to its waypoint (the numpy expressions it replaced, np.maximum's NaN kept) and limited
    to it (own_speed) or to max_speed, then the robots given (present, seen, not driven, still)."""
    for b in range(mask.shape[0]):
        for h in range(mask.shape[1]):
            tx, ty = target[b, h, 0] - pos[b, h, 0], target[b, h, 1] - pos[b, h, 1]
            dist = np.sqrt(tx * tx + ty * ty)
            scale = pref_speed[b, h] / (dist if dist >= _TINY or dist != dist else _TINY)
            a_pos[b, h, 0], a_pos[b, h, 1] = pos[b, h, 0], pos[b, h, 1]
            a_vel[b, h, 0], a_vel[b, h, 1] = vel[b, h, 0], vel[b, h, 1]
            a_pref[b, h, 0], a_pref[b, h, 1] = tx * scale, ty * scale
            a_radius[b, h] = radius
            a_speed[b, h] = pref_speed[b, h] if own_speed else max_speed
            a_present[b, h], a_drive[b, h] = mask[b, h], drive[b, h]
        for k in range(robot_pos.shape[1]):
            at = mask.shape[1] + k
            a_pos[b, at, 0], a_pos[b, at, 1] = robot_pos[b, k, 0], robot_pos[b, k, 1]
            a_vel[b, at, 0], a_vel[b, at, 1] = robot_vel[b, k, 0], robot_vel[b, k, 1]
            a_pref[b, at, 0] = a_pref[b, at, 1] = 0.0
            a_radius[b, at], a_speed[b, at] = robot_radius, 0.0
            a_present[b, at], a_drive[b, at] = True, False


@kernel
def _census(mask, model, group, orca, replay):
    """(any present ORCA person, any present person a force walks, anyone in a walking group) of
    people (B, H) in one pass: a step with social-force people only skips the others' code, and
    one with ORCA people and people on their recorded tracks (whose step the replay overwrites)
    skips the forces."""
    has_orca = has_other = has_group = False
    for b in range(mask.shape[0]):
        for h in range(mask.shape[1]):
            if mask[b, h]:
                if model[b, h] == orca:
                    has_orca = True
                elif model[b, h] != replay:
                    has_other = True
            if group[b, h] >= 0:
                has_group = True
    return has_orca, has_other, has_group


def step_people(
    pos: np.ndarray,
    vel: np.ndarray,
    target: np.ndarray,
    pref_speed: np.ndarray,
    mask: np.ndarray,
    model: np.ndarray,
    group: np.ndarray,
    robot_pos: np.ndarray,
    robot_vel: np.ndarray,
    walls: WallIndex,
    cfg: WorldConfig,
    desired_vel: np.ndarray | None = None,
    learned: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move every person one step of cfg.dt; walls stay solid (socialzoo.humans.motion).

    The models meet in one step: social-force people feel every person (ORCA ones included) and the
    robots; ORCA people avoid every person and, unless the config hides them, the robots. Each model
    costs only where someone uses it, and with social-force people only the step is exactly the
    social-force step it always was.

    Args:
        pos: (B, H, 2) positions, world frame, m.
        vel: (B, H, 2) velocities, world frame, m/s.
        target: (B, H, 2) waypoints, world frame, m.
        pref_speed: (B, H) preferred speeds, m/s (the social force's speed cap).
        mask: (B, H) present people.
        model: (B, H) SOCIAL_FORCE, ORCA or LEARNED (socialzoo.humans.models).
        group: (B, H) walking group (its first member's slot), -1 for none.
        robot_pos: (B, R, 2) robots the people react to, world frame, m (R = 0: none).
        robot_vel: (B, R, 2) their velocity vectors, m/s.
        walls: the map's wall index.
        cfg: the world's parameters (human, orca, groups, robot, dt).
        desired_vel: (B, H, 2) desired velocities of learned people, m/s.
        learned: (B, H) people whose desired velocity is `desired_vel`.

    Returns:
        (pos, vel, blocked): the new positions and velocities, and the people a wall stopped.
    """
    has_orca, has_other, has_group = _census(mask, model, group, ORCA, REPLAY)
    orca = mask & (model == ORCA) if has_orca else None
    if has_orca and not has_other:
        # Nobody feels a force: only the wall distances of the motion step are needed.
        accel = np.zeros(pos.shape)
        _, wall_dist = walls.nearest(pos)
    else:
        accel, wall_dist = human_acceleration(
            pos, vel, target, pref_speed, mask, robot_pos, robot_vel, walls, cfg.human, desired_vel, learned
        )
    if has_group:
        add_group_accelerations(pos, vel, target, group, mask & (model == SOCIAL_FORCE), cfg.groups, accel)
    velocity = None
    if orca is not None:
        velocity = orca_people_velocities(
            pos, vel, target, pref_speed, mask, orca, robot_pos, robot_vel, walls, cfg
        )
    return integrate_humans(pos, vel, accel, pref_speed, mask, walls, wall_dist, cfg.dt, velocity, orca)


def step_people_packed(
    pos: np.ndarray,
    vel: np.ndarray,
    target: np.ndarray,
    pref_speed: np.ndarray,
    mask: np.ndarray,
    model: np.ndarray,
    group: np.ndarray,
    robot_pos: np.ndarray,
    robot_vel: np.ndarray,
    walls: WallIndex,
    cfg: WorldConfig,
    desired_vel: np.ndarray | None = None,
    learned: np.ndarray | None = None,
    moved: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`step_people` over the rows where some present person is `moved` (B, H), each with only its
    present people, packed in slot order into as many slots as the fullest of those rows has.

    For sparse crowds (recorded scenes, whose slots hold people who have not entered yet or have
    left, and whose replayed people no model moves). Every kernel loops per world over present
    people in slot order (pairs of an absent person add nothing), so each stepped person moves
    exactly as unpacked; the others keep their position and velocity.
    """
    new_pos, new_vel = pos.copy(), vel.copy()
    blocked = np.zeros(mask.shape, dtype=bool)
    moving = mask if moved is None else mask & moved
    # Nobody moved (a batch of replayed people only): skip the packing's pass over every slot.
    if not moving.any():
        return new_pos, new_vel, blocked
    rows, order, where = _pack_slots(mask, moving)
    # Flat gathers and scatters: indexing (B, H, 2) arrays by (rows, slots) pairs costs ten times more.
    flat = (rows[:, None] * mask.shape[1] + order).reshape(-1)

    def packed(array: np.ndarray) -> np.ndarray:
        rest = array.shape[2:]
        return array.reshape((-1,) + rest).take(flat, axis=0).reshape(order.shape + rest)

    inside = packed(mask)
    # Walking groups name their first member's slot: renumber to the packed slots.
    old_group = packed(group)
    new_group = (
        np.where(old_group >= 0, np.take_along_axis(where, np.maximum(old_group, 0), axis=1), -1)
        if (old_group >= 0).any()
        else old_group
    )
    p, v, b = step_people(
        packed(pos), packed(vel), packed(target), packed(pref_speed), inside, packed(model), new_group,
        robot_pos[rows], robot_vel[rows], walls, cfg,
        None if desired_vel is None else packed(desired_vel), None if learned is None else packed(learned),
    )  # fmt: skip
    _unpack(flat, inside.reshape(-1), p.reshape(-1, 2), v.reshape(-1, 2), b.reshape(-1),
            new_pos.reshape(-1, 2), new_vel.reshape(-1, 2), blocked.reshape(-1))  # fmt: skip
    return new_pos, new_vel, blocked


@kernel
def _pack_slots(mask: np.ndarray, moving: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The packing of step_people_packed: rows (n,), the rows where someone is `moving`; order
    (n, W), each row's present slots in slot order, then its first absent ones (W: the most present
    people of those rows); where (n, H), each slot's place in order (-1: not packed)."""
    b, h = mask.shape
    picked = np.zeros(b, dtype=np.bool_)
    n, width = 0, 0
    for r in range(b):
        count = 0
        for s in range(h):
            count += mask[r, s]
            picked[r] = picked[r] or moving[r, s]
        if picked[r]:
            n += 1
            width = max(width, count)
    rows = np.empty(n, dtype=np.int64)
    order = np.empty((n, width), dtype=np.int64)
    where = np.full((n, h), -1, dtype=np.int64)
    j = 0
    for r in range(b):
        if not picked[r]:
            continue
        rows[j] = r
        k = 0
        for present in (True, False):
            for s in range(h):
                if k < width and mask[r, s] == present:
                    order[j, k] = s
                    where[j, s] = k
                    k += 1
        j += 1
    return rows, order, where


@kernel
def _unpack(flat, inside, pos, vel, blocked, out_pos, out_vel, out_blocked):  # type: ignore[no-untyped-def]
    """Write the packed people who are inside back to their flat slots `flat` (the others keep
    theirs)."""
    for i in range(flat.shape[0]):
        if inside[i]:
            j = flat[i]
            out_pos[j, 0], out_pos[j, 1] = pos[i, 0], pos[i, 1]
            out_vel[j, 0], out_vel[j, 1] = vel[i, 0], vel[i, 1]
            out_blocked[j] = blocked[i]
