"""The metrics of Table I of the social-navigation evaluation guidelines (Francis et al., ACM THRI 2025, arXiv
2306.16740), computed from trajectory arrays."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from socialzoo.core.geometry import wall_distances
from socialzoo.core.metrics import names
from socialzoo.core.validation import check_number

# Registry order is the order of the table `socialzoo metrics` prints.
GUIDELINE_KEYS: tuple[str, ...] = names("guidelines")


@dataclass(frozen=True, kw_only=True)
class GuidelineParams:
    """The thresholds Table I leaves to the evaluator (defaults and their sources in
    docs/guideline_metrics.md).

    Attributes:
        personal_space: a person's personal space, m: a sample complies when every present
            person's boundary is at least this far from the robot's (Table I's 0.5 m, after
            Pérez-D'Arpino et al. 2021's personal space compliance).
        stall_speed: the robot is stalled during a step whose speed is below this, m/s.
        progress_time: the window of failure to progress, s.
        progress_distance: the progress towards the goal the robot must make within a window, m.
    """

    personal_space: float = 0.5
    stall_speed: float = 0.05
    progress_time: float = 10.0
    progress_distance: float = 0.25

    def __post_init__(self) -> None:
        for name in ("personal_space", "stall_speed", "progress_time", "progress_distance"):
            check_number(
                "GuidelineParams", name, getattr(self, name), low=0, low_open=name == "progress_time"
            )


@dataclass(frozen=True, kw_only=True)
class Trajectories:
    """B episodes of up to N samples, padded to N (the arrays' second axis); what Table I needs.

    Attributes:
        dt: time between samples, s (> 0).
        robot_pos: (B, N, 2) robot centre, m.
        goal: (B, 2) the robot's goal, m.
        length: (B,) samples of each episode (1..N); None: all N.
        robot_vel: (B, N, 2) the robot's world-frame velocity at each sample, m/s; None: from the
            positions (see the module's conventions).
        robot_radius: the robot's disc radius, m: a number or (B,).
        goal_radius: the goal is reached within this centre distance, m: a number or (B,).
        people_pos: (B, N, H, 2) people's centres, m (anything where absent); None: nobody.
        people_vel: (B, N, H, 2) their velocities, m/s; None (or NaN where not given): (p_k -
            p_(k-1)) / dt where present at both samples (no velocity at a sample without its
            predecessor).
        people_mask: (B, N, H) who is present at each sample; None: everyone, always.
        people_radius: the people's disc radius, m: a number, (H,) or (B, H).
        walls: (W, 4) wall segments x0, y0, x1, y1 shared by the batch, m; None: no walls.
        wall_distance: (B, N) precomputed distance from the robot centre to the nearest wall, m
            (exact, e.g. from a distance field), used instead of `walls`.
        others_pos: (B, N, K, 2) the other robots' centres, m; None: none.
        others_mask: (B, N, K) which other robots are present; None: all, always.
        others_radius: their disc radius, m: a number, (K,) or (B, K).
        others_goal: (B, K, 2) their goals, for the aggregated time (NaN: a robot outside the
            cooperative set); None: the set is the robot alone.
        others_goal_radius: their goal radius, m (a number or (B, K)); None: the robot's.
        shortest_path: (B,) the length of the shortest collision-free path from the start to the
            goal, m (SPL's l); None: the straight-line distance.
        goal_distance: (B, N) distance left to the goal used for progress (e.g. along the map's
            routes), m; None: the straight-line distance.
        time_limit: (B,) or a number: the episode's time limit, s; None: an episode that ended
            with neither the goal nor a collision timed out.
        wall_contact: (B, N) bool, the simulator's wall contact flags; None: the wall gap.
        human_contact: (B, N) or (B, N, H) bool, the simulator's human contact flags; None: the gaps.
        robot_contact: (B, N) or (B, N, K) bool, contacts with other robots; None: the gaps.
    """

    dt: float
    robot_pos: Any
    goal: Any
    length: Any = None
    robot_vel: Any = None
    robot_radius: Any = 0.3
    goal_radius: Any = 0.5
    people_pos: Any = None
    people_vel: Any = None
    people_mask: Any = None
    people_radius: Any = 0.2
    walls: Any = None
    wall_distance: Any = None
    others_pos: Any = None
    others_mask: Any = None
    others_radius: Any = 0.3
    others_goal: Any = None
    others_goal_radius: Any = None
    shortest_path: Any = None
    goal_distance: Any = None
    time_limit: Any = None
    wall_contact: Any = None
    human_contact: Any = None
    robot_contact: Any = None


def _float(a: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    arr = np.asarray(a, dtype=np.float64)
    try:
        return np.broadcast_to(arr, shape)
    except ValueError:
        raise ValueError(
            f"Trajectories.{name} must have shape {shape} (or broadcast to it), got {arr.shape}"
        ) from None


def _per_body(a: Any, b: int, count: int, name: str) -> np.ndarray:
    """A radius given as a number, (count,) or (B, count), as (B, 1, count)."""
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim == 1:
        arr = arr[None, :]
    return _float(arr, (b, count), name)[:, None, :]


def _bools(a: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    arr = np.asarray(a)
    if arr.dtype != bool:
        arr = arr.astype(bool)
    try:
        return np.broadcast_to(arr, shape)
    except ValueError:
        raise ValueError(f"Trajectories.{name} must have shape {shape}, got {arr.shape}") from None


def _starts(contact: np.ndarray) -> np.ndarray:
    """Collisions per episode: samples in contact whose previous sample was not, summed over every
    axis after the sample axis (axis 1)."""
    before = np.zeros_like(contact)
    before[:, 1:] = contact[:, :-1]
    starts = contact & ~before
    return starts.reshape(starts.shape[0], -1).sum(axis=1).astype(np.int64)


def _stats(x: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(min, mean, max) along axis 1 of x over the entries m; NaN where there are none."""
    count = m.sum(axis=1)
    some = count > 0
    lo = np.where(some, np.where(m, x, np.inf).min(axis=1), np.nan)
    hi = np.where(some, np.where(m, x, -np.inf).max(axis=1), np.nan)
    mean = np.where(m, x, 0.0).sum(axis=1) / np.maximum(count, 1)
    return lo, np.where(some, mean, np.nan), hi


def _first(flags: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(any, index of the first True) along axis 1 (index N where none)."""
    hit = np.asarray(flags.any(axis=1), dtype=bool)
    return hit, np.where(hit, flags.argmax(axis=1), flags.shape[1])


def _flags_alone(traj: Trajectories, flag_name: str, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(collisions (B,), contact at each sample (B, N)) from the simulator's contact flags of a
    group that has no positions (a log with the flags but no people or other robots): the flags
    count as given, since a contact the simulator saw is a contact whether or not the bodies were
    logged. No flags (or per-body flags of no body): none."""
    b, n = valid.shape
    flags = getattr(traj, flag_name)
    if flags is None or np.ndim(flags) == 3:
        return np.zeros(b, dtype=np.int64), np.zeros((b, n), dtype=bool)
    contact = _bools(flags, (b, n), flag_name) & valid
    return _starts(contact), contact


def _bodies(traj: Trajectories, group: str, pos: np.ndarray, r_robot: np.ndarray, valid: np.ndarray) -> tuple:
    """The people ("people") or the other robots ("others") of `traj` against the robot: their
    centres (B, N, M, 2), presence (B, N, M), presence within the robot's episode, reach (the sums
    of the radii, (B, 1, M)), boundary gaps (B, N, M), collisions (B,) and contact at each sample
    (B, N), from the gaps or the simulator's contact flags."""
    b, n = pos.shape[:2]
    axis, flag_name = {"people": ("H", "human_contact"), "others": ("K", "robot_contact")}[group]
    bodies = np.asarray(getattr(traj, f"{group}_pos"), dtype=np.float64)
    if bodies.ndim != 4:
        raise ValueError(f"Trajectories.{group}_pos must have shape (B, N, {axis}, 2), got {bodies.shape}")
    m = bodies.shape[2]
    bodies = _float(bodies, (b, n, m, 2), f"{group}_pos")
    mask = getattr(traj, f"{group}_mask")
    mask = np.ones((b, n, m), dtype=bool) if mask is None else _bools(mask, (b, n, m), f"{group}_mask")
    here = mask & valid[:, :, None]
    reach = r_robot[:, None, None] + _per_body(getattr(traj, f"{group}_radius"), b, m, f"{group}_radius")
    gap = np.linalg.norm(bodies - pos[:, :, None, :], axis=3) - reach
    flags = getattr(traj, flag_name)
    if flags is None:
        contact = (gap < 0) & here
    else:
        flags = np.asarray(flags)
        per_body = flags.ndim == 3
        contact = _bools(flags, (b, n, m) if per_body else (b, n), flag_name) & (here if per_body else valid)
    hit = contact if contact.ndim == 2 else contact.any(axis=2)
    return bodies, mask, here, reach, gap, _starts(contact), hit


def time_to_collision(rel_pos: np.ndarray, rel_vel: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Time until two discs touch when both keep their velocities: the least t >= 0 with
    |rel_pos + rel_vel t| = reach (reach the sum of the radii); 0 when they overlap already, inf
    when they never touch. rel_pos and rel_vel (..., 2) are the other body's minus the robot's."""
    c = (rel_pos * rel_pos).sum(axis=-1) - reach * reach
    a = (rel_vel * rel_vel).sum(axis=-1)
    b = 2.0 * (rel_pos * rel_vel).sum(axis=-1)
    disc = b * b - 4.0 * a * c
    closing = (a > 0) & (b < 0) & (disc >= 0)
    root = np.sqrt(np.where(closing, disc, 0.0))
    t = np.where(closing, (-b - root) / np.where(closing, 2.0 * a, 1.0), np.inf)
    return np.where(c <= 0, 0.0, t)


def guideline_metrics(traj: Trajectories, params: GuidelineParams | None = None) -> dict[str, np.ndarray]:
    """Every Table I metric of each episode of `traj`: {name: (B,) array} in registry order
    (GUIDELINE_KEYS; bool, int64 or float64 by the metric's kind, NaN where undefined).

    Batched numpy, no loop over steps, people or episodes: the live env path
    (socialzoo.bench.guideline_recorder) and the episode logs (socialzoo.bench.episode_log) call it with
    the same arrays and get the same numbers.

    Raises:
        ValueError: arrays of the wrong shape, a dt that is not > 0, a length outside 1..N.
    """
    p = params or GuidelineParams()
    dt = float(traj.dt)
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"Trajectories.dt must be a number > 0, got {traj.dt!r}")
    pos = np.asarray(traj.robot_pos, dtype=np.float64)
    if pos.ndim != 3 or pos.shape[2] != 2 or pos.shape[1] < 1:
        raise ValueError(f"Trajectories.robot_pos must have shape (B, N, 2) with N >= 1, got {pos.shape}")
    b, n = pos.shape[:2]
    k = np.arange(n)
    length = np.full(b, n) if traj.length is None else np.asarray(traj.length).astype(np.int64).reshape(-1)
    if length.shape != (b,) or (length < 1).any() or (length > n).any():
        raise ValueError(f"Trajectories.length must be (B,) ints in 1..{n}, got {traj.length!r}")
    goal = _float(traj.goal, (b, 2), "goal")
    r_robot = _float(traj.robot_radius, (b,), "robot_radius")
    goal_radius = _float(traj.goal_radius, (b,), "goal_radius")
    logged = k[None, :] < length[:, None]  # (B, N) samples of the log

    # ---- the goal: the robot's episode ends at the first sample within the goal radius
    to_goal = np.linalg.norm(pos - goal[:, None, :], axis=2)
    reached, reach_at = _first((to_goal <= goal_radius[:, None]) & logged)
    end = np.where(reached, reach_at, length - 1)  # last sample of the robot's episode
    valid = k[None, :] <= end[:, None]
    step = valid.copy()
    step[:, 0] = False  # steps k = 1..end (from sample k-1 to sample k)

    # ---- the robot's motion
    if traj.robot_vel is not None:
        vel = _float(traj.robot_vel, (b, n, 2), "robot_vel")
    else:
        vel = np.zeros((b, n, 2))
        vel[:, 1:] = np.diff(pos, axis=1) / dt
    speed = np.linalg.norm(vel, axis=2)
    accel = np.zeros((b, n))
    accel[:, 1:] = np.diff(speed, axis=1) / dt
    jerk = np.zeros((b, n))
    jerk[:, 2:] = np.diff(accel[:, 1:], axis=1) / dt
    jerk_ok = step.copy()
    jerk_ok[:, :2] = False
    moved = np.zeros((b, n))
    moved[:, 1:] = np.linalg.norm(np.diff(pos, axis=1), axis=2)
    path_length = np.where(step, moved, 0.0).sum(axis=1)
    stalled_time = dt * (step & (speed < p.stall_speed)).sum(axis=1)

    # ---- people: boundary gaps, contacts, personal space, time to collision
    zeros = np.zeros(b, dtype=np.int64)
    human_collisions, hum_contact = _flags_alone(traj, "human_contact", valid)
    min_human = np.full(b, np.nan)
    compliant = valid.copy()
    ttc = np.full(b, np.nan)
    if traj.people_pos is not None and np.asarray(traj.people_pos).size:
        ppos, _, present, reach, gap, human_collisions, hum_contact = _bodies(
            traj, "people", pos, r_robot, valid
        )
        h = ppos.shape[2]
        rel = ppos - pos[:, :, None, :]
        some = present.any(axis=(1, 2))
        min_human = np.where(some, np.where(present, gap, np.inf).min(axis=(1, 2)), np.nan)
        compliant = valid & ~(present & (gap < p.personal_space)).any(axis=2)
        pvel = np.zeros((b, n, h, 2))
        with np.errstate(invalid="ignore"):
            pvel[:, 1:] = np.diff(ppos, axis=1) / dt
        known = present.copy()
        known[:, 1:] &= present[:, :-1]
        known[:, 0] = False
        if traj.people_vel is not None:  # given velocities, else (NaN) those of the positions
            given = _float(traj.people_vel, (b, n, h, 2), "people_vel")
            has = present & np.isfinite(given).all(axis=3)
            pvel = np.where(has[..., None], given, pvel)
            known |= has
        with np.errstate(invalid="ignore", over="ignore"):
            t = time_to_collision(rel, pvel - vel[:, :, None, :], reach)
        # Overlapping discs are 0 s from contact whatever their velocities, so a person's first
        # sample (no velocity from the positions yet) counts when it overlaps.
        overlap = present & (gap <= 0)
        t = np.where(known, t, np.where(overlap, 0.0, np.inf))
        ttc = np.where((known | overlap).any(axis=(1, 2)), t.min(axis=(1, 2)), np.nan)

    # ---- walls: clearing distance and contacts
    if traj.wall_distance is not None:
        centre = _float(traj.wall_distance, (b, n), "wall_distance")
    elif traj.walls is not None and np.size(traj.walls):
        centre = wall_distances(pos, traj.walls)
    else:
        centre = np.full((b, n), np.inf)
    clearance = centre - r_robot[:, None]
    known_wall = valid & np.isfinite(clearance)
    cd_min, cd_avg, _ = _stats(clearance, known_wall)
    if traj.wall_contact is not None:
        wall_contact = _bools(traj.wall_contact, (b, n), "wall_contact") & valid
    else:
        wall_contact = known_wall & (clearance < 0)
    wall_collisions = _starts(wall_contact)

    # ---- other robots: contacts and the cooperative set's goals
    robot_collisions, rob_contact = _flags_alone(traj, "robot_contact", valid)
    others_reach_at = np.zeros((b, 0))
    if traj.others_pos is not None and np.asarray(traj.others_pos).size:
        opos, omask, _, _, _, robot_collisions, rob_contact = _bodies(traj, "others", pos, r_robot, valid)
        kk = opos.shape[2]
        if traj.others_goal is not None:
            ogoal = _float(traj.others_goal, (b, kk, 2), "others_goal")
            oradius = _float(
                goal_radius[:, None] if traj.others_goal_radius is None else traj.others_goal_radius,
                (b, kk),
                "others_goal_radius",
            )
            member = np.isfinite(ogoal).all(axis=2)  # a NaN goal: outside the cooperative set
            with np.errstate(invalid="ignore"):
                at_goal = np.linalg.norm(opos - ogoal[:, None], axis=3) <= oradius[:, None, :]
            at_goal &= omask & logged[:, :, None]
            hit = at_goal.any(axis=1)
            others_reach_at = np.where(member, np.where(hit, at_goal.argmax(axis=1), np.nan), -np.inf)

    # ---- the episode's outcome
    any_contact = (hum_contact | wall_contact | rob_contact) & valid
    collided = any_contact.any(axis=1)
    success = reached & ~collided  # a contact at the goal sample fails it too
    duration = dt * (length - 1)
    if traj.time_limit is None:
        limit_hit = np.ones(b, dtype=bool)
    else:
        limit_hit = duration >= _float(traj.time_limit, (b,), "time_limit") - 0.5 * dt
    timeout = ~reached & ~collided & limit_hit
    straight = np.linalg.norm(goal - pos[:, 0], axis=1)
    shortest = straight if traj.shortest_path is None else _float(traj.shortest_path, (b,), "shortest_path")
    longest = np.maximum(path_length, shortest)
    spl = np.where(success, np.divide(shortest, longest, out=np.ones(b), where=longest > 0), 0.0)

    # ---- failure to progress: windows of progress_time without progress_distance of progress
    left = to_goal if traj.goal_distance is None else _float(traj.goal_distance, (b, n), "goal_distance")
    w = max(1, round(min(p.progress_time / dt, n)))  # a window as long as the episode finds none
    if n > w:
        windows = np.lib.stride_tricks.sliding_window_view(left, w + 1, axis=1)  # (B, N - w, w + 1)
        stuck = windows[:, :, 1:].min(axis=2) > windows[:, :, 0] - p.progress_distance
        stuck &= valid[:, w:]
        failures = _starts(stuck)
    else:
        failures = zeros

    # ---- aggregated time: the last of the cooperative set (the robot and others with goals) to arrive
    own = np.where(reached, reach_at, np.nan)[:, None]
    arrivals = np.concatenate([own, others_reach_at], axis=1)
    aggregated = dt * arrivals.max(axis=1)  # NaN when one never arrived

    v_min, v_avg, v_max = _stats(speed, step)
    a_min, a_avg, a_max = _stats(accel, step)
    j_min, j_avg, j_max = _stats(jerk, jerk_ok)
    out: dict[str, np.ndarray] = {
        "gl_success": success,
        "gl_collisions": human_collisions + wall_collisions + robot_collisions,
        "gl_wall_collisions": wall_collisions,
        "gl_human_collisions": human_collisions,
        "gl_robot_collisions": robot_collisions,
        "gl_timeout": timeout,
        "gl_failure_to_progress": failures,
        "gl_stalled_time": stalled_time,
        "gl_time_to_goal": np.where(success, dt * reach_at, np.nan),
        "gl_path_length": path_length,
        "gl_spl": spl,
        "gl_velocity_min": v_min,
        "gl_velocity_avg": v_avg,
        "gl_velocity_max": v_max,
        "gl_acceleration_min": a_min,
        "gl_acceleration_avg": a_avg,
        "gl_acceleration_max": a_max,
        "gl_jerk_min": j_min,
        "gl_jerk_avg": j_avg,
        "gl_jerk_max": j_max,
        "gl_clearing_distance_min": cd_min,
        "gl_clearing_distance_avg": cd_avg,
        "gl_personal_space_compliance": compliant.sum(axis=1) / valid.sum(axis=1),
        "gl_min_distance_to_human": min_human,
        "gl_min_time_to_collision": ttc,
        "gl_aggregated_time": aggregated,
    }
    if tuple(out) != GUIDELINE_KEYS:  # the registry and this function list the same metrics
        raise AssertionError(f"guideline_metrics: {tuple(out)} != registry {GUIDELINE_KEYS}")
    return out


def episode_metrics(params: GuidelineParams | None = None, **arrays: Any) -> dict[str, Any]:
    """The Table I metrics of one episode: `arrays` are Trajectories' fields without the batch
    axis (robot_pos (N, 2), people_pos (N, H, 2), goal (2,), ...); {name: bool, int or float}."""
    batched: dict[str, Any] = {}
    for key, value in arrays.items():
        if value is None or key in ("dt", "walls", "robot_radius", "goal_radius"):
            batched[key] = value
        elif key in ("people_radius", "others_radius") and np.ndim(value) <= 1:
            batched[key] = value
        else:
            batched[key] = np.asarray(value)[None]
    found = guideline_metrics(Trajectories(**batched), params)
    return {name: values[0].item() for name, values in found.items()}
