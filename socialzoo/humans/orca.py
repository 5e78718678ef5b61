"""ORCA people: optimal reciprocal collision avoidance (van den Berg, Guy, Lin and Manocha, "Reciprocal n-body
collision avoidance", ISRR 2009 / Springer 2011), batched and compiled."""

from __future__ import annotations

import math

import numpy as np

from socialzoo.core.config import OrcaConfig
from socialzoo.core.jit import kernel
from socialzoo.core.walls import WallIndex, grid_cell

# Tolerance of the linear programs (parallel lines) and of the covered-wall test, as in the paper's
# reference implementation.
EPSILON = 1e-5
# Columns of a line row: a point on the line and its unit direction; the allowed velocities lie
# to the left of the direction.
_PX, _PY, _DX, _DY = range(4)
# A post (a zero-length wall) is avoided as a wall seen end-on: a stub from it straight away from the
# agent, this fraction of their distance long (its velocity obstacle is the post's alone).
_STUB = 1e-9


@kernel
def _linear_program1(lines, line_no, radius, opt_x, opt_y, direction_opt):  # type: ignore[no-untyped-def]
    """Best point on line `line_no` inside the disc and left of lines 0 .. line_no - 1.

    Returns (feasible, x, y). With direction_opt the point furthest along (opt_x, opt_y), else
    the point closest to it.
    """
    px, py = lines[line_no, _PX], lines[line_no, _PY]
    dx, dy = lines[line_no, _DX], lines[line_no, _DY]
    dot = px * dx + py * dy
    discriminant = dot * dot + radius * radius - (px * px + py * py)
    if discriminant < 0.0:
        # The max-speed disc misses the line altogether.
        return False, 0.0, 0.0
    root = math.sqrt(discriminant)
    t_left = -dot - root
    t_right = -dot + root
    for i in range(line_no):
        qx, qy = lines[i, _PX], lines[i, _PY]
        ex, ey = lines[i, _DX], lines[i, _DY]
        denominator = dx * ey - dy * ex
        numerator = ex * (py - qy) - ey * (px - qx)
        if abs(denominator) <= EPSILON:
            # (Nearly) parallel: line i either allows all of line_no or none of it.
            if numerator < 0.0:
                return False, 0.0, 0.0
            continue
        t = numerator / denominator
        if denominator >= 0.0:
            t_right = min(t_right, t)
        else:
            t_left = max(t_left, t)
        if t_left > t_right:
            return False, 0.0, 0.0
    if direction_opt:
        t = t_right if opt_x * dx + opt_y * dy > 0.0 else t_left
    else:
        t = dx * (opt_x - px) + dy * (opt_y - py)
        if t < t_left:
            t = t_left
        elif t > t_right:
            t = t_right
    return True, px + t * dx, py + t * dy


@kernel
def _linear_program2(lines, count, radius, opt_x, opt_y, direction_opt):  # type: ignore[no-untyped-def]
    """The velocity in the disc of `radius` left of lines[:count] closest to (opt_x, opt_y)
    (or furthest along it with direction_opt, where it is a unit vector).

    Returns (fail, x, y): fail = count on success, else the first line that leaves nothing
    feasible, with (x, y) the solution for the lines before it.
    """
    if direction_opt:
        rx, ry = opt_x * radius, opt_y * radius
    else:
        norm2 = opt_x * opt_x + opt_y * opt_y
        if norm2 > radius * radius:
            scale = radius / math.sqrt(norm2)
            rx, ry = opt_x * scale, opt_y * scale
        else:
            rx, ry = opt_x, opt_y
    for i in range(count):
        if lines[i, _DX] * (lines[i, _PY] - ry) - lines[i, _DY] * (lines[i, _PX] - rx) > 0.0:
            # The current solution breaks line i: the new optimum lies on it.
            ok, x, y = _linear_program1(lines, i, radius, opt_x, opt_y, direction_opt)
            if not ok:
                return i, rx, ry
            rx, ry = x, y
    return count, rx, ry


@kernel
def _linear_program3(lines, count, num_obstacle, begin, radius, rx, ry, projected):  # type: ignore[no-untyped-def]
    """The velocity that minimises the largest violation of the agent lines (from `begin` on)
    while keeping every wall line, starting from (rx, ry); `projected` is scratch space.

    For each agent line violated more than the best so far, the other agent lines are turned
    into lines of equal violation with it, and a two-dimensional program over those and the
    wall lines finds the velocity furthest into line i (the paper's three-dimensional program).
    """
    distance = 0.0
    for i in range(begin, count):
        px, py = lines[i, _PX], lines[i, _PY]
        dx, dy = lines[i, _DX], lines[i, _DY]
        if dx * (py - ry) - dy * (px - rx) <= distance:
            continue
        num = 0
        for j in range(num_obstacle):
            for c in range(4):
                projected[num, c] = lines[j, c]
            num += 1
        for j in range(num_obstacle, i):
            qx, qy = lines[j, _PX], lines[j, _PY]
            ex, ey = lines[j, _DX], lines[j, _DY]
            determinant = dx * ey - dy * ex
            if abs(determinant) <= EPSILON:
                if dx * ex + dy * ey > 0.0:
                    # Parallel, same direction: line j adds nothing beyond line i.
                    continue
                lx, ly = 0.5 * (px + qx), 0.5 * (py + qy)
            else:
                k = (ex * (py - qy) - ey * (px - qx)) / determinant
                lx, ly = px + k * dx, py + k * dy
            ux, uy = ex - dx, ey - dy
            norm = math.sqrt(ux * ux + uy * uy)
            projected[num, _PX] = lx
            projected[num, _PY] = ly
            projected[num, _DX] = ux / norm
            projected[num, _DY] = uy / norm
            num += 1
        fail, x, y = _linear_program2(projected, num, radius, -dy, dx, True)
        if fail >= num:
            # A failure here can only be rounding: the current velocity is kept.
            rx, ry = x, y
        distance = dx * (py - ry) - dy * (px - rx)
    return rx, ry


@kernel
def _add_line(lines, count, px, py, dx, dy):  # type: ignore[no-untyped-def]
    lines[count, _PX] = px
    lines[count, _PY] = py
    lines[count, _DX] = dx
    lines[count, _DY] = dy
    return count + 1


@kernel
def _wall_lines(  # type: ignore[no-untyped-def]
    lines, count, px, py, vx, vy, radius, inv_tau, x1, y1, x2, y2
):
    """Add the ORCA line of the wall edge (x1, y1) -> (x2, y2), which has the agent on its right,
    unless earlier lines already cover its velocity obstacle; returns the new line count."""
    r1x, r1y = x1 - px, y1 - py
    r2x, r2y = x2 - px, y2 - py
    # Already covered: both ends, scaled to the horizon and grown by the radius, lie beyond a line.
    for j in range(count):
        lx, ly = lines[j, _PX], lines[j, _PY]
        ldx, ldy = lines[j, _DX], lines[j, _DY]
        if (inv_tau * r1x - lx) * ldy - (inv_tau * r1y - ly) * ldx - inv_tau * radius >= -EPSILON and (
            inv_tau * r2x - lx
        ) * ldy - (inv_tau * r2y - ly) * ldx - inv_tau * radius >= -EPSILON:
            return count
    ox, oy = x2 - x1, y2 - y1
    length = math.sqrt(ox * ox + oy * oy)
    ux, uy = ox / length, oy / length  # the edge's direction; its other end walks back along -u
    dist1 = r1x * r1x + r1y * r1y
    dist2 = r2x * r2x + r2y * r2y
    radius2 = radius * radius
    s = (-r1x * ox - r1y * oy) / (ox * ox + oy * oy)
    cx, cy = -r1x - s * ox, -r1y - s * oy
    dist_line = cx * cx + cy * cy
    # Already touching: the only constraint is not to move further in.
    if s < 0.0 and dist1 <= radius2:
        norm = math.sqrt(dist1)
        return _add_line(lines, count, 0.0, 0.0, -r1y / norm, r1x / norm)
    if s > 1.0 and dist2 <= radius2:
        # The far end's own edge (the wall walked back) handles it unless the agent faces it.
        if r2x * (-uy) - r2y * (-ux) >= 0.0:
            norm = math.sqrt(dist2)
            return _add_line(lines, count, 0.0, 0.0, -r2y / norm, r2x / norm)
        return count
    if 0.0 <= s <= 1.0 and dist_line <= radius2:
        return _add_line(lines, count, 0.0, 0.0, -ux, -uy)
    # The legs of the velocity obstacle: tangents from the agent to the discs at the ends. Seen
    # obliquely, both legs come from the nearer end ("same"). Directions of the ends' edges:
    # first end along u (its neighbour edge, the wall walked back, along -u), second end along -u.
    same = (s < 0.0 or s > 1.0) and dist_line <= radius2
    if same:
        # The nearer end: the first (its edge along u) or the second (along -u); -1.0 * u is -u exactly.
        sign = 1.0 if s < 0.0 else -1.0
        ex, ey, dist = (r1x, r1y, dist1) if s < 0.0 else (r2x, r2y, dist2)
        c1x, c1y, c2x, c2y = ex, ey, ex, ey
        dir1x, dir1y = sign * ux, sign * uy
        dir2x, dir2y = dir1x, dir1y
        left_nx, left_ny = -dir1x, -dir1y
        leg = math.sqrt(dist - radius2)
        lgx = (ex * leg - ey * radius) / dist
        lgy = (ex * radius + ey * leg) / dist
        rgx = (ex * leg + ey * radius) / dist
        rgy = (-ex * radius + ey * leg) / dist
    else:
        c1x, c1y, c2x, c2y = r1x, r1y, r2x, r2y
        dir1x, dir1y, dir2x, dir2y = ux, uy, -ux, -uy
        left_nx, left_ny = -ux, -uy
        leg1 = math.sqrt(dist1 - radius2)
        lgx = (r1x * leg1 - r1y * radius) / dist1
        lgy = (r1x * radius + r1y * leg1) / dist1
        leg2 = math.sqrt(dist2 - radius2)
        rgx = (r2x * leg2 + r2y * radius) / dist2
        rgy = (-r2x * radius + r2y * leg2) / dist2
    # A leg that points into the neighbouring edge is replaced by that edge; a velocity that
    # projects onto such a "foreign" leg adds no constraint (the neighbour edge's line covers it).
    left_foreign = False
    right_foreign = False
    if lgx * (-left_ny) - lgy * (-left_nx) >= 0.0:
        lgx, lgy = -left_nx, -left_ny
        left_foreign = True
    if rgx * dir2y - rgy * dir2x <= 0.0:
        rgx, rgy = dir2x, dir2y
        right_foreign = True
    lcx, lcy = inv_tau * c1x, inv_tau * c1y
    rcx, rcy = inv_tau * c2x, inv_tau * c2y
    cvx, cvy = rcx - lcx, rcy - lcy
    t = 0.5 if same else ((vx - lcx) * cvx + (vy - lcy) * cvy) / (cvx * cvx + cvy * cvy)
    t_left = (vx - lcx) * lgx + (vy - lcy) * lgy
    t_right = (vx - rcx) * rgx + (vy - rcy) * rgy
    grow = radius * inv_tau
    first = (t < 0.0 and t_left < 0.0) or (same and t_left < 0.0 and t_right < 0.0)
    if first or (t > 1.0 and t_right < 0.0):
        # Closest to the cut-off disc of the first end (else of the second).
        ex, ey, kx, ky = (lcx, lcy, c1x, c1y) if first else (rcx, rcy, c2x, c2y)
        wx, wy = vx - ex, vy - ey
        norm = math.sqrt(wx * wx + wy * wy)
        if norm <= 0.0:
            wx, wy, norm = -kx, -ky, math.sqrt(kx * kx + ky * ky)
        wx, wy = wx / norm, wy / norm
        return _add_line(lines, count, ex + grow * wx, ey + grow * wy, wy, -wx)
    inf = math.inf
    d_cut = inf
    if not (t < 0.0 or t > 1.0 or same):
        ax, ay = vx - (lcx + t * cvx), vy - (lcy + t * cvy)
        d_cut = ax * ax + ay * ay
    d_left = inf
    if t_left >= 0.0:
        ax, ay = vx - (lcx + t_left * lgx), vy - (lcy + t_left * lgy)
        d_left = ax * ax + ay * ay
    d_right = inf
    if t_right >= 0.0:
        ax, ay = vx - (rcx + t_right * rgx), vy - (rcy + t_right * rgy)
        d_right = ax * ax + ay * ay
    if d_cut <= d_left and d_cut <= d_right:
        # The cut-off segment, walked against the edge.
        ldx, ldy = -dir1x, -dir1y
        return _add_line(lines, count, lcx + grow * (-ldy), lcy + grow * ldx, ldx, ldy)
    if d_left <= d_right:
        if left_foreign:
            return count
        return _add_line(lines, count, lcx + grow * (-lgy), lcy + grow * lgx, lgx, lgy)
    if right_foreign:
        return count
    ldx, ldy = -rgx, -rgy
    return _add_line(lines, count, rcx + grow * (-ldy), rcy + grow * ldx, ldx, ldy)


@kernel
def _orca(  # type: ignore[no-untyped-def]
    pos, vel, pref, radius, max_speed, present, drive, seen,
    grid, cell_start, cell_walls, walls, max_candidates,
    neighbor_dist, max_neighbors, time_horizon, time_horizon_obst, dt, out,
):  # fmt: skip
    """Fill out (B, N, 2) with the ORCA velocity of every driven agent; see orca_velocities."""
    batch, num = present.shape
    capacity = max_candidates + max_neighbors
    lines = np.empty((capacity, 4))
    projected = np.empty((capacity, 4))
    near_dist = np.empty(max(max_neighbors, 1))
    near_index = np.empty(max(max_neighbors, 1), dtype=np.int64)
    wall_dist = np.empty(max(max_candidates, 1))
    wall_index = np.empty(max(max_candidates, 1), dtype=np.int64)
    wall_flip = np.empty(max(max_candidates, 1), dtype=np.bool_)
    inv_tau = 1.0 / time_horizon
    inv_tau_obst = 1.0 / time_horizon_obst
    inv_dt = 1.0 / dt
    for b in range(batch):
        for i in range(num):
            if not (present[b, i] and drive[b, i]):
                out[b, i, 0] = vel[b, i, 0]
                out[b, i, 1] = vel[b, i, 1]
                continue
            px, py = pos[b, i, 0], pos[b, i, 1]
            vx, vy = vel[b, i, 0], vel[b, i, 1]
            r = radius[b, i]
            speed = max_speed[b, i]
            # Neighbours: the max_neighbors nearest within neighbor_dist, nearest first (ties in
            # index order); once the list is full the search radius shrinks to its farthest.
            num_near = 0
            range2 = neighbor_dist * neighbor_dist
            if max_neighbors > 0:
                for j in range(num):
                    if j == i or not present[b, j] or not seen[b, j]:
                        continue
                    ddx, ddy = pos[b, j, 0] - px, pos[b, j, 1] - py
                    d2 = ddx * ddx + ddy * ddy
                    if d2 < range2:
                        if num_near < max_neighbors:
                            num_near += 1
                        k = num_near - 1
                        while k > 0 and d2 < near_dist[k - 1]:
                            near_dist[k] = near_dist[k - 1]
                            near_index[k] = near_index[k - 1]
                            k -= 1
                        near_dist[k] = d2
                        near_index[k] = j
                        if num_near == max_neighbors:
                            range2 = near_dist[num_near - 1]
            # Walls within reach of the obstacle horizon, nearest first, each as the edge that has
            # the agent on its right. A wall the agent is exactly in line with, seen end-on, is kept
            # as it is given (its velocity obstacle, that of its nearer end, is the same either way
            # round; RVO2 drops it and walks the agent into it), and so is a post, which lies before
            # its own start (the wall index's points); one the agent stands on is dropped.
            reach = time_horizon_obst * speed + r
            reach2 = reach * reach
            cell = grid_cell(px, py, grid)
            num_walls = 0
            for k in range(cell_start[cell], cell_start[cell + 1]):
                w = cell_walls[k]
                ax, ay, bx, by = walls[w, 0], walls[w, 1], walls[w, 2], walls[w, 3]
                ox, oy = bx - ax, by - ay
                len2 = ox * ox + oy * oy
                side = (ax - px) * oy - (ay - py) * ox
                t = ((px - ax) * ox + (py - ay) * oy) / len2 if len2 > 0.0 else -1.0
                if (side == 0.0 and 0.0 <= t <= 1.0) or (px == ax and py == ay):
                    continue
                if t < 0.0:
                    ex, ey = px - ax, py - ay
                elif t > 1.0:
                    ex, ey = px - bx, py - by
                else:
                    ex, ey = px - (ax + t * ox), py - (ay + t * oy)
                d2 = ex * ex + ey * ey
                if d2 < reach2:
                    wall_dist[num_walls] = d2
                    wall_index[num_walls] = w
                    wall_flip[num_walls] = side > 0.0
                    num_walls += 1
            # Nearest first; a stable sort keeps equally near walls in the grid's order.
            order = np.argsort(wall_dist[:num_walls], kind="mergesort")
            count = 0
            for q in range(num_walls):
                m = order[q]
                w = wall_index[m]
                e = 2 if wall_flip[m] else 0  # the column of the edge's first end
                x1, y1, x2, y2 = walls[w, e], walls[w, e + 1], walls[w, 2 - e], walls[w, 3 - e]
                if (x2 - x1) * (x2 - x1) + (y2 - y1) * (y2 - y1) <= 0.0:
                    x2, y2 = x1 + _STUB * (x1 - px), y1 + _STUB * (y1 - py)
                count = _wall_lines(lines, count, px, py, vx, vy, r, inv_tau_obst, x1, y1, x2, y2)
            num_obstacle = count
            # Agent lines: each agent takes half of the change of relative velocity that gets it
            # out of the velocity obstacle (truncated at time_horizon; within one step when the
            # two already overlap).
            for q in range(num_near):
                j = near_index[q]
                rpx, rpy = pos[b, j, 0] - px, pos[b, j, 1] - py
                rvx, rvy = vx - vel[b, j, 0], vy - vel[b, j, 1]
                d2 = rpx * rpx + rpy * rpy
                combined = r + radius[b, j]
                combined2 = combined * combined
                if d2 > combined2:
                    wx, wy = rvx - inv_tau * rpx, rvy - inv_tau * rpy
                    w2 = wx * wx + wy * wy
                    dot = wx * rpx + wy * rpy
                    if dot < 0.0 and dot * dot > combined2 * w2:
                        # Closest to the cut-off disc.
                        wl = math.sqrt(w2)
                        uwx, uwy = wx / wl, wy / wl
                        ldx, ldy = uwy, -uwx
                        ux, uy = (combined * inv_tau - wl) * uwx, (combined * inv_tau - wl) * uwy
                    else:
                        leg = math.sqrt(d2 - combined2)
                        if rpx * wy - rpy * wx > 0.0:
                            ldx = (rpx * leg - rpy * combined) / d2
                            ldy = (rpx * combined + rpy * leg) / d2
                        else:
                            ldx = -(rpx * leg + rpy * combined) / d2
                            ldy = -(-rpx * combined + rpy * leg) / d2
                        dot2 = rvx * ldx + rvy * ldy
                        ux, uy = dot2 * ldx - rvx, dot2 * ldy - rvy
                else:
                    # Overlapping: get apart within one step.
                    wx, wy = rvx - inv_dt * rpx, rvy - inv_dt * rpy
                    wl = math.sqrt(wx * wx + wy * wy)
                    if wl <= 0.0:
                        # Same place, same velocity: part them along x, by index order.
                        wx, wy, wl = (1.0 if i < j else -1.0), 0.0, 1.0
                    uwx, uwy = wx / wl, wy / wl
                    ldx, ldy = uwy, -uwx
                    ux, uy = (combined * inv_dt - wl) * uwx, (combined * inv_dt - wl) * uwy
                count = _add_line(lines, count, vx + 0.5 * ux, vy + 0.5 * uy, ldx, ldy)
            fail, nx, ny = _linear_program2(lines, count, speed, pref[b, i, 0], pref[b, i, 1], False)
            if fail < count:
                nx, ny = _linear_program3(lines, count, num_obstacle, fail, speed, nx, ny, projected)
            out[b, i, 0] = nx
            out[b, i, 1] = ny


def orca_velocities(
    pos: np.ndarray,
    vel: np.ndarray,
    pref_vel: np.ndarray,
    radius: np.ndarray,
    max_speed: np.ndarray,
    present: np.ndarray,
    drive: np.ndarray,
    seen: np.ndarray,
    walls: WallIndex,
    cfg: OrcaConfig,
    dt: float,
) -> np.ndarray:
    """The ORCA velocity of every driven agent of B rows.

    Each driven agent picks the velocity closest to its preferred one among those that, for a time
    horizon, collide with no neighbour (each agent taking half of the avoidance) and, for a second
    horizon, with no wall: the solution of a small linear program over the ORCA lines inside the
    max-speed disc, with a fall-back that minimises the largest violation of the agent constraints
    when they leave nothing feasible (the paper's sections 4 and 5.2: linear programs in two and three
    dimensions). Each wall is the obstacle edge that faces the agent (a wall seen from its other side is
    the same segment walked the other way), with convex ends; the walls and the kernel are described in
    docs/humans.md, "ORCA people".

    Args:
        pos: (B, N, 2) agent positions, world frame, m.
        vel: (B, N, 2) current velocities, world frame, m/s.
        pref_vel: (B, N, 2) preferred velocities, world frame, m/s.
        radius: (B, N) agent radii, m.
        max_speed: (B, N) speed limits of the driven agents, m/s.
        present: (B, N) agents that exist.
        drive: (B, N) agents whose new velocity is computed.
        seen: (B, N) agents the others avoid (an invisible robot is present but not seen).
        walls: the map's wall index.
        cfg: neighbour distance and count, time horizons (its radius and speeds are not read:
            they are the per-agent arrays here).
        dt: the step, s (the horizon within which overlapping agents get apart).

    Returns:
        (B, N, 2) new velocities, m/s: ORCA's for driven agents, `vel` for the others.
    """
    batch, num = present.shape
    out = np.empty((batch, num, 2))
    active = present & drive
    if not active.any():
        out[...] = vel
        return out
    reach = cfg.time_horizon_obst * float(max_speed[active].max()) + float(radius[active].max())
    # A grid table of every wall within `reach` of a cell: the wall index's fine one when its reach
    # suffices (walking people with a short obstacle horizon), else a coarser one of at least that
    # reach, rounded up to 0.5 m so that few tables are built (each is built once per map and cached).
    rounded = math.ceil(reach * 2.0) / 2.0
    fine = reach <= walls.reach
    table = walls.fine if fine else walls.table(cell_size=max(walls.cell_size, rounded / 4.0), reach=rounded)
    _orca(
        np.ascontiguousarray(pos, dtype=np.float64),
        np.ascontiguousarray(vel, dtype=np.float64),
        np.ascontiguousarray(pref_vel, dtype=np.float64),
        np.ascontiguousarray(radius, dtype=np.float64),
        np.ascontiguousarray(max_speed, dtype=np.float64),
        np.ascontiguousarray(present, dtype=np.bool_),
        np.ascontiguousarray(drive, dtype=np.bool_),
        np.ascontiguousarray(seen, dtype=np.bool_),
        table.shape_args, table.cell_start, table.cell_walls, walls.walls, table.max_candidates,
        float(cfg.neighbor_dist), int(cfg.max_neighbors), float(cfg.time_horizon),
        float(cfg.time_horizon_obst), float(dt), out,
    )  # fmt: skip
    return out
