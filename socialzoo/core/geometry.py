"""Vectorised 2D geometry on segments, points and rays (numpy only).

Every function broadcasts over leading axes, so one call serves a batch of envs, humans and walls.
"""

from __future__ import annotations

import numpy as np

# Segments whose cross product is below this are treated as parallel (metres squared).
PARALLEL_EPS = 1e-12


def cross2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z component of the cross product of 2D vectors, shape (...,)."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def wrap_angle(theta: np.ndarray | float) -> np.ndarray:
    """Wrap angles (rad) into [-pi, pi)."""
    return (np.asarray(theta) + np.pi) % (2.0 * np.pi) - np.pi


def rotate(vec: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Rotate 2D vectors (..., 2) by angles (...,) counter-clockwise."""
    c, s = np.cos(theta), np.sin(theta)
    x, y = vec[..., 0], vec[..., 1]
    return np.stack((c * x - s * y, s * x + c * y), axis=-1)


def to_frame(points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Express world points (..., 2) in the frame of poses (..., 3) = (x, y, theta)."""
    return rotate(points - pose[..., :2], -pose[..., 2])


def closest_point_on_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closest point of segments [a, b] to points p, and its distance.

    Args:
        p: points, shape (..., 2), metres.
        a: segment starts, shape broadcastable with p.
        b: segment ends, shape broadcastable with p.

    Returns:
        (closest, dist): closest point (..., 2) and Euclidean distance (...,).
        Degenerate segments (a == b) behave as the point a.
    """
    ab = b - a
    ap = p - a
    abx, aby = ab[..., 0], ab[..., 1]
    denom = abx * abx + aby * aby
    t = (ap[..., 0] * abx + ap[..., 1] * aby) / np.where(denom > 0.0, denom, 1.0)
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    closest = a + t[..., None] * ab
    diff = p - closest
    return closest, np.sqrt(diff[..., 0] ** 2 + diff[..., 1] ** 2)


def segments_intersect(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Whether closed segments [p0, p1] and [q0, q1] share a point (touching counts).

    All arguments broadcast; shapes (..., 2). Returns bool (...,).
    Collinear overlapping segments and degenerate (point) segments are handled.
    """
    r = p1 - p0
    s = q1 - q0
    qp = q0 - p0
    denom = cross2(r, s)
    t_num = cross2(qp, s)
    u_num = cross2(qp, r)
    parallel = np.abs(denom) <= PARALLEL_EPS
    safe = np.where(parallel, 1.0, denom)
    t = t_num / safe
    u = u_num / safe
    hit = (~parallel) & (t >= 0.0) & (t <= 1.0) & (u >= 0.0) & (u <= 1.0)
    if np.any(parallel):
        # Parallel, collinear or degenerate: they meet iff an end point lies on the other segment.
        p0b, p1b, q0b, q1b = np.broadcast_arrays(p0, p1, q0, q1)
        idx = parallel.reshape(p0b.shape[:-1]) if parallel.ndim else np.array(True)
        a0, a1, b0, b1 = p0b[idx], p1b[idx], q0b[idx], q1b[idx]
        touch = np.zeros(len(a0), dtype=bool)
        for point, start, end in ((a0, b0, b1), (a1, b0, b1), (b0, a0, a1), (b1, a0, a1)):
            touch |= closest_point_on_segment(point, start, end)[1] <= 1e-9
        if hit.ndim == 0:
            return np.asarray(touch[0])
        hit[idx] = touch
    return hit


def segments_gap(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Distance between closed segments [p0, p1] and [q0, q1] that do not meet; (...,).

    Segments that do not meet are closest at an end point of one of them; for segments that do
    meet this overestimates (their distance is 0). All arguments broadcast; shapes (..., 2).
    """
    p0x, p0y, p1x, p1y = p0[..., 0], p0[..., 1], p1[..., 0], p1[..., 1]
    q0x, q0y, q1x, q1y = q0[..., 0], q0[..., 1], q1[..., 0], q1[..., 1]
    pdx, pdy, qdx, qdy = p1x - p0x, p1y - p0y, q1x - q0x, q1y - q0y
    p_len2, q_len2 = pdx * pdx + pdy * pdy, qdx * qdx + qdy * qdy
    # Reciprocal squared lengths, 0 for a point (whose projection parameter is then 0).
    p_inv = np.divide(1.0, p_len2, out=np.zeros(np.shape(p_len2)), where=p_len2 > 0.0)
    q_inv = np.divide(1.0, q_len2, out=np.zeros(np.shape(q_len2)), where=q_len2 > 0.0)
    best = point_segment_dist2(p0x, p0y, q0x, q0y, qdx, qdy, q_inv)
    np.minimum(best, point_segment_dist2(p1x, p1y, q0x, q0y, qdx, qdy, q_inv), out=best)
    np.minimum(best, point_segment_dist2(q0x, q0y, p0x, p0y, pdx, pdy, p_inv), out=best)
    np.minimum(best, point_segment_dist2(q1x, q1y, p0x, p0y, pdx, pdy, p_inv), out=best)
    return np.sqrt(best, out=best)


def point_segment_dist2(
    px: np.ndarray,
    py: np.ndarray,
    ax: np.ndarray,
    ay: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    inv_len2: np.ndarray,
) -> np.ndarray:
    """Squared distance from points (px, py) to segments a + t (dx, dy), t in [0, 1].

    Component arrays (all broadcast); inv_len2 is 1 / (dx^2 + dy^2), or 0 for a point segment.
    """
    rx, ry = px - ax, py - ay
    t = (rx * dx + ry * dy) * inv_len2
    np.clip(t, 0.0, 1.0, out=t)
    rx -= t * dx
    ry -= t * dy
    return rx * rx + ry * ry


def ray_segment_hit(origin: np.ndarray, direction: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance along unit rays to segments [a, b]; +inf where the ray misses.

    Args:
        origin: ray origins (..., 2).
        direction: unit ray directions (..., 2).
        a, b: segment end points, broadcastable with origin.

    Returns:
        Distance (...,) in metres, >= 0, or inf.
    """
    s = b - a
    denom = cross2(direction, s)
    ao = a - origin
    safe = np.where(np.abs(denom) <= PARALLEL_EPS, 1.0, denom)
    t = cross2(ao, s) / safe
    u = cross2(ao, direction) / safe
    hit = (np.abs(denom) > PARALLEL_EPS) & (t >= 0.0) & (u >= 0.0) & (u <= 1.0)
    return np.where(hit, t, np.inf)


def ray_circle_hit(
    origin: np.ndarray, direction: np.ndarray, centre: np.ndarray, radius: float | np.ndarray
) -> np.ndarray:
    """Distance along unit rays to the first crossing of circles; +inf on a miss.

    A ray starting inside a circle hits it at distance 0.
    """
    oc = centre - origin
    proj = np.einsum("...i,...i->...", oc, direction)
    perp2 = np.einsum("...i,...i->...", oc, oc) - proj**2
    r2 = np.asarray(radius) ** 2
    half_chord = np.sqrt(np.maximum(r2 - perp2, 0.0))
    t = proj - half_chord
    inside = np.einsum("...i,...i->...", oc, oc) <= r2
    hit = (perp2 <= r2) & ((t >= 0.0) | inside)
    return np.where(inside, 0.0, np.where(hit, t, np.inf))


def segment_hits_box(a: np.ndarray, b: np.ndarray, half_length: float, half_width: float) -> np.ndarray:
    """Whether segments [a, b] (in a box's own frame) touch the box |x|<=hl, |y|<=hw.

    Liang-Barsky clipping of the segment against the four slabs. Shapes (..., 2) -> (...,).
    """
    d = b - a
    t0 = np.zeros(d.shape[:-1])
    t1 = np.ones(d.shape[:-1])
    inside = np.ones(d.shape[:-1], dtype=bool)
    for axis, half in ((0, half_length), (1, half_width)):
        da = d[..., axis]
        pa = a[..., axis]
        still = np.abs(da) <= PARALLEL_EPS
        inside &= ~(still & (np.abs(pa) > half))
        safe = np.where(still, 1.0, da)
        ta = (-half - pa) / safe
        tb = (half - pa) / safe
        lo = np.where(still, -np.inf, np.minimum(ta, tb))
        hi = np.where(still, np.inf, np.maximum(ta, tb))
        t0 = np.maximum(t0, lo)
        t1 = np.minimum(t1, hi)
    return inside & (t0 <= t1)
