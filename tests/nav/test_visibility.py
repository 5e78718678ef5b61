"""Sight lines: the distance-field test, clearances and blocking walls, and the step-to-step cache."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.core.geometry import segments_gap, segments_intersect
from socialzoo.core.walls import WallIndex
from socialzoo.nav.distance_field import distance_field
from socialzoo.nav.local_planner import LocalPlannerConfig
from socialzoo.nav.sight_cache import SightCache
from socialzoo.nav.visibility import Sight, lines_of_sight, near_sight_line, sight_lines, visible_humans

PLANNER = LocalPlannerConfig()


def building(random_building, seed: int):
    rng = np.random.default_rng(seed)
    walls = WallIndex(random_building(rng))
    field = distance_field(walls, PLANNER.field_resolution, PLANNER.field_range, PLANNER.field_pad)
    return rng, walls, field


def near_sight_lines(p0, p1, walls):
    """near_sight_line (the sight cache's kernel) for each segment [p0, p1], ends' clearance exact."""
    end = walls.nearest(np.concatenate((p0, p1)))[1]
    end = np.minimum(end[: len(p0)], end[len(p0) :])
    t = walls.fine
    wall, clearance = np.array(
        [
            near_sight_line(*a, *b, e, t.shape_args, t.cell_start, t.cell_walls, walls.walls)
            for a, b, e in zip(p0.tolist(), p1.tolist(), end.tolist(), strict=True)
        ]
    ).T
    return Sight(wall < 0, clearance, wall.astype(np.intp))


def test_fast_sight_lines_match_the_wall_test(random_building):
    rng, walls, field = building(random_building, 11)
    p0 = rng.uniform(-1, 21, (3000, 2))
    p1 = rng.uniform(-1, 21, (3000, 2))
    p1[:20] = p0[:20]  # points
    p0[20:60] = walls.wall_a[rng.integers(0, walls.num_walls, 40)]  # starting on a wall
    np.testing.assert_array_equal(lines_of_sight(p0, p1, walls, field), ~walls.crosses(p0, p1))


@pytest.mark.parametrize("method", ["pieces", "near walls"])
def test_clearance_is_a_lower_bound_and_the_wall_blocks(random_building, method):
    rng, walls, field = building(random_building, 3)
    p0 = rng.uniform(-1, 21, (2000, 2))
    p1 = p0 + rng.uniform(-6, 6, (2000, 2))
    p1[:10] = p0[:10]
    # Lines up to one grid reach long, covered by a single sample.
    angle = rng.uniform(0, 2 * np.pi, 400)
    p1[10:410] = p0[10:410] + rng.uniform(0.5, 1.0, (400, 1)) * np.column_stack(
        (np.cos(angle), np.sin(angle))
    )
    sight = sight_lines(p0, p1, walls, field) if method == "pieces" else near_sight_lines(p0, p1, walls)
    np.testing.assert_array_equal(sight.clear, ~walls.crosses(p0, p1))
    assert 100 < sight.clear.sum() < 1900
    # Brute force: every line against every wall.
    gap = segments_gap(p0[:, None], p1[:, None], walls.wall_a[None], walls.wall_b[None]).min(axis=1)
    clear = sight.clear
    # (Pieces are measured in their own coordinates: equal up to rounding.)
    assert np.all(sight.clearance[clear] <= gap[clear] + 1e-12)
    assert np.all(sight.clearance[clear] >= 0.0) and np.all(sight.clearance[~clear] == 0.0)
    # Close lines are measured exactly (up to the exact-test band), far ones within the field's error.
    # Pieces are measured exactly within 0.1 m of a wall; the grid lists every wall within its
    # reach (1 m) of a sample: of p0 for lines up to 1 m, else of samples at most 1 m apart.
    length = np.linalg.norm(p1 - p0, axis=1)
    exact_below = np.full(len(p0), 0.1) if method == "pieces" else np.where(length <= 1.0, 1.0 - length, 0.5)
    near = clear & (gap < exact_below)
    np.testing.assert_allclose(sight.clearance[near], gap[near], atol=1e-9)
    assert np.all(
        sight.clearance[clear] >= np.minimum(gap[clear], exact_below[clear]) - 2 * PLANNER.field_resolution
    )
    blocked = ~clear
    assert np.all(sight.wall[clear] == -1)
    w = sight.wall[blocked]
    assert np.all(segments_intersect(p0[blocked], p1[blocked], walls.wall_a[w], walls.wall_b[w]))


def random_walk(random_building, seed: int, steps: int, rows: int = 6, humans: int = 9):
    """Observers and humans wandering the building; yields (observer, humans, mask, jumped rows)."""
    rng, walls, field = building(random_building, seed)
    observer = rng.uniform(0, 20, (rows, 2))
    human_pos = rng.uniform(0, 20, (rows, humans, 2))
    mask = rng.random((rows, humans)) < 0.8
    for _ in range(steps):
        observer = np.clip(observer + rng.normal(0, 0.05, observer.shape), -1, 21)
        human_pos = np.clip(human_pos + rng.normal(0, 0.05, human_pos.shape), -1, 21)
        mask ^= rng.random(mask.shape) < 0.01  # humans come and go
        jumped = np.flatnonzero(rng.random(rows) < 0.02)
        observer[jumped] = rng.uniform(0, 20, (len(jumped), 2))
        human_pos[jumped] = rng.uniform(0, 20, (len(jumped), humans, 2))
        yield walls, field, observer, human_pos, mask.copy(), jumped


def test_cache_gives_the_answers_of_a_full_test_every_step(random_building):
    cache = None
    for walls, field, observer, human_pos, mask, jumped in random_walk(random_building, 7, 400):
        if cache is None:
            cache = SightCache(walls, field, *mask.shape)
        cache.forget(jumped)
        got = cache.visible(observer, human_pos, mask)
        pose = np.column_stack((observer, np.zeros(len(observer))))
        np.testing.assert_array_equal(got, visible_humans(pose, human_pos, mask, walls))
    assert cache is not None
    # Slow motion: most lines keep their answer, so few are re-tested.
    assert cache.lines_tested < 0.3 * cache.lines_asked


def test_a_jump_expires_what_was_known(random_building):
    # A line cleared in one place is not trusted after its ends jump, even without forget():
    # the certificate is the displacement, so a jump expires it.
    _, walls, field = building(random_building, 5)
    cache = SightCache(walls, field, 1, 1)
    inside = np.array([[1.0, 1.0]]), np.array([[[3.0, 3.0]]])  # same room
    across = np.array([[1.0, 1.0]]), np.array([[[9.0, 1.2]]])  # through two walls
    mask = np.ones((1, 1), bool)
    assert cache.visible(*inside, mask).all()
    assert not cache.visible(*across, mask).any()
    assert cache.visible(*inside, mask).all()
