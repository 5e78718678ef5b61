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
    """(any present ORCA person, any present person a force walks, anyone in a walking group, any
    present person on a recorded track) of people (B, H) in one pass: a step with social-force
    people only skips the others' code, and one with ORCA people and people on their recorded
    tracks (whose step the replay overwrites) skips the forces."""
    has_orca = has_other = has_group = has_replay = False
    for b in range(mask.shape[0]):
        for h in range(mask.shape[1]):
            if mask[b, h]:
                if model[b, h] == orca:
                    has_orca = True
                elif model[b, h] == replay:
                    has_replay = True
                else:
                    has_other = True
            if group[b, h] >= 0:
                has_group = True
    return has_orca, has_other, has_group, has_replay


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
        model: (B, H) SOCIAL_FORCE, ORCA or LEARNED (socialzoo.humans.models); REPLAY people
            (on recorded tracks, which the replay places) stand where they are.
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
    has_orca, has_other, has_group, has_replay = _census(mask, model, group, ORCA, REPLAY)
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
    # Replayed people are where their recording puts them after the step, at its velocity
    # (socialzoo.env.replay), so the motion step leaves them standing where they were.
    moving = mask & (model != REPLAY) if has_replay else mask
    return integrate_humans(pos, vel, accel, pref_speed, moving, walls, wall_dist, cfg.dt, velocity, orca)


def step_people_packed(
    pos: np.ndarray,
    vel: np.ndarray,
    route: np.ndarray,
    waypoint: np.ndarray,
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

    Takes `step_people`'s arguments, but the people's routes (B, H, L, 2) and waypoints (B, H) for
    their targets: the packing gathers the targets of the packed slots only, route[waypoint] of the
    people it steps and its own position for every other packed slot (only the stepped people's
    are read), without a pass over every slot of the batch's cold route array.
    """
    new_pos, new_vel = pos.copy(), vel.copy()
    blocked = np.zeros(mask.shape, dtype=bool)
    moving = mask if moved is None else mask & moved
    # Nobody moved (a batch of replayed people only): skip the packing's pass over every slot.
    if not moving.any():
        return new_pos, new_vel, blocked
    # One compiled pass packs what every step reads (seven numpy takes and the groups' renumbering
    # cost 1.7 times more); learned people's desired velocities, when given, by flat takes.
    rows, flat, p_pos, p_vel, p_target, p_pref, inside, p_model, p_group = _pack_people(
        pos, vel, route, waypoint, pref_speed, mask, model, group, moving
    )

    def packed(array: np.ndarray) -> np.ndarray:
        rest = array.shape[2:]
        return array.reshape((-1,) + rest).take(flat, axis=0).reshape(inside.shape + rest)

    p, v, b = step_people(
        p_pos, p_vel, p_target, p_pref, inside, p_model, p_group, robot_pos[rows], robot_vel[rows], walls, cfg,
        None if desired_vel is None else packed(desired_vel), None if learned is None else packed(learned),
    )  # fmt: skip
    _unpack(flat, inside.reshape(-1), p.reshape(-1, 2), v.reshape(-1, 2), b.reshape(-1),
            new_pos.reshape(-1, 2), new_vel.reshape(-1, 2), blocked.reshape(-1))  # fmt: skip
    return new_pos, new_vel, blocked


@kernel
def _pack_people(pos, vel, route, waypoint, pref_speed, mask, model, group, moving):  # type: ignore[no-untyped-def]
    """The packing of step_people_packed: rows (n,), the rows where someone is `moving`; flat
    (n * W,), each of those rows' present slots in slot order, then its first absent ones (W: the
    most present people of those rows), as flat indices into (B * H); then pos, vel, target,
    pref_speed, mask, model and group (n, W, ...) at those slots, walking groups (their first
    member's slot) renumbered to the packed slots (-1 where that slot is not packed). The target is
    route[b, h, waypoint[b, h]] of a moving person and its position for any other slot."""
    b, h = mask.shape
    present = np.zeros(b, dtype=np.int64)  # each row's present people; -1: a row not packed
    n, width = 0, 0
    for r in range(b):
        picked = False
        for s in range(h):
            if mask[r, s]:
                present[r] += 1
            if moving[r, s]:
                picked = True
        if picked:
            n += 1
            width = max(width, present[r])
        else:
            present[r] = -1
    rows = np.empty(n, dtype=np.int64)
    flat = np.empty(n * width, dtype=np.int64)
    p_pos, p_vel, p_target = np.empty((n, width, 2)), np.empty((n, width, 2)), np.empty((n, width, 2))
    p_pref, p_mask = np.empty((n, width)), np.empty((n, width), dtype=np.bool_)
    p_model, p_group = np.empty((n, width), dtype=model.dtype), np.empty((n, width), dtype=group.dtype)
    where = np.empty(h, dtype=np.int64)  # a row's slots' places in the packing (-1: not packed)
    j = 0
    for r in range(b):
        if present[r] < 0:
            continue
        rows[j] = r
        # One pass over the slots: the present ones from place 0, the first absent ones after them.
        k_present, k_absent = 0, present[r]
        for s in range(h):
            if mask[r, s]:
                k = k_present
                k_present += 1
            elif k_absent < width:
                k = k_absent
                k_absent += 1
            else:
                where[s] = -1
                continue
            flat[j * width + k] = r * h + s
            where[s] = k
            p_pos[j, k, 0], p_pos[j, k, 1] = pos[r, s, 0], pos[r, s, 1]
            p_vel[j, k, 0], p_vel[j, k, 1] = vel[r, s, 0], vel[r, s, 1]
            if moving[r, s]:
                w = waypoint[r, s]
                p_target[j, k, 0], p_target[j, k, 1] = route[r, s, w, 0], route[r, s, w, 1]
            else:
                p_target[j, k, 0], p_target[j, k, 1] = pos[r, s, 0], pos[r, s, 1]
            p_pref[j, k], p_mask[j, k], p_model[j, k] = pref_speed[r, s], mask[r, s], model[r, s]
        for k in range(width):
            first = group[r, flat[j * width + k] - r * h]
            p_group[j, k] = where[first] if first >= 0 else -1
        j += 1
    return rows, flat, p_pos, p_vel, p_target, p_pref, p_mask, p_model, p_group


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
