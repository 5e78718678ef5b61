"""step_people_packed: the rows where someone is moved, with only their present people, step
exactly as the full step_people steps them (recorded scenes' sparse crowds)."""

from __future__ import annotations

import numpy as np

from socialzoo.core.config import WorldConfig
from socialzoo.core.walls import WallIndex
from socialzoo.humans.models import LEARNED, ORCA, REPLAY, SOCIAL_FORCE
from socialzoo.humans.people import step_people, step_people_packed


def _crowd(seed: int):
    rng = np.random.default_rng(seed)
    b, h = 6, 15
    model = rng.choice(np.array([SOCIAL_FORCE, ORCA, REPLAY], dtype=np.int8), size=(b, h))
    group = np.full((b, h), -1)
    group[0, [3, 5]] = 3  # a walking pair in slots 3 and 5
    model[0, [3, 5]] = SOCIAL_FORCE
    mask = rng.random((b, h)) < 0.45
    mask[0, [3, 5]] = True
    mask[4] = False  # an empty row
    # A pair whose first member (the slot that names the group) is absent: packed, it walks alone.
    group[2, [1, 6]] = 1
    model[2, 6] = SOCIAL_FORCE
    mask[2, 1], mask[2, 6] = False, True
    return (
        rng.uniform(-4, 4, (b, h, 2)), rng.normal(0, 1, (b, h, 2)), rng.uniform(-6, 6, (b, h, 2)),
        rng.uniform(0.8, 1.4, (b, h)), mask, model, group, rng.uniform(-4, 4, (b, 1, 2)), rng.normal(0, 1, (b, 1, 2)),
    )  # fmt: skip


def _routed(args):
    """`_crowd`'s step arguments for step_people_packed: each person's target as the point at a
    random waypoint of a random 4-point route, in place of the target."""
    target = args[2]
    rng = np.random.default_rng(11)
    route = rng.uniform(-6, 6, target.shape[:2] + (4, 2))
    waypoint = rng.integers(0, 4, target.shape[:2])
    b, h = np.indices(waypoint.shape)
    route[b, h, waypoint] = target
    return (args[0], args[1], route, waypoint, *args[3:])


def test_packed_people_step_exactly_as_unpacked() -> None:
    walls = WallIndex(np.array([[-5.0, -5.0, 5.0, -5.0], [5.0, -5.0, 5.0, 5.0]]))
    cfg = WorldConfig(dt=0.1)
    for seed in range(3):
        args = _crowd(seed)
        mask, model = args[4], args[5]
        moved = model != REPLAY
        full = step_people(*args, walls, cfg)
        packed = step_people_packed(*_routed(args), walls, cfg, moved=moved)
        stepped = mask & moved.any(axis=1, where=mask, keepdims=True)
        for whole, part in zip(full[:2], packed[:2], strict=True):
            assert np.array_equal(whole[stepped], part[stepped])
        # Rows where no present person is moved are not stepped at all.
        idle = ~(mask & moved).any(axis=1)
        assert np.array_equal(packed[0][idle], args[0][idle])


def test_nobody_moved_returns_new_arrays_equal_to_the_old() -> None:
    walls = WallIndex(np.array([[-5.0, -5.0, 5.0, -5.0], [5.0, -5.0, 5.0, 5.0]]))
    args = _crowd(0)
    pos, vel, mask = args[0], args[1], args[4]
    new_pos, new_vel, blocked = step_people_packed(
        *_routed(args), walls, WorldConfig(dt=0.1), moved=np.zeros_like(mask)
    )
    assert np.array_equal(new_pos, pos) and np.array_equal(new_vel, vel) and not blocked.any()
    assert blocked.shape == mask.shape and new_pos is not pos and new_vel is not vel


def test_packed_learned_people_step_exactly_as_unpacked() -> None:
    """Learned people's desired velocities are packed with the same flat indices as the rest."""
    walls = WallIndex(np.array([[-5.0, -5.0, 5.0, -5.0], [5.0, -5.0, 5.0, 5.0]]))
    cfg = WorldConfig(dt=0.1)
    rng = np.random.default_rng(7)
    args = list(_crowd(1))
    mask, model = args[4], args[5].copy()
    model[1:4, ::3] = LEARNED
    args[5] = model
    desired = rng.normal(0, 1, args[0].shape)
    learned = mask & (model == LEARNED)
    moved = model != REPLAY
    full = step_people(*args, walls, cfg, desired, learned)
    packed = step_people_packed(*_routed(args), walls, cfg, desired, learned, moved=moved)
    stepped = mask & moved.any(axis=1, where=mask, keepdims=True)
    for whole, part in zip(full, packed, strict=True):
        assert np.array_equal(whole[stepped], part[stepped])


def test_people_on_their_recorded_tracks_are_left_where_they_are() -> None:
    # The replay puts them where their recording says, at its velocity, after the step; the motion
    # step moves the others and leaves them standing where they were.
    walls = WallIndex(np.array([[-5.0, -5.0, 5.0, -5.0], [5.0, -5.0, 5.0, 5.0]]))
    args = _crowd(1)
    pos, vel, mask, model = args[0], args[1], args[4], args[5]
    new_pos, new_vel, _ = step_people(*args, walls, WorldConfig(dt=0.1))
    replayed = mask & (model == REPLAY)
    assert replayed.any() and (vel[replayed] != 0).all()
    assert np.array_equal(new_pos[replayed], pos[replayed]) and not new_vel[replayed].any()
    walking = mask & (model != REPLAY)
    assert (new_pos[walking] != pos[walking]).any(axis=1).all()
