"""Geometry primitives against direct scalar computations."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from socialzoo.core.geometry import (
    closest_point_on_segment,
    ray_circle_hit,
    ray_segment_hit,
    segment_hits_box,
    segments_intersect,
    to_frame,
    wrap_angle,
)

# Half-integer coordinates: exact arithmetic, so touching and collinear cases are decided exactly.
coord = st.integers(-20, 20).map(lambda v: v / 2)
point = st.tuples(coord, coord)


def _orient(a, b, c):
    v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    return 0 if abs(v) < 1e-12 else (1 if v > 0 else -1)


def _on_segment(a, b, p):
    return (
        min(a[0], b[0]) - 1e-12 <= p[0] <= max(a[0], b[0]) + 1e-12
        and min(a[1], b[1]) - 1e-12 <= p[1] <= max(a[1], b[1]) + 1e-12
    )


def _scalar_intersect(p0, p1, q0, q1):
    o1, o2, o3, o4 = _orient(p0, p1, q0), _orient(p0, p1, q1), _orient(q0, q1, p0), _orient(q0, q1, p1)
    if o1 != o2 and o3 != o4:
        return True
    return (
        (o1 == 0 and _on_segment(p0, p1, q0))
        or (o2 == 0 and _on_segment(p0, p1, q1))
        or (o3 == 0 and _on_segment(q0, q1, p0))
        or (o4 == 0 and _on_segment(q0, q1, p1))
    )


@settings(max_examples=300, deadline=None)
@given(point, point, point, point)
def test_segments_intersect_matches_orientation_test(p0, p1, q0, q1):
    got = bool(segments_intersect(*(np.array(v, dtype=float) for v in (p0, p1, q0, q1))))
    assert got == _scalar_intersect(p0, p1, q0, q1)


def test_segments_intersect_cases():
    a = np.array
    assert segments_intersect(a([0, 0]), a([2, 0]), a([1, -1]), a([1, 1]))
    assert not segments_intersect(a([0, 0]), a([2, 0]), a([3, -1]), a([3, 1]))
    assert segments_intersect(a([0, 0]), a([2, 0]), a([2, 0]), a([3, 1])), "touching end points"
    assert segments_intersect(a([0, 0]), a([2, 0]), a([1, 0]), a([3, 0])), "collinear overlap"
    assert not segments_intersect(a([0, 0]), a([2, 0]), a([3, 0]), a([4, 0])), "collinear apart"
    assert not segments_intersect(a([0, 0]), a([2, 0]), a([0, 1]), a([2, 1])), "parallel"


@settings(max_examples=200, deadline=None)
@given(point, point, point)
def test_closest_point_is_closest_sample(p, a, b):
    p, a, b = (np.array(v, dtype=float) for v in (p, a, b))
    closest, dist = closest_point_on_segment(p, a, b)
    samples = a + np.linspace(0, 1, 2001)[:, None] * (b - a)
    brute = np.min(np.linalg.norm(samples - p, axis=1))
    assert dist <= brute + 1e-9
    assert abs(dist - np.linalg.norm(closest - p)) < 1e-9
    assert dist >= brute - np.linalg.norm(b - a) / 2000 - 1e-9


def test_ray_hits():
    o = np.array([0.0, 0.0])
    d = np.array([1.0, 0.0])
    assert ray_segment_hit(o, d, np.array([2.0, -1.0]), np.array([2.0, 1.0])) == 2.0
    assert np.isinf(ray_segment_hit(o, d, np.array([-2.0, -1.0]), np.array([-2.0, 1.0])))
    assert math.isclose(float(ray_circle_hit(o, d, np.array([3.0, 0.0]), 0.5)), 2.5)
    assert np.isinf(ray_circle_hit(o, d, np.array([3.0, 2.0]), 0.5))
    assert ray_circle_hit(o, d, np.array([0.1, 0.0]), 0.5) == 0.0


def test_segment_hits_box():
    hl, hw = 0.25, 0.215
    a = np.array
    assert segment_hits_box(a([-1.0, 0.0]), a([1.0, 0.0]), hl, hw)
    assert segment_hits_box(a([0.0, 0.0]), a([0.01, 0.0]), hl, hw), "inside"
    assert not segment_hits_box(a([-1.0, 0.3]), a([1.0, 0.3]), hl, hw)
    assert segment_hits_box(a([0.25, 1.0]), a([0.25, -1.0]), hl, hw), "grazing the front edge"
    assert not segment_hits_box(a([0.3, 1.0]), a([0.3, -1.0]), hl, hw)
    assert not segment_hits_box(a([0.5, 0.0]), a([1.0, 1.0]), hl, hw)


def test_frames_and_angles():
    pose = np.array([1.0, 2.0, np.pi / 2])
    local = to_frame(np.array([1.0, 3.0]), pose)
    np.testing.assert_allclose(local, [1.0, 0.0], atol=1e-12)
    assert math.isclose(float(wrap_angle(3 * np.pi)), -np.pi)
    assert math.isclose(float(wrap_angle(0.5)), 0.5)
