"""Vectorised 2D geometry on segments, points and rays."""

from __future__ import annotations

import math

import numpy as np

from socialzoo.core.jit import kernel

# Segments whose cross product is below this are treated as parallel (metres squared).
PARALLEL_EPS = 1e-12
# An end point this close to the other segment touches it (parallel segments), metres.
_TOUCH = 1e-9


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


@kernel
def point_near_segment(px: float, py: float, ax: float, ay: float, bx: float, by: float, tol: float) -> bool:
    """Whether point p lies within tol of segment [a, b] (a point if a == b); scalar kernel."""
    abx, aby = bx - ax, by - ay
    len2 = abx * abx + aby * aby
    return math.sqrt(point_segment_dist2(px, py, ax, ay, abx, aby, 1.0 / len2 if len2 > 0.0 else 0.0)) <= tol


@kernel
def segments_meet(
    p0x: float, p0y: float, p1x: float, p1y: float, q0x: float, q0y: float, q1x: float, q1y: float
) -> bool:
    """Whether closed segments [p0, p1] and [q0, q1] share a point (touching counts); scalar kernel.

    Parallel, collinear or degenerate (point) segments meet iff an end point lies on the other.
    """
    rx, ry = p1x - p0x, p1y - p0y
    sx, sy = q1x - q0x, q1y - q0y
    qpx, qpy = q0x - p0x, q0y - p0y
    denom = rx * sy - ry * sx
    if abs(denom) > PARALLEL_EPS:
        t = (qpx * sy - qpy * sx) / denom
        u = (qpx * ry - qpy * rx) / denom
        return 0.0 <= t <= 1.0 and 0.0 <= u <= 1.0
    return (
        point_near_segment(p0x, p0y, q0x, q0y, q1x, q1y, _TOUCH)
        or point_near_segment(p1x, p1y, q0x, q0y, q1x, q1y, _TOUCH)
        or point_near_segment(q0x, q0y, p0x, p0y, p1x, p1y, _TOUCH)
        or point_near_segment(q1x, q1y, p0x, p0y, p1x, p1y, _TOUCH)
    )


@kernel
def point_segment_dist2(
    px: float, py: float, ax: float, ay: float, dx: float, dy: float, inv_len2: float
) -> float:
    """Squared distance from point p to segment a + t (dx, dy), t in [0, 1]; scalar kernel.

    inv_len2 is 1 / (dx^2 + dy^2), or 0 for a point segment.
    """
    rx, ry = px - ax, py - ay
    t = min(max((rx * dx + ry * dy) * inv_len2, 0.0), 1.0)
    rx -= t * dx
    ry -= t * dy
    return rx * rx + ry * ry


@kernel
def segments_gap_at(
    p0x: float, p0y: float, p1x: float, p1y: float, q0x: float, q0y: float, q1x: float, q1y: float
) -> float:
    """Distance between closed segments that do not meet (see segments_gap); scalar kernel."""
    pdx, pdy, qdx, qdy = p1x - p0x, p1y - p0y, q1x - q0x, q1y - q0y
    p_len2, q_len2 = pdx * pdx + pdy * pdy, qdx * qdx + qdy * qdy
    # Reciprocal squared lengths, 0 for a point (whose projection parameter is then 0).
    p_inv = 1.0 / p_len2 if p_len2 > 0.0 else 0.0
    q_inv = 1.0 / q_len2 if q_len2 > 0.0 else 0.0
    best = min(
        point_segment_dist2(p0x, p0y, q0x, q0y, qdx, qdy, q_inv),
        point_segment_dist2(p1x, p1y, q0x, q0y, qdx, qdy, q_inv),
        point_segment_dist2(q0x, q0y, p0x, p0y, pdx, pdy, p_inv),
        point_segment_dist2(q1x, q1y, p0x, p0y, pdx, pdy, p_inv),
    )
    return math.sqrt(best)


@kernel
def _segment_pairs(p0, p1, q0, q1, gap, out):
    """out[k] = segments_meet (gap False) or segments_gap_at (gap True) of rows k of (N, 2) arrays."""
    for k in range(out.shape[0]):
        args = (p0[k, 0], p0[k, 1], p1[k, 0], p1[k, 1], q0[k, 0], q0[k, 1], q1[k, 0], q1[k, 1])
        out[k] = segments_gap_at(*args) if gap else segments_meet(*args)


def _on_segment_pairs(p0, p1, q0, q1, dtype) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Broadcast four (..., 2) arrays and apply the scalar segment-pair kernel to every pair."""
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (p0, p1, q0, q1)))
    shape = arrays[0].shape[:-1]
    # Plain (N, 2) rows: broadcast views are read-only aliases, which numba warns about.
    a0, a1, b0, b1 = (np.ascontiguousarray(v).reshape(-1, 2) for v in arrays)
    out = np.empty(int(np.prod(shape)), dtype=dtype)
    _segment_pairs(a0, a1, b0, b1, dtype == np.float64, out)
    return out.reshape(shape)


def segments_intersect(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Whether closed segments [p0, p1] and [q0, q1] share a point (touching counts).

    All arguments broadcast; shapes (..., 2). Returns bool (...,).
    Collinear overlapping segments and degenerate (point) segments are handled (segments_meet).
    """
    return _on_segment_pairs(p0, p1, q0, q1, np.bool_)


def segments_gap(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Distance between closed segments [p0, p1] and [q0, q1] that do not meet; (...,).

    Segments that do not meet are closest at an end point of one of them; for segments that do
    meet this overestimates (their distance is 0). All arguments broadcast; shapes (..., 2).
    """
    return _on_segment_pairs(p0, p1, q0, q1, np.float64)


def ray_segment_hit(origin: np.ndarray, direction: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance along unit rays to segments [a, b]; +inf where the ray misses.

    Args:
        origin: ray origins (..., 2).
        direction: unit ray directions (..., 2).
        a: segment start points, broadcastable with origin.
        b: segment end points, broadcastable with origin.

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


# (point, wall) pairs per block of wall_distances' query: bounded memory for long trajectories.
_WALL_PAIRS_PER_BLOCK = 1 << 21


def wall_distances(points: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Distance from each point (..., 2) to the nearest of the wall segments (W, 4), m (inf
    without walls); blocks of points bound the (points, W) temporaries."""
    pts = np.asarray(points, dtype=np.float64)
    segs = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    flat = pts.reshape(-1, 2)
    out = np.full(len(flat), np.inf)
    if len(segs) == 0 or len(flat) == 0:
        return out.reshape(pts.shape[:-1])
    a, d = segs[:, :2], segs[:, 2:] - segs[:, :2]
    len2 = (d * d).sum(axis=1)
    inv = np.divide(1.0, len2, out=np.zeros_like(len2), where=len2 > 0)
    block = max(1, _WALL_PAIRS_PER_BLOCK // len(segs))
    for lo in range(0, len(flat), block):  # blocks of points: a log or a grid is one or a few blocks
        r = flat[lo : lo + block, None, :] - a[None]
        t = np.clip((r * d[None]).sum(axis=2) * inv[None], 0.0, 1.0)
        gap = r - t[..., None] * d[None]
        out[lo : lo + block] = np.sqrt((gap * gap).sum(axis=2).min(axis=1))
    return out.reshape(pts.shape[:-1])
