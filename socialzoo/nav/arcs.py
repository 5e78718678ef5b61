"""Arc geometry of the trajectory rollout (socialzoo.nav.local_planner): the arcs and their wall samples, the wall
distance-field codes along every arc, and where arcs enter human discs."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.nav.planner_config import LocalPlannerConfig

# Curvatures below this are straight lines; the closed forms below use it in place of zero.
_STRAIGHT = 1e-9
_TWO_PI = 2.0 * math.pi
# Guards float32 divisions by quantities that vanish only in degenerate geometry.
_TINY32 = np.float32(1e-30)


@dataclass(frozen=True)
class ArcTable:
    """Arc geometry shared by every call with one config.

    Attributes:
        curvature: (A,) signed curvature, 1/m.
        abs_curvature: (A,) |curvature|, with straight arcs at a tiny positive value.
        side: (A,) +1 for left turns (and straight), -1 for right turns.
        lengths: (K,) arc length of the wall-check samples, m, increasing from 0.
        free_at: (K + 1,) free length when the first blocked sample is k (k = K: none blocked):
            the length of the sample before it, 0 for k = 0, inf for k = K, m.
        offsets: (A, K, 2) sample positions in the robot frame (x ahead, y left), m.
        cell_offsets: (K, A, 2) float32 offsets in distance-field cells (cfg.field_resolution),
            sample-major so that a prefix of samples is one contiguous block.
        abs_curvature32, side32, half_k2, two_over_k2: float32 (A,) copies for the human terms:
            |c|, side, c^2 / 2 and 2 / c^2.
    """

    curvature: np.ndarray
    abs_curvature: np.ndarray
    side: np.ndarray
    lengths: np.ndarray
    free_at: np.ndarray
    offsets: np.ndarray
    cell_offsets: np.ndarray
    abs_curvature32: np.ndarray
    side32: np.ndarray
    half_k2: np.ndarray
    two_over_k2: np.ndarray


def arc_points(
    abs_curvature: np.ndarray, side: np.ndarray, length: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Robot-frame point reached after `length` metres along arcs; broadcasts, returns (x, y).

    Arcs have constant curvature c and start at the robot, heading along its x axis; a robot-frame
    point after s metres is (sin(|c| s) / |c|, side * (1 - cos(|c| s)) / |c|). Straight arcs use a
    tiny curvature in the same closed forms.
    """
    turn = abs_curvature * length
    x = np.sin(turn) / abs_curvature
    # 1 - cos(u) written as 2 sin^2(u / 2): exact for the tiny curvature of straight arcs.
    y = side * 2.0 * np.sin(0.5 * turn) ** 2 / abs_curvature
    return x, y


@lru_cache(maxsize=16)
def arc_table(cfg: LocalPlannerConfig) -> ArcTable:
    """Precomputed arcs and sample offsets for a config."""
    curvature = cfg.curvatures
    side = np.where(curvature < 0.0, -1.0, 1.0)
    abs_curvature = np.maximum(np.abs(curvature), _STRAIGHT)
    near = np.arange(0.0, cfg.near_range - 1e-9, cfg.near_sample_spacing)
    far = np.arange(cfg.near_range, cfg.max_arc_length + 0.5 * cfg.sample_spacing, cfg.sample_spacing)
    lengths = np.unique(np.round(np.concatenate((near, np.minimum(far, cfg.max_arc_length))), 9))
    free_at = np.concatenate(([0.0], lengths[:-1], [np.inf]))
    x, y = arc_points(abs_curvature[:, None], side[:, None], lengths[None, :])
    offsets = np.stack((x, y), axis=-1)
    k32 = abs_curvature.astype(np.float32)
    return ArcTable(
        curvature=curvature,
        abs_curvature=abs_curvature,
        side=side,
        lengths=lengths,
        free_at=free_at,
        offsets=offsets,
        cell_offsets=np.ascontiguousarray(
            (offsets / cfg.field_resolution).astype(np.float32).transpose(1, 0, 2)
        ),
        abs_curvature32=k32,
        side32=side.astype(np.float32),
        half_k2=(0.5 * abs_curvature**2).astype(np.float32),
        two_over_k2=(2.0 / abs_curvature**2).astype(np.float32),
    )


@kernel
def arc_wall_codes(
    x, y, cos, sin, offsets, field_shape, field_codes, stop_code, lengths, trim, here, codes, num_free,
):  # fmt: skip
    """Distance-field codes along every arc of every row, as running minima, as far as they count.

    codes (S, A, N) gets, for sample j of arc a of row i, the smallest field code over samples
    0..j; sample 0 (the robot's own position) reads 255, because it never blocks an arc: the
    robot is where it is, and an arc leading away from a wall it is too close to must stay open.
    here (N,) gets the code at the robot. offsets (K >= S, A, 2) are the arc samples in field
    cells (ArcTable.cell_offsets), rotated by each row's heading in float32.

    An arc is sampled only while it counts: up to its first blocked sample (a code below
    stop_code[here[i]], stop_code (256,) being the blocking code for each code at the robot) and
    while the previous sample's length (lengths (>= S,), m) is below its trimmed length trim
    (N, A), m. Later samples repeat the last code read: the free length, the first blocked
    sample or the trimmed length, whichever comes first, and the clearance read at a sample
    within it are those of a full sampling (about 60% of the lookups are skipped on gdc1).
    num_free (A, N) gets the number of samples whose code does not block.
    """
    ox, oy, res, num_x, num_y, _ = field_shape
    num_samples, num_arcs, n = codes.shape
    c = cos.astype(np.float32)
    s = sin.astype(np.float32)
    sx = ((x - ox) / res).astype(np.float32)
    sy = ((y - oy) / res).astype(np.float32)
    stop = np.empty(n, dtype=np.uint8)
    for i in range(n):
        ix = min(max(int(sx[i]), 0), num_x - 1)
        iy = min(max(int(sy[i]), 0), num_y - 1)
        here[i] = field_codes[ix * num_y + iy]
        stop[i] = stop_code[here[i]]
        for a in range(num_arcs):
            codes[0, a, i] = 255
            num_free[a, i] = num_samples
    for j in range(1, num_samples):
        before = lengths[j - 1]
        for a in range(num_arcs):
            off_x, off_y = offsets[j, a, 0], offsets[j, a, 1]
            for i in range(n):
                prev = codes[j - 1, a, i]
                if prev < stop[i] or before >= trim[i, a]:
                    codes[j, a, i] = prev
                    continue
                # Truncation is the floor on the grid, then rows near its border are clamped.
                ix = min(max(int(off_x * c[i] - off_y * s[i] + sx[i]), 0), num_x - 1)
                iy = min(max(int(off_x * s[i] + off_y * c[i] + sy[i]), 0), num_y - 1)
                code = min(field_codes[ix * num_y + iy], prev)
                codes[j, a, i] = code
                if code < stop[i]:
                    num_free[a, i] = j


@dataclass(frozen=True)
class HumanArcs:
    """Circle-disc terms of pair humans against every arc (float32, (P, A) unless noted)."""

    yp: np.ndarray  # human's lateral offset towards the arc's turning side, m
    r: np.ndarray  # k * (distance from the turning centre to the human)
    r_minus_a: np.ndarray  # r - (1 - k yp), free of cancellation
    psi: np.ndarray  # turning angle at the human's closest approach, in [0, 2 pi)
    dist2: np.ndarray  # (P, 1) squared robot-human distance, m^2
    hit: np.ndarray  # free length before the inflated disc, m (inf on a miss)


def human_arcs(hx: np.ndarray, hy: np.ndarray, radius: np.ndarray, table: ArcTable) -> HumanArcs:
    """Where every arc enters the discs of radius `radius` around humans (hx, hy) (P,), robot frame.

    Along an arc of curvature k, the squared distance to h after turning u = k s is
    (2 / k^2) (a - r cos(u - psi) + k^2 |h|^2 / 2) with a = 1 - k yp, b = k hx, r = |(a, b)|,
    psi = atan2(b, a). Every term is written so that it stays accurate in float32 down to the
    tiny curvature of the straight arc.
    """
    k = table.abs_curvature32
    hx32 = hx.astype(np.float32)[:, None]
    yp = table.side32 * hy.astype(np.float32)[:, None]
    dist2 = hx32 * hx32 + (hy * hy).astype(np.float32)[:, None]
    a = 1.0 - k * yp
    b = k * hx32
    b2 = b * b
    r = np.sqrt(a * a + b2)
    psi = np.arctan2(b, a)
    # r - a = b^2 / (r + a) when a > 0 (no cancellation); r + |a| never vanishes unless r does.
    abs_a = np.abs(a)
    r_minus_a = np.where(a > 0.0, b2 / np.maximum(r + abs_a, _TINY32), r + abs_a)
    r = np.maximum(r, _TINY32)
    e = table.half_k2 * (dist2 - (radius * radius).astype(np.float32)[:, None])
    # 1 - cos(delta), delta the half-angle of the arc inside the disc.
    one_minus = (r_minus_a - e) / r
    meets = (one_minus >= 0.0) & (one_minus <= 2.0)
    delta = 2.0 * np.arcsin(np.sqrt(np.clip(0.5 * one_minus, 0.0, 1.0)))
    enter = psi - delta
    enter += np.float32(_TWO_PI) * (enter < 0.0)
    hit = np.where(meets, enter / k, np.float32(np.inf))
    psi += np.float32(_TWO_PI) * (psi < 0.0)
    return HumanArcs(yp=yp, r=r, r_minus_a=r_minus_a, psi=psi, dist2=dist2, hit=hit)


def human_gaps(h: HumanArcs, length: np.ndarray, table: ArcTable) -> np.ndarray:
    """(P, A) smallest robot-human centre distance along the arcs' first `length` (P, A) metres."""
    k = table.abs_curvature32
    turn = length.astype(np.float32) * k
    half = 0.5 * (turn - h.psi)
    end2 = table.two_over_k2 * (table.half_k2 * h.dist2 - h.r_minus_a + 2.0 * h.r * np.sin(half) ** 2)
    # Distance from the turning circle to the human, (r - 1) / k = (k |h|^2 - 2 yp) / (r + 1).
    ring = (k * h.dist2 - 2.0 * h.yp) / (h.r + 1.0)
    near2 = np.where(h.psi <= turn, ring * ring, np.minimum(end2, h.dist2))
    return np.sqrt(np.maximum(near2, 0.0))
