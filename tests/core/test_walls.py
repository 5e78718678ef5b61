"""The grid wall index gives the same answers as brute force over every wall."""

import math
import tracemalloc

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from socialzoo.core.geometry import (
    closest_point_on_segment,
    ray_segment_hit,
    segment_hits_box,
    segments_intersect,
    to_frame,
)
from socialzoo.core.walls import WallIndex


def random_walls(rng, n, size=20.0, max_len=4.0):
    a = rng.uniform(0, size, (n, 2))
    angle = rng.uniform(0, 2 * np.pi, n)
    length = rng.uniform(0.0, max_len, n)
    b = a + length[:, None] * np.stack((np.cos(angle), np.sin(angle)), axis=1)
    walls = np.hstack((a, b))
    walls[0, 2:] = walls[0, :2]  # a zero-length wall must not break anything
    return walls


@pytest.fixture(scope="module", params=[0, 1, 2])
def scene(request):
    rng = np.random.default_rng(request.param)
    walls = random_walls(rng, 120)
    return WallIndex(walls), walls, rng


def test_nearest_matches_brute_force(scene):
    index, walls, rng = scene
    pts = rng.uniform(-2, 22, (3000, 2))
    closest, dist = index.nearest(pts)
    _, all_dist = closest_point_on_segment(pts[:, None, :], walls[None, :, :2], walls[None, :, 2:])
    brute = all_dist.min(axis=1)
    within = brute <= index.reach
    np.testing.assert_allclose(dist[within], brute[within], atol=1e-12)
    assert np.all(np.isinf(dist[~within]))
    np.testing.assert_allclose(np.linalg.norm(closest[within] - pts[within], axis=1), dist[within], atol=1e-9)
    np.testing.assert_array_equal(closest[~within], pts[~within])
    # The answers come from the pruned candidate lists, which are shorter.
    assert len(index.nearest_candidates.cell_walls) < len(index.fine.cell_walls)


def test_crosses_matches_brute_force(scene):
    index, walls, rng = scene
    p0 = rng.uniform(-2, 22, (2000, 2))
    # Mix short moves (the human step) and long lines of sight.
    length = np.where(rng.random(2000) < 0.5, rng.uniform(0, 0.1, 2000), rng.uniform(0, 15, 2000))
    angle = rng.uniform(0, 2 * np.pi, 2000)
    p1 = p0 + length[:, None] * np.stack((np.cos(angle), np.sin(angle)), axis=1)
    got = index.crosses(p0, p1)
    brute = segments_intersect(p0[:, None], p1[:, None], walls[None, :, :2], walls[None, :, 2:]).any(axis=1)
    np.testing.assert_array_equal(got, brute)
    assert got.any() and not got.all()


def test_footprint_matches_brute_force(scene):
    index, walls, rng = scene
    pose = np.column_stack((rng.uniform(-1, 21, (3000, 2)), rng.uniform(-np.pi, np.pi, 3000)))
    got = index.footprint_hits(pose, 0.25, 0.215)
    a = to_frame(walls[None, :, :2], pose[:, None, :])
    b = to_frame(walls[None, :, 2:], pose[:, None, :])
    brute = segment_hits_box(a, b, 0.25, 0.215).any(axis=1)
    np.testing.assert_array_equal(got, brute)
    assert got.any() and not got.all()


def test_footprint_larger_than_reach_is_refused(scene):
    index, _, _ = scene
    with pytest.raises(ValueError, match="exceeds the wall index reach"):
        index.footprint_hits(np.zeros((1, 3)), 2.0, 2.0)


def test_cast_rays_match_brute_force(scene):
    index, walls, rng = scene
    origins = rng.uniform(0, 20, (50, 2))
    angles = rng.uniform(-np.pi, np.pi, (50, 90))
    got = index.cast_rays(origins, angles, 8.0)
    direction = np.stack((np.cos(angles), np.sin(angles)), axis=-1)
    hits = ray_segment_hit(origins[:, None, None], direction[:, :, None], walls[:, :2], walls[:, 2:])
    brute = np.minimum(hits.min(axis=-1), 8.0)
    np.testing.assert_allclose(got, brute, atol=1e-9)


def test_cast_rays_are_the_pairwise_formula_bit_for_bit_without_a_pair_by_ray_array():
    # Walls and origins on a lattice: rays start on walls and pass corners, so ties and signed
    # zeros occur; every wall is within the 8 m range of every origin.
    rng = np.random.default_rng(0)
    walls = rng.integers(0, 8, (60, 4)).astype(float)
    index = WallIndex(walls)
    origins = rng.integers(0, 8, (200, 2)).astype(float)
    angles = np.tile(np.linspace(-np.pi, np.pi, 90, endpoint=False), (200, 1))
    table = index.table(cell_size=2.0, reach=8.0)  # cast_rays' table for an 8 m range
    query, wall = table.candidates(table.cells(origins))
    direction = np.stack((np.cos(angles), np.sin(angles)), axis=-1)
    hits = ray_segment_hit(
        origins[query, None], direction[query], walls[wall, None, :2], walls[wall, None, 2:]
    )
    expected = np.full(angles.shape, 8.0)
    np.minimum.at(expected, query, hits)
    index.cast_rays(origins, angles, 8.0)  # compiled and its table built outside the trace
    tracemalloc.start()
    got = index.cast_rays(origins, angles, 8.0)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert np.array_equal(got.view(np.int64), expected.view(np.int64))
    # One (pairs, rays) float array is 8.6 MB here; a building's hundreds of walls within a 10 m
    # range made such temporaries GiBs at B = 512.
    assert peak < hits.nbytes / 4, peak


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.1, 2.0), st.floats(0.2, 3.0))
def test_any_cell_size_and_reach_agree_with_brute_force(seed, cell_size, reach):
    rng = np.random.default_rng(seed)
    walls = random_walls(rng, 40, size=10.0)
    index = WallIndex(walls, cell_size=cell_size, reach=reach)
    pts = rng.uniform(-1, 11, (300, 2))
    _, dist = index.nearest(pts)
    _, all_dist = closest_point_on_segment(pts[:, None, :], walls[None, :, :2], walls[None, :, 2:])
    brute = all_dist.min(axis=1)
    within = brute <= reach
    np.testing.assert_allclose(dist[within], brute[within], atol=1e-12)
    p1 = pts + rng.normal(0, 3, pts.shape)
    brute_cross = segments_intersect(pts[:, None], p1[:, None], walls[None, :, :2], walls[None, :, 2:]).any(1)
    np.testing.assert_array_equal(index.crosses(pts, p1), brute_cross)


def test_same_cost_structure_on_a_large_map():
    """Candidate counts depend on local density, not on the number of walls in the map."""
    rng = np.random.default_rng(5)
    room = np.array([[0, 0, 10, 0], [10, 0, 10, 10], [10, 10, 0, 10], [0, 10, 0, 0]], dtype=float)
    clutter = random_walls(rng, 2000, size=200.0, max_len=2.0) + np.array([300.0, 300.0, 300.0, 300.0])
    small = WallIndex(room)
    large = WallIndex(np.vstack((room, clutter)))
    pts = rng.uniform(0.5, 9.5, (500, 2))
    q_small, _ = small.fine.candidates(small.fine.cells(pts))
    q_large, _ = large.fine.candidates(large.fine.cells(pts))
    assert len(q_small) == len(q_large)


def test_rejects_nan_walls():
    with pytest.raises(ValueError, match="NaN"):
        WallIndex(np.array([[0.0, 0.0, math.nan, 1.0]]))


def test_walls_spread_too_wide_for_the_grid_are_refused_naming_their_extent():
    # A 10 m room drawn in millimetres: its 25 cm grid would have 1.6e9 cells (12 GB of counts alone).
    room_mm = np.array([[0, 0, 1e4, 0], [1e4, 0, 1e4, 1e4], [1e4, 1e4, 0, 1e4], [0, 1e4, 0, 0]])
    with pytest.raises(
        ValueError, match=r"the walls span 10000 x 10000 m \(from \(0, 0\) to \(10000, 10000\)\)"
    ):
        WallIndex(room_mm).table()
    assert WallIndex(room_mm / 1000).table().num_x == 50  # the same room in metres
