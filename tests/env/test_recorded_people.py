"""Recorded people in the batched world (socialzoo.env.replay): replayed positions at the
recording's frames, entering and leaving, the hybrid people's reaction rule, the measures against
the recording, and both tasks with every adapter on a recorded scene."""

from __future__ import annotations

import dataclasses
import itertools

import gymnasium as gym
import numpy as np
import pytest

from socialzoo.core.config import WorldConfig
from socialzoo.core.walls import WallIndex
from socialzoo.data.tracks import Recording, Track
from socialzoo.env.core import BatchedCore
from socialzoo.env.replay import RecordingError
from socialzoo.humans.models import REPLAY, SOCIAL_FORCE, PeopleConfig
from socialzoo.scenarios.catalogue import FAMILIES, register_family
from socialzoo.scenarios.recorded import RecordedScene, people_scenario, replaced_scenario
from socialzoo.scenarios.recorded_people import RecordedPeople
from socialzoo.scenarios.scenario import Scenario

DT = 0.4


def _walker(person: int, first: int, a, b, speed: float = 1.2) -> Track:
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = int(np.ceil(np.hypot(*(b - a)) / speed / DT)) + 1
    return Track(person, first, np.linspace(a, b, n))


def _recording(count: int = 160, seed: int = 0) -> Recording:
    rng = np.random.default_rng(seed)
    tracks = [
        _walker(
            p, int(rng.integers(0, 300)), rng.uniform(-8, 8, 2), rng.uniform(-8, 8, 2), rng.uniform(0.8, 1.5)
        )
        for p in range(count)
    ]
    tracks.sort(key=lambda t: (t.first_frame, t.person))
    return Recording(
        name="synthetic",
        dt=DT,
        num_frames=max(t.last_frame for t in tracks) + 1,
        tracks=tuple(tracks),
        source="test",
    )


@pytest.fixture(scope="module")
def family() -> RecordedScene:
    name = "recorded_test_synthetic"
    fam = FAMILIES.get(name)
    if not isinstance(fam, RecordedScene):
        fam = register_family(RecordedScene(_recording(), name=name))
    return fam  # type: ignore[return-value]


def _core(scenarios: list[Scenario], models: str, dt: float = 0.1, **people) -> BatchedCore:
    world = WorldConfig(dt=dt)
    core = BatchedCore(
        len(scenarios),
        1,
        max(s.num_humans for s in scenarios),
        world,
        WallIndex(np.zeros((0, 4))),
        people=PeopleConfig(models=models, **people),
    )
    core.reset_rows(np.arange(len(scenarios)), scenarios)
    return core


def _two_walkers(robot_start=(50.0, 50.0)) -> Scenario:
    """A person walking +x from (0, 0) from frame 0, another entering at frame 5 and leaving at 15."""
    tracks = np.full((2, 30, 2), np.nan)
    tracks[0, :25] = np.stack((np.arange(25) * 0.5, np.zeros(25)), -1)
    tracks[1, 5:16] = np.stack((np.full(11, 3.0), 5.0 - np.arange(11) * 0.4), -1)
    recorded = RecordedPeople(dt=DT, tracks=tracks)
    start = np.array([[*robot_start, 0.0]])
    return people_scenario(recorded, start, start + [[1.0, 0.0, 0.0]], seed=3, family="test")


def test_replay_is_the_recording_at_every_frame() -> None:
    scenario = _two_walkers()
    core = _core([scenario], "replay")
    tracks = scenario.recorded.tracks
    for step in range(1, 30 * 4):
        core.step(np.zeros((1, 1, 2)))
        if step % 4:
            continue
        frame = step // 4
        present = ~np.isnan(tracks[:, frame, 0])
        s = core.state
        assert np.array_equal(s.human_mask[0, :2], present), frame
        err = np.abs(s.human_pos[0, :2][present] - tracks[present, frame]).max(initial=0.0)
        assert err < 0.01, (frame, err)  # within 1 cm of the file (here exact)
        assert (s.human_model[0, :2] == REPLAY).all()
    # Between frames: linear interpolation, with the segment's velocity.
    core = _core([scenario], "replay")
    for _ in range(2):
        core.step(np.zeros((1, 1, 2)))
    np.testing.assert_allclose(core.state.human_pos[0, 0], [0.25, 0.0], atol=1e-12)
    np.testing.assert_allclose(core.state.human_vel[0, 0], [1.25, 0.0], atol=1e-12)


def test_a_modelled_person_enters_when_recorded_and_leaves_at_its_route_end() -> None:
    scenario = _two_walkers()
    core = _core([scenario], "sf")
    assert not core.state.human_mask[0, 1]
    seen = []
    for _ in range(300):
        core.step(np.zeros((1, 1, 2)))
        seen.append(bool(core.state.human_mask[0, 1]))
    first = seen.index(True)
    assert first + 1 == 5 * 4  # frame 5 at 0.1 s steps
    np.testing.assert_allclose(core.replay.exit_at[0, 1] > 0, True)
    assert not seen[-1]  # left at its route's end
    assert core.state.human_model[0, 1] == SOCIAL_FORCE


def test_hybrid_people_leave_their_track_only_when_a_robot_comes_near() -> None:
    far = _core([_two_walkers((50.0, 50.0))], "hybrid:sf")
    near = _core([_two_walkers((6.0, 0.0))], "hybrid:sf")  # on the first walker's line
    for _ in range(40):
        far.step(np.zeros((1, 1, 2)))
        near.step(np.zeros((1, 1, 2)))
    assert (far.state.human_model[0, :2] == REPLAY).all()
    assert np.isnan(far.replay.reacted_at[0]).all()
    reacted = near.replay.reacted_at[0, 0]
    # The walker meets the robot's disc within react_time (2 s) of reaching ~2.4 m before it.
    assert 0.0 < reacted < 10.0
    assert near.state.human_model[0, 0] == SOCIAL_FORCE
    # The rule: a robot within react_radius or a meeting within react_time.
    walker_at = reacted * 1.25
    assert 6.0 - walker_at <= 1.25 * 2.0 + 0.6 + 1e-6
    with pytest.raises(ValueError, match="react_radius"):
        PeopleConfig(models="hybrid:sf", react_radius=-1.0)


def test_the_recorded_distance_left_starts_where_the_person_reacted() -> None:
    # The walker reacts at 2.5 s, a quarter into the segment of frames 6-7 (x = 3.125 m): its
    # recorded way to its last frame (x = 12 m) is 8.875 m, not the 9 m from frame 6.
    near = _core([_two_walkers((6.0, 0.0))], "hybrid:sf")
    for _ in range(40):
        near.step(np.zeros((1, 1, 2)))
    reacted = near.replay.reacted_at[0, 0]
    assert (reacted / DT) % 1.0 > 0.0  # between frames
    assert near.replay.recorded_left[0, 0] == pytest.approx(12.0 - 1.25 * reacted, abs=1e-9)


def test_a_reacting_persons_walk_counts_from_its_reaction_to_the_step_it_left_in() -> None:
    # With a radius this wide the walker reacts at the end of the first step (x = 0.125 m), having
    # walked its track during it: nothing walked off it yet, and its extra distance is 0 (its way
    # left is straight). Then every step's move counts until the one in which it left, the model
    # moving it there before it leaves.
    core = _core([_two_walkers()], "hybrid:sf", react_radius=1000.0)
    core.step(np.zeros((1, 1, 2)))
    assert core.replay.reacted_at[0, 0] == pytest.approx(0.1)
    assert core.replay.walked[0, 0] == 0.0
    (summary,) = core.replay.summaries([0], [np.nan])
    assert summary["people_reacting"] == 1
    assert summary["reacting_extra_distance"] == pytest.approx(0.0, abs=1e-12)
    moves = 0.0
    for _ in range(200):
        before = core.state.human_pos[0, 0].copy()
        core.step(np.zeros((1, 1, 2)))
        moves += float(np.hypot(*(core.state.human_pos[0, 0] - before)))
        if core.replay.gone[0, 0]:
            break
    else:
        pytest.fail("the walker never left")
    assert core.replay.walked[0, 0] == pytest.approx(moves, abs=1e-9)


def test_a_reacting_person_is_counted_to_its_routes_end_whether_it_left_or_not() -> None:
    # A lone walker reacts at once (a wide radius) and walks its straight track on undisturbed by its
    # model. Still walking, it is counted to its route's end (the straight way left at its speed); it
    # leaves within the waypoint radius (1 m) of that end, 0.875 m short of it, and is counted to it
    # all the same: its measures read 0 before and after it left (after, they read -0.7 s and -0.875 m,
    # the way it did not walk, when one who left was counted to where it left).
    tracks = np.stack((np.arange(25) * 0.5, np.zeros(25)), -1)[None]
    start = np.array([[50.0, 50.0, 0.0]])
    scenario = people_scenario(
        RecordedPeople(dt=DT, tracks=tracks), start, start + [[1.0, 0.0, 0.0]], seed=3, family="test"
    )
    core = _core([scenario], "hybrid:sf", react_radius=1000.0)
    walking = None
    for _ in range(200):
        core.step(np.zeros((1, 1, 2)))
        (summary,) = core.replay.summaries([0], [np.nan])
        if core.replay.gone[0, 0]:
            break
        walking = summary
    else:
        pytest.fail("the walker never left")
    assert walking is not None and summary["people_reacting"] == 1
    for measures in (walking, summary):
        assert measures["reacting_extra_distance"] == pytest.approx(0.0, abs=1e-6)
        assert measures["reacting_time_lost"] == pytest.approx(0.0, abs=1e-6)
    assert core.replay.rest[0, 0] == pytest.approx(0.875)  # where it left, from its route's end


def _to_the_end(robot_start=(50.0, 50.0)) -> Scenario:
    """A person on every frame of a 10-frame recording, walking +x at 1.25 m/s, another on frames 2-9."""
    tracks = np.stack((np.arange(10) * 0.5, np.zeros(10)), -1)[None].repeat(2, 0)
    tracks[1, :, 1] = 3.0
    tracks[1, :2] = np.nan
    start = np.array([[*robot_start, 0.0]])
    return people_scenario(
        RecordedPeople(dt=DT, tracks=tracks), start, start + [[1.0, 0.0, 0.0]], seed=1, family="test"
    )


def test_everyone_leaves_when_the_recording_ends() -> None:
    core = _core([_to_the_end()], "replay")
    for _ in range(9 * 4):
        core.step(np.zeros((1, 1, 2)))
    assert core.state.human_mask[0, 0]  # on the last frame
    core.step(np.zeros((1, 1, 2)))
    assert not core.state.human_mask[0, 0]  # past it: no frame after it is recorded


@pytest.mark.parametrize("humans", ["replay", "hybrid:sf"])
def test_a_recorded_row_plays_the_same_whatever_else_its_batch_holds(humans: str) -> None:
    # Row 0 alone, and beside a row whose recording is longer: the same world and measures bit for
    # bit, also past the end of row 0's recording (the longer one once kept row 0's people there).
    walker = np.stack((np.linspace(-20.0, 20.0, 80), np.full(80, -9.0)), -1)[None]
    start = np.array([[50.0, 50.0, 0.0]])
    longer = people_scenario(
        RecordedPeople(dt=DT, tracks=walker), start, start + [[1.0, 0.0, 0.0]], seed=9, family="test"
    )
    alone = _core([_to_the_end((3.0, 0.0))], humans)
    batch = _core([_to_the_end((3.0, 0.0)), longer], humans)
    for step in range(14 * 4):
        alone.step(np.zeros((1, 1, 2)))
        batch.step(np.zeros((2, 1, 2)))
        for name in ("human_pos", "human_vel", "human_mask", "human_model"):
            assert np.array_equal(
                getattr(alone.state, name)[0], getattr(batch.state, name)[0], equal_nan=name == "human_pos"
            ), (
                step,
                name,
            )
    ended = alone.replay.summaries([0], [np.nan])[0]
    assert ended == pytest.approx(batch.replay.summaries([0], [np.nan])[0], nan_ok=True, rel=0, abs=0)
    if humans != "replay":
        assert ended["people_reacting"] == 1


def test_hybrid_people_do_not_react_to_a_robot_they_cannot_see() -> None:
    # docs/recorded.md: hybrid people react to the robot only if they can see it (robot_visible).
    scenario = _two_walkers((6.0, 0.0))  # on the first walker's line
    core = BatchedCore(
        1,
        1,
        scenario.num_humans,
        WorldConfig(dt=0.1),
        WallIndex(np.zeros((0, 4))),
        people=PeopleConfig(models="hybrid:sf"),
        robot_visible=False,
    )
    core.reset_rows(np.arange(1), [scenario])
    for _ in range(40):
        core.step(np.zeros((1, 1, 2)))
    assert np.isnan(core.replay.reacted_at[0]).all()
    assert (core.state.human_model[0, :2] == REPLAY).all()


def test_replay_needs_recorded_people() -> None:
    from socialzoo.scenarios.catalogue import get_family

    plain = get_family("frontal_approach").make(100)
    with pytest.raises(RecordingError, match="recorded"):
        _core([plain], "replay")


def test_the_replaced_scenario_and_its_json(family: RecordedScene) -> None:
    seed = family.case_seed("test", 0)
    scenario = family.make(seed)
    track = family.recording.tracks[family.track_of(seed)]
    np.testing.assert_array_equal(scenario.robot_starts[0, :2], track.positions[0])
    np.testing.assert_array_equal(scenario.robot_goals[0, :2], track.positions[-1])
    assert scenario.recorded.time_limit >= 10.0
    assert Scenario.from_json(scenario.to_json()) == scenario
    again = replaced_scenario(family.recording, family.track_of(seed), seed=seed, family=family.name)
    assert again == scenario
    test, val, train = (set(family.track_splits[k].tolist()) for k in ("test", "val", "train"))
    assert not (test & val or test & train or val & train) and train


def test_an_episode_with_nobody_else_in_it_and_its_json(tmp_path) -> None:
    # A recording of one's own may be quiet: nobody else is seen during the robot's budget, so the
    # episode has no person slots. Its JSON wrote the tracks as [], which read back as shape (0,) and
    # was refused ("RecordedPeople.tracks must have 3 dimensions"), so the scenario did not round-trip.
    alone = Recording(
        name="alone", dt=DT, num_frames=21, tracks=(_walker(1, 0, (0, 0), (8, 0), 1.0),), source="t"
    )
    scenario = replaced_scenario(alone, 0, seed=1000, family="test")
    assert scenario.num_humans == 0 and scenario.recorded.tracks.shape == (0, 21, 2)
    path = scenario.save(tmp_path / "alone.json")
    assert Scenario.load(path) == scenario
    assert Scenario.load(path).recorded.tracks.shape == (0, 21, 2)


@pytest.mark.parametrize("models", ["replay", "hybrid:sf", "sf"])
def test_counterfactual_people_are_refused_among_recorded_people(family: RecordedScene, models: str) -> None:
    # PeopleConfig.counterfactual steps each row's twin without the robot, but not the recording: its
    # replayed people stood still or walked off their tracks and nobody entered, so with people replaying
    # (who ignore the robot) Recorded-v3 read people_time_lost 3.0 s and people_extra_distance 9.2 m on
    # zara1's test case 1 where both are 0. The recording is the world without the robot; its measures
    # (docs/recorded.md) compare with it.
    from socialzoo.env.config import EnvConfig

    people = {"models": models, "counterfactual": True}
    with pytest.raises(ValueError, match=r"counterfactual.*recorded"):
        EnvConfig(family=family.name, people=PeopleConfig(**people))
    with pytest.raises(ValueError, match=r"counterfactual.*recorded"):
        gym.make("socialzoo/Recorded-v4", family=family.name, people=people)
    scenario = _two_walkers()
    core = BatchedCore(
        1, 1, 2, WorldConfig(dt=0.1), WallIndex(np.zeros((0, 4))), people=PeopleConfig(**people)
    )
    with pytest.raises(ValueError, match=r"counterfactual.*recorded"):
        core.reset_rows(np.arange(1), [scenario])
    assert core.state is None  # refused before anything was written


def test_groups_among_recorded_people_are_companions_who_keep_their_own_routes() -> None:
    # "groups" on a recorded scene grouped people in slot order, strangers entering far apart and at other
    # times, and gave each member its leader's route: on zara1 a person entering at (0.2, 3.9) for
    # (15.1, 4.9) was sent back to (0.1, 6.9). docs/recorded.md: a model walks each recorded person from
    # its entry along its own route. Now the people who enter together (the same frame, within 1.2 m, with
    # velocities within 0.5 m/s) walk as a group, each along its own route.
    from socialzoo.env.people import People
    from socialzoo.scenarios.recorded import open_area_map

    tracks = np.full((5, 40, 2), np.nan)
    ahead = np.arange(30)[:, None] * np.array([0.5, 0.0])
    tracks[0, 2:32] = np.array([0.0, 0.0]) + ahead  # a couple entering at frame 2 side by side...
    tracks[1, 2:32] = np.array([0.0, 0.8]) + ahead
    tracks[2, 2:32] = np.array([0.0, 5.0]) + ahead  # ... someone entering then, 5 m away
    tracks[3, 2:32] = np.array([0.3, -0.6]) - ahead  # ... and beside them, walking the other way
    tracks[4, 9:39] = np.array([0.0, 0.4]) + ahead  # ... and later where they entered
    start = np.array([[50.0, 50.0, 0.0]])
    scenario = people_scenario(
        RecordedPeople(dt=DT, tracks=tracks), start, start + [[1.0, 0.0, 0.0]], seed=3, family="test"
    )
    walls = open_area_map(_recording(count=20), "groups_test")
    people = People(PeopleConfig(models="groups"), WorldConfig(dt=0.1), 1, 1, 5, walls.wall_index, walls)
    (grouped,), _ = people.prepare([scenario])
    assert grouped.human_group.tolist() == [0, 0, -1, -1, -1]
    for a, b in zip(grouped.human_routes, scenario.human_routes, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(grouped.human_spawn, scenario.human_spawn)
    np.testing.assert_array_equal(grouped.human_speed, scenario.human_speed)


@pytest.mark.parametrize("models", ["sf", "orca"])
def test_a_modelled_person_seen_on_one_frame_enters_where_it_was_seen(models: str) -> None:
    # A tracker's one-frame detection (a person on one row of a track file), or a person whose whole track
    # falls between two world steps: a model walks it from its recorded entry. At 0.25 s steps the row of
    # frame 3 (1.2 s) is first reached at 1.25 s, between frames, where the next frame is not recorded: the
    # person entered at NaN and stayed present there, so every observation of the robot held NaN.
    tracks = np.full((3, 30, 2), np.nan)
    tracks[0, 3] = (4.0, 3.0)  # one frame
    tracks[1, :25] = np.stack((np.arange(25) * 0.5, np.zeros(25)), -1)
    tracks[2, 10:12] = ((1.0, -2.0), (1.01, -2.0))  # two frames, both between steps of 1.2 s (3.6, 4.8 s)
    start = np.array([[50.0, 50.0, 0.0]])
    scenario = people_scenario(
        RecordedPeople(dt=DT, tracks=tracks), start, start + [[1.0, 0.0, 0.0]], seed=3, family="test"
    )
    for dt, slot, entry in ((0.25, 0, (4.0, 3.0)), (1.2, 2, (1.01, -2.0))):
        core = _core([scenario], models, dt=dt)
        seen = []
        for _ in range(round(12.0 / dt)):
            core.step(np.zeros((1, 1, 2)))
            state = core.state
            assert np.isfinite(state.human_pos[0][state.human_mask[0]]).all()
            if state.human_mask[0, slot]:
                seen.append(state.human_pos[0, slot].copy())
        # It enters at its recorded place and leaves there: its route is that place.
        assert seen and np.hypot(*(seen[0] - entry)) < 0.5
        assert not core.state.human_mask[0, slot]


def test_a_person_split_by_a_gap_is_in_one_split() -> None:
    # A gap longer than MAX_GAP_FRAMES splits a person into two tracks with one person id; the tracks
    # were split apart, so the robot could train in the place of a person it is tested in place of.
    from socialzoo.scenarios.recorded import split_tracks

    tracks = []
    for track in _recording(count=120).tracks:
        half = len(track.positions) // 2
        if track.person % 2 or half < 12:
            tracks.append(track)
            continue
        tracks.append(Track(track.person, track.first_frame, track.positions[:half]))
        tracks.append(Track(track.person, track.first_frame + half + 5, track.positions[half:]))
    tracks.sort(key=lambda t: (t.first_frame, t.person))
    rec = Recording(
        name="gaps",
        dt=DT,
        num_frames=max(t.last_frame for t in tracks) + 1,
        tracks=tuple(tracks),
        source="test",
    )
    splits = split_tracks(rec)
    persons = {k: {rec.tracks[i].person for i in v.tolist()} for k, v in splits.items()}
    assert persons["test"] and persons["val"] and persons["train"]
    assert not (persons["test"] & persons["val"] or persons["test"] & persons["train"])
    assert not persons["val"] & persons["train"]
    assert sum(len(v) for v in splits.values()) == len(set(np.concatenate(list(splits.values())).tolist()))


def test_the_robot_in_a_persons_place_never_meets_that_persons_other_track(tmp_path) -> None:
    # A tracker's gap splits a person in two tracks (one id): the robot in the place of the first is
    # that person, so its second track, which starts 0.5 m past the robot's goal while the robot's
    # budget runs, is nobody else of the episode (it was a person slot, the robot meeting itself).
    from socialzoo.data.tracks import read_tracks

    rows = [(f * 10, 1, f * 10 / 29, 0.0) for f in range(30)]  # (0, 0) to (10, 0)
    rows += [(f * 10, 1, 10.5 + (f - 35) * 0.38, 0.0) for f in range(35, 61)]  # after a 5-frame gap
    rows += [(f * 10, 2, 5.0, -6.0 + f * 0.2) for f in range(61)]  # somebody else
    path = tmp_path / "gap.txt"
    path.write_text("\n".join("\t".join(map(str, row)) for row in sorted(rows)))
    rec = read_tracks(path)
    first = next(k for k, t in enumerate(rec.tracks) if t.person == 1 and t.first_frame == 0)
    assert rec.persons.tolist().count(1) == 2
    scenario = replaced_scenario(rec, first, seed=0, family="test")
    assert scenario.recorded.persons.tolist() == [2]
    assert scenario.num_humans == 1


def test_the_open_area_map_is_the_registered_recordings(tmp_path, monkeypatch) -> None:
    # The map file is named after the family: a second recording registered under the same
    # name (docs/recorded.md's "recorded_mine") must get its own walls, not the first one's.
    from socialzoo.maps.map_file import load_map

    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))
    first = _recording(count=20)
    moved = dataclasses.replace(
        first, tracks=tuple(Track(t.person, t.first_frame, t.positions + 100.0) for t in first.tracks)
    )
    for recording in (first, moved, first):
        path = RecordedScene(recording, name="recorded_mine").open_map()
        walls = load_map(path).walls
        points = np.concatenate([t.positions for t in recording.tracks])
        assert walls[:, [0, 2]].min() < points[:, 0].min() and walls[:, [0, 2]].max() > points[:, 0].max()
        assert walls[:, [1, 3]].min() < points[:, 1].min() and walls[:, [1, 3]].max() > points[:, 1].max()
    assert [p.name for p in (tmp_path / "maps").iterdir()] == ["recorded_mine.json"]


def _read_only(monkeypatch, folder) -> None:
    """Every write below `folder` fails as on a read-only file system (the tests run as any user, root too)."""
    import os
    import pathlib

    def guard(call):
        def guarded(path, *args, **kwargs):
            mode = str(kwargs.get("mode", args[0] if args else "r"))
            writing = call.__name__ != "open" or any(c in mode for c in "wax+")
            if writing and pathlib.Path(path).resolve().is_relative_to(pathlib.Path(folder).resolve()):
                raise OSError(30, "Read-only file system", str(path))
            return call(path, *args, **kwargs)

        return guarded

    for name in ("mkdir", "open", "unlink", "touch"):
        monkeypatch.setattr(pathlib.Path, name, guard(getattr(pathlib.Path, name)))
    monkeypatch.setattr(os, "replace", guard(os.replace))


def test_the_open_area_map_is_read_from_a_read_only_cache(tmp_path, monkeypatch) -> None:
    # docs/data.md: a complete cache may be read-only (a shared folder). Recorded-v4 builds on the scene's
    # open-area map in that cache; it wrote the map again (a staged copy) on every env made, so a read-only
    # cache refused every env even with the current map in it.
    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path / "shared"))
    path = RecordedScene(_recording(count=20), name="recorded_mine").open_map()
    written = (tmp_path / "shared" / "maps" / "recorded_mine.json").read_bytes()
    _read_only(monkeypatch, tmp_path / "shared")
    assert RecordedScene(_recording(count=20), name="recorded_mine").open_map() == path
    assert (tmp_path / "shared" / "maps" / "recorded_mine.json").read_bytes() == written


def test_a_read_only_cache_without_the_open_area_map_writes_it_to_the_users_cache(
    tmp_path, monkeypatch
) -> None:
    # The shared read-only cache holds the recordings but no map yet (nobody who could write it played
    # the scene): the map goes to the user's own socialzoo cache folder instead.
    from socialzoo.maps.map_file import load_map

    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path / "shared"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "mine"))
    (tmp_path / "shared").mkdir()
    _read_only(monkeypatch, tmp_path / "shared")
    path = RecordedScene(_recording(count=20), name="recorded_mine").open_map()
    assert path == str(tmp_path / "mine" / "socialzoo" / "maps" / "recorded_mine.json")
    assert load_map(path).name == "recorded_mine"
    assert not (tmp_path / "shared" / "maps").exists()
    # Once the shared cache can be written, its map is written there (the user's copy is a fallback).
    monkeypatch.undo()
    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path / "shared"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "mine"))
    shared = RecordedScene(_recording(count=20), name="recorded_mine").open_map()
    assert shared == str(tmp_path / "shared" / "maps" / "recorded_mine.json")


def test_the_open_area_map_of_a_large_recording_keeps_its_graph_small() -> None:
    # A recording of one's own over a 150 m square (a plaza; or positions left in pixels) made a 2 m
    # grid of 5,900 nodes, whose all-pairs table (N^3) kept Recorded-v4's first reset busy for tens of
    # minutes (a 60 m square: 1,100 nodes, 15 s). Its spacing widens instead; a scene's own size keeps 2 m.
    from socialzoo.scenarios.recorded import MAX_OPEN_NODES, OPEN_SPACING, open_area_map

    corners = [Track(0, 0, np.linspace([0.0, 0.0], [4.0, 0.0], 10)), Track(1, 0, np.full((10, 2), 150.0))]
    large = Recording(name="plaza", dt=DT, num_frames=10, tracks=tuple(corners), source="test")
    m = open_area_map(large, "recorded_plaza")
    assert 0.9 * MAX_OPEN_NODES <= len(m.nodes) <= MAX_OPEN_NODES
    assert m.walls.min() == -3.0 and m.walls.max() == 153.0
    small = open_area_map(_recording(count=20), "recorded_small")
    spacings = np.abs(np.diff(small.nodes, axis=0))
    assert np.isclose(spacings[spacings > 0].min(), OPEN_SPACING)


@pytest.mark.parametrize("humans", ["replay", "hybrid:sf", "orca"])
def test_crowdnav_plays_a_recorded_scene_deterministically(family: RecordedScene, humans: str) -> None:
    from gymnasium.utils.env_checker import check_env

    def rollout() -> tuple[np.ndarray, dict]:
        env = gym.make("socialzoo/CrowdNavRecorded-v3", family=family.name, humans=humans)
        check_env(env.unwrapped, skip_render_check=True)
        obs, _ = env.reset(seed=4)
        trace = [obs]
        info: dict = {}
        for _ in range(60):
            obs, _, term, trunc, info = env.step(env.action_space.sample())
            trace.append(obs)
            if term or trunc:
                obs, _ = env.reset()
        env.action_space.seed(0)
        return np.stack(trace), info

    a, _ = rollout()
    b, _ = rollout()
    assert np.array_equal(a, b)


def test_crowdnav_takes_the_hybrid_reaction_rule(family: RecordedScene) -> None:
    from socialzoo.humans.models import REPLAY

    def walked_by_a_model(humans: object) -> tuple[int, int]:
        env = gym.make("socialzoo/CrowdNavRecorded-v3", family=family.name, humans=humans)
        env.reset(seed=0, options={"split": "test", "case": 0})
        env.step(np.zeros(2, dtype=np.float32))
        state = env.unwrapped.task.core.state
        present = state.human_mask[0]
        return int((state.human_model[0][present] != REPLAY).sum()), int(present.sum())

    everyone, present = walked_by_a_model({"models": "hybrid:orca", "react_radius": 1000.0})
    assert present > 1 and everyone == present
    by_default, _ = walked_by_a_model("hybrid:orca")
    assert by_default < present
    with pytest.raises(ValueError, match="react_radius must be >= 0"):
        gym.make("socialzoo/CrowdNavRecorded-v3", family=family.name, humans={"react_radius": -1.0})
    with pytest.raises(ValueError, match="known fields"):
        gym.make("socialzoo/CrowdNavRecorded-v3", family=family.name, humans={"radius": 2.0})


def test_the_task_id_commands_play_the_family_and_people_given(
    family: RecordedScene, tmp_path, capsys
) -> None:
    from socialzoo.cli import main

    config = ["--task-config", f"family={family.name}", "--task-config", 'humans={"models": "hybrid:orca"}']
    argv = ["benchmark", "--maps", "socialzoo/CrowdNavRecorded-v3", "--policies", "orca", "--trials", "3"]
    assert main([*argv, *config, "--out", str(tmp_path), "--no-figures"]) == 0
    table = (tmp_path / "crowdnav.md").read_text()
    assert f"family={family.name}" in table and "hybrid:orca" in table
    assert "| orca |" in table and "replaced person's time" in table
    page = tmp_path / "case.html"
    argv = ["replay", "--env", "socialzoo/CrowdNavRecorded-v3", "--policy", "orca", "--case", "1", *config]
    assert main([*argv, "--out", str(page)]) == 0
    assert f"family={family.name}" in page.read_text()
    assert "test case 1" in capsys.readouterr().out


def test_recorded_metrics_in_both_tasks(family: RecordedScene) -> None:
    env = gym.make("socialzoo/Recorded-v4", family=family.name, people={"models": "hybrid:sf"})
    env.reset(seed=0, options={"split": "test", "case": 0})
    for _ in range(5000):
        _, _, term, trunc, info = env.step(0)  # GoAlone
        if term or trunc:
            break
    metrics = info["metrics"]
    for key in ("person_time", "person_time_ratio", "person_path_deviation", "people_reacting"):
        assert key in metrics
    assert metrics["person_time"] > 0
    crowd = gym.make("socialzoo/CrowdNavRecorded-v3", family=family.name)
    crowd.reset(seed=0, options={"split": "test", "case": 0})
    for _ in range(500):
        _, _, term, trunc, info = crowd.step(np.zeros(2, dtype=np.float32))
        if term or trunc:
            break
    assert term or trunc
    assert info["episode"]["person_time"] > 0 if "episode" in info else True


@pytest.mark.parametrize(
    ("other", "drive", "walked_into"),
    [
        # Walks past the parked robot 0.595 m from its centre at 1.5 m/s: its closest approach, mid-step,
        # is within the 0.6 m of the radii, but no step ends with the two touching.
        ([(k, -2.4 + 0.6 * k, 0.595) for k in range(9)], 0.0, 1),
        # Stands 0.595 m beside the line the robot drives at 1 m/s, level with no step's end.
        ([(k, 0.595, -2.125) for k in range(20)], 1.0, 0),
    ],
)
def test_crowdnav_counts_the_people_who_walked_into_the_robot_among_the_collisions_it_judged(
    other: list[tuple[int, float, float]], drive: float, walked_into: int, tmp_path, monkeypatch
) -> None:
    # CrowdNavRecorded-v3 judges a collision by the closest approach during a step; its
    # people_walked_into_robot counted only contacts at the steps' ends, so a person walking past the
    # robot ended the episode in a collision with nobody counted (docs/recorded.md).
    from socialzoo.data.tracks import read_tracks

    robot = [(k, 0.0, -0.4 * k) for k in range(16)]  # the replaced person: 6 m in 6 s
    rows = sorted([(10 * k, 1, x, y) for k, x, y in robot] + [(10 * k, 2, x, y) for k, x, y in other])
    path = tmp_path / "tracks.txt"
    path.write_text("".join(f"{f}\t{p}\t{x:.4f}\t{y:.4f}\n" for f, p, x, y in rows))
    name = "recorded_test_walked_into"
    monkeypatch.setitem(FAMILIES, name, RecordedScene(read_tracks(path), name=name))
    env = gym.make("socialzoo/CrowdNavRecorded-v3", family=name, humans="replay")
    env.reset(seed=0)  # the one eligible track: the other person's lasts under 4 s or 2 m
    core = env.unwrapped.task.core
    for _ in range(40):
        _, _, term, trunc, info = env.step(np.array([drive, 0.0], dtype=np.float32))  # towards the goal
        state = core.state
        # No step ends with the two touching: the collision is the judgement's during a step.
        assert np.hypot(*(state.human_pos[0, 0] - state.robot_pose[0, 0, :2])) > 0.6
        if term or trunc:
            break
    assert term and info["metrics"]["collision"] == 1.0
    assert info["metrics"]["people_walked_into_robot"] == walked_into


def test_vector_parallel_and_torchrl_adapters_run_a_recorded_scene(family: RecordedScene) -> None:
    from pettingzoo.test import parallel_api_test

    from socialzoo.env.parallel import TaskParallelEnv
    from socialzoo.env.vector import TaskVectorEnv

    vec = TaskVectorEnv(4, task="crowdnav", family=family.name, humans="hybrid:orca", robot_visible=True)
    vec.reset(seed=1)
    for _ in range(20):
        vec.step(vec.action_space.sample())
    par = TaskParallelEnv(task="crowdnav", family=family.name, humans="replay", robot_visible=True)
    parallel_api_test(par, num_cycles=20)
    pytest.importorskip("torchrl")
    from torchrl.envs.utils import check_env_specs

    from socialzoo.env.torchrl_single import TaskTorchEnv

    check_env_specs(TaskTorchEnv(2, task="crowdnav", family=family.name, humans="replay"))


def _shared_slot() -> Scenario:
    """One slot holding two people one after another (frames 0-10, then 40-60), another slot alone."""
    tracks = np.full((2, 70, 2), np.nan)
    tracks[0, 0:11] = np.stack((np.arange(11) * 0.5, np.zeros(11)), -1)
    tracks[0, 40:61] = np.stack((np.full(21, -3.0), np.arange(21) * 0.4), -1)
    tracks[1, 0:70] = np.stack((np.full(70, 8.0), np.arange(70) * 0.1), -1)
    start = np.array([[50.0, 50.0, 0.0]])
    return people_scenario(
        RecordedPeople(dt=DT, tracks=tracks), start, start + [[1.0, 0.0, 0.0]], seed=5, family="test"
    )


@pytest.mark.parametrize("dt", [0.4, 0.04, 1 / 30])
def test_slot_rest_and_route_stride_are_seconds_at_any_frame_rate(dt: float) -> None:
    """A recording at another frame rate (25 Hz, 30 Hz) keeps the rules' seconds: people share a slot
    only 10 s apart, and route points are 1.6 s apart (at 2.5 Hz: 25 and 4 frames, as always)."""

    def walker(person: int, first: int, seconds: float, y: float) -> Track:
        n = round(seconds / dt) + 1
        return Track(person, first, np.stack((np.linspace(0.0, 6.0, n), np.full(n, y)), -1))

    leaves = round(8 / dt)  # person 1 leaves 8 s in; person 2 enters 12 s after that
    tracks = (walker(0, 0, 40.0, 5.0), walker(1, 0, 8.0, 0.0), walker(2, leaves + round(12 / dt), 8.0, 0.0))
    rec = Recording(name="rate", dt=dt, num_frames=tracks[0].last_frame + 1, tracks=tracks, source="test")
    shared = replaced_scenario(rec, 0, seed=0, family="test").recorded
    assert shared.num_people == 1  # 12 s apart: one slot
    stride = round(1.6 / dt)
    np.testing.assert_array_equal(shared.slot_routes[0][:3], [0, stride, 2 * stride])
    close = (tracks[0], tracks[1], walker(2, leaves + round(6 / dt), 8.0, 0.0))
    rec = dataclasses.replace(rec, tracks=close)
    assert replaced_scenario(rec, 0, seed=0, family="test").recorded.num_people == 2  # 6 s apart: two


def test_a_shared_slot_replays_each_person_at_their_frames() -> None:
    scenario = _shared_slot()
    assert scenario.recorded.occupants.entry[0, :2].tolist() == [0, 40]
    core = _core([scenario], "replay")
    tracks = scenario.recorded.tracks
    for step in range(1, 69 * 4):
        core.step(np.zeros((1, 1, 2)))
        if step % 4 == 0:
            frame = step // 4
            present = ~np.isnan(tracks[:, frame, 0])
            assert np.array_equal(core.state.human_mask[0, :2], present), frame
            assert (
                np.abs(core.state.human_pos[0, :2][present] - tracks[present, frame]).max(initial=0.0) < 0.01
            )


def test_the_second_person_of_a_shared_slot_walks_its_own_route() -> None:
    core = _core([_shared_slot()], "sf")
    mask = []
    for _ in range(65 * 4):
        core.step(np.zeros((1, 1, 2)))
        mask.append(bool(core.state.human_mask[0, 0]))
        if len(mask) == 45 * 4:  # the second person walks up from (-3, 0) towards (-3, 8)
            assert core.state.human_pos[0, 0, 0] == pytest.approx(-3.0, abs=0.5)
            assert core.state.human_pos[0, 0, 1] > 0.5
    assert mask[40 * 4 - 1] and mask[4]  # both entered
    assert not mask[35 * 4]  # the first had left before the second entered


def test_a_reacting_person_whose_slot_is_taken_before_it_left_is_counted_to_its_routes_end() -> None:
    # The slot's first person (1.25 m/s, recorded exit 4 s) reacts to a robot parked on its line and is
    # held there until the slot's second person enters (16 s): its time counts to then plus the straight
    # way left at its speed, as its distance counts that way (its time lacked it).
    scenario = dataclasses.replace(_shared_slot(), robot_starts=np.array([[4.6, 0.0, 0.0]]))
    core = _core([scenario], "hybrid:orca")
    for _ in range(41 * 4):
        runner = core.replay
        rest, walked, left = (
            float(runner.rest[0, 0]),
            float(runner.walked[0, 0]),
            float(runner.recorded_left[0, 0]),
        )
        still_walking = np.isnan(runner.exit_at[0, 0]) and not np.isnan(runner.reacted_at[0, 0])
        core.step(np.zeros((1, 1, 2)))
        if runner.occupant[0, 0] == 1:
            break
    else:
        pytest.fail("the second person never entered")
    assert still_walking and rest > 0.5
    count, lost, extra = runner.folded[0]
    assert count == 1
    assert lost == pytest.approx(16.0 + rest / 1.25 - 4.0, abs=1e-9)
    assert extra == pytest.approx(walked + rest - left, abs=1e-9)


def test_a_person_who_enters_and_reacts_at_once_has_walked_nothing_yet() -> None:
    # The second person of the shared slot enters at (-3, 0) beside the robot and reacts on its
    # first step; the slot's position before that step was the first person's, 8 m away.
    scenario = dataclasses.replace(_shared_slot(), robot_starts=np.array([[-3.0, 0.8, 0.0]]))
    core = _core([scenario], "hybrid:sf")
    for _ in range(65 * 4):
        before = core.state
        core.step(np.zeros((1, 1, 2)))
        if not np.isnan(core.replay.reacted_at[0, 0]):
            break
    else:
        pytest.fail("the second person never reacted")
    assert core.replay.occupant[0, 0] == 1
    assert before.human_pos[0, 0, 0] > 4.0  # the slot held the first person, who left near (5, 0)
    assert core.replay.walked[0, 0] == 0.0


def _trace(core: BatchedCore, row: int, steps: int) -> list[np.ndarray]:
    """Row `row`'s people (positions, velocities, presence, models) and recorded metrics over `steps`
    steps of robots standing still."""
    out = []
    for _ in range(steps):
        core.step(np.zeros((core.batch_size, 1, 2)))
        s = core.state
        out += [
            s.human_pos[row].copy(),
            s.human_vel[row].copy(),
            s.human_mask[row].copy(),
            s.human_model[row].copy(),
        ]
    metrics = core.replay.summaries([row], [float("nan")])[0]
    return out + [np.array([metrics[k] for k in sorted(metrics)])]


@pytest.mark.parametrize(("humans", "before"), [("hybrid:sf", "recorded"), ("sf", "plain")])
def test_a_reset_row_plays_as_a_fresh_one(family: RecordedScene, humans: str, before: str) -> None:
    """A recorded row reset after another episode (a recorded one in which people reacted and left
    their slots; or a scenario without recordings) holds and plays exactly what a row reset only
    once does (ReplayRunner.reset clears everything the last episode left)."""
    new, old = family.make(1000), family.make(1008)
    if before == "plain":
        old = Scenario(
            map_name="arena", seed=5, robot_starts=[[0.0, 0.0, 0.0]], robot_goals=[[4.0, 0.0, 0.0]],
            human_spawn=[[1.0, 1.0], [2.0, -1.0]], human_start_index=[-1, -1], human_goal_index=[-1, -1],
            human_routes=(np.array([[1.0, 1.0], [3.0, 1.0]]), np.array([[2.0, -1.0], [2.0, 3.0]])),
            human_speed=[1.0, 1.2],
        )  # fmt: skip
    h = max(new.num_humans, old.num_humans, family.make(1001).num_humans)

    def core(scenarios: list[Scenario]) -> BatchedCore:
        c = BatchedCore(
            len(scenarios),
            1,
            h,
            WorldConfig(dt=0.1),
            WallIndex(np.zeros((0, 4))),
            people=PeopleConfig(models=humans),
        )
        c.reset_rows(np.arange(len(scenarios)), scenarios)
        return c

    used, fresh = core([family.make(1001), old]), core([new])
    _trace(used, 1, 200)
    if before == "recorded":
        assert used.replay.folded[1, 0] > 0  # a reacting person left its slot
    used.reset_rows(np.array([1]), [new])
    bank = used.replay.bank
    assert bank.recording(bank.entry_of[1]) is new.recorded
    assert (bank.people[1], bank.frames[1]) == (fresh.replay.bank.people[0], fresh.replay.bank.frames[0])
    for name, array in vars(fresh.replay).items():
        if isinstance(array, np.ndarray) and array.shape[:1] == (1,):
            # The used runner's axes may be longer: what lies beyond the recording is not read.
            block = (1,) + tuple(slice(0, n) for n in array.shape[1:])
            np.testing.assert_array_equal(getattr(used.replay, name)[block], array[0], err_msg=name)
    # Over the episode's time budget (a task ends it there).
    steps = int(new.recorded.time_limit / 0.1)
    for a, b in zip(_trace(used, 1, steps), _trace(fresh, 0, steps), strict=True):
        np.testing.assert_array_equal(a, b)


def test_rows_sharing_a_recording_read_one_bank_entry(family: RecordedScene) -> None:
    """Rows whose scenarios hold one recording point at one entry of the runner's bank, which holds it
    frame-major; a reset from a recording the bank holds copies nothing (socialzoo.env.recording_bank)."""
    pool = len(family.track_splits["train"])
    first, again, other = family.make(1000), family.make(1000 + pool), family.make(1001)
    assert first.recorded is again.recorded and first.seed != again.seed
    core = _core([first, again, other, other], "hybrid:sf")
    bank = core.replay.bank
    assert bank.entries == 2
    assert bank.entry_of[0] == bank.entry_of[1] != bank.entry_of[2] == bank.entry_of[3]
    assert bank.point_at[0] == bank.point_at[1] and bank.slot_at[0] == bank.slot_at[1]
    rec = first.recorded
    at, n, t = bank.point_at[0], rec.num_people, rec.num_frames
    assert (bank.people[0], bank.frames[0]) == (n, t)
    np.testing.assert_array_equal(bank.pos[at : at + t * n].reshape(t, n, 2), rec.tracks.transpose(1, 0, 2))
    np.testing.assert_array_equal(
        bank.vel[at : at + t * n].reshape(t, n, 2), rec.velocities.transpose(1, 0, 2)
    )
    held = {name: getattr(bank, name) for name in ("pos", "vel", "entry", "speed", "route_frame", "robot")}
    kept = {name: array.copy() for name, array in held.items()}
    core.reset_rows(np.array([3]), [family.make(1000 + 2 * pool)])
    assert bank.entry_of[3] == bank.entry_of[0] and bank.point_at[3] == at and bank.entries == 2
    for name, array in held.items():
        assert getattr(bank, name) is array, name  # not reallocated
        np.testing.assert_array_equal(array, kept[name], err_msg=name)  # nor written
    # The runner's own arrays are per slot and robot, none per frame: a longer recording adds nothing there.
    frames = {k: v.shape for k, v in vars(core.replay).items() if isinstance(v, np.ndarray)}
    assert all(
        shape[1:] in {(), (core.max_humans,), (1,), (1, core.max_humans), (3,)} for shape in frames.values()
    )


def test_the_bank_forgets_recordings_nobody_holds(family: RecordedScene) -> None:
    """A family that builds a new recording for every reset keeps the bank bounded: once the recordings
    that no row plays and nobody holds outweigh the others, they are dropped, and the rows play on
    exactly as before. A family that keeps its recordings has each added once and never dropped."""
    rows, h = 4, family.max_people
    fresh_scenario = lambda seed: replaced_scenario(  # noqa: E731
        family.recording, family.track_of(seed), seed=seed, family=family.name
    )

    def core(scenarios: list[Scenario]) -> BatchedCore:
        c = BatchedCore(
            len(scenarios), 1, h, WorldConfig(dt=0.1), WallIndex(np.zeros((0, 4))),
            people=PeopleConfig(models="hybrid:sf"),
        )  # fmt: skip
        c.reset_rows(np.arange(len(scenarios)), scenarios)
        return c

    used = core([fresh_scenario(1000 + k) for k in range(rows)])
    bank = used.replay.bank
    largest, sizes, entries = 0, [], []
    for k in range(rows, 160):
        used.reset_rows(np.array([k % rows]), [fresh_scenario(1000 + k)])
        largest = max(largest, int(bank._bytes[bank.entry_of[k % rows]]))
        for _ in range(3):
            used.step(np.zeros((rows, 1, 2)))
        assert all(
            bank.recording(e) is s.recorded for e, s in zip(bank.entry_of, used.scenarios, strict=True)
        )
        sizes.append(bank.nbytes)
        entries.append(bank.entries)
    # The rows' recordings, at most as much garbage and the latest, in arrays at most twice that (they double).
    assert max(sizes) <= 2 * (2 * rows + 1) * largest + 64 * 1024
    assert max(entries) < 40 and min(entries[60:]) < max(entries)  # dropped, again and again
    # After many compactions a row plays what it plays in a fresh batch, bit for bit.
    last = fresh_scenario(1160)
    used.reset_rows(np.array([0]), [last])
    alone = core([last])
    for a, b in zip(_trace(used, 0, 150), _trace(alone, 0, 150), strict=True):
        np.testing.assert_array_equal(a, b)
    # The family's own scenarios are kept (RecordedScene.make): ten recordings drawn again and again
    # are added once each, and nothing is dropped (univ's rows once re-added most of what they drew).
    kept = core([family.make(1000 + k) for k in range(rows)])
    for k in range(200):
        kept.reset_rows(np.array([k % rows]), [family.make(1000 + (k * 7) % 10)])
    assert kept.replay.bank.entries == 10 and kept.replay.bank.used_bytes[1] == 0


@pytest.mark.parametrize("copy_env", ["pickle", "deepcopy"])
@pytest.mark.parametrize("humans", ["replay", "hybrid:orca"])
def test_a_copied_recorded_vector_env_plays_on_as_the_original(
    family: RecordedScene, humans: str, copy_env: str
) -> None:
    """A recorded VectorEnv pickled mid-episode (what a worker process receives) or deep-copied steps on
    as the original, bit for bit, through autoresets: the bank's weak references and its pointer's
    column views (entry_of ...) are rebuilt, not copied."""
    import copy
    import pickle

    from socialzoo.env.vector import TaskVectorEnv

    rng = np.random.default_rng(0)
    vec = TaskVectorEnv(4, task="crowdnav", family=family.name, humans=humans, robot_visible=True)
    vec.reset(seed=1)
    for _ in range(30):
        vec.step(rng.uniform(-1, 1, (4, 2)).astype(np.float32))
    other = pickle.loads(pickle.dumps(vec)) if copy_env == "pickle" else copy.deepcopy(vec)
    bank = other.task.core.replay.bank
    assert np.shares_memory(bank.entry_of, bank.pointer)
    for action in rng.uniform(-1, 1, (150, 4, 2)).astype(np.float32):
        for a, b in zip(vec.step(action), other.step(action), strict=True):
            if isinstance(a, np.ndarray):
                np.testing.assert_array_equal(a, b)


def test_a_compacted_core_plays_its_recorded_rows_on(family: RecordedScene) -> None:
    """Compaction (socialzoo.env.compaction) keeps recorded rows' episodes: the new core's bank holds
    the kept rows' recordings, and each kept row steps on exactly as in the full batch."""
    from socialzoo.env.compaction import compact_core

    full = _core([family.make(1000 + k) for k in range(4)], "hybrid:sf")
    for _ in range(40):
        full.step(np.zeros((4, 1, 2)))
    keep = [3, 1]
    small = compact_core(full, keep)
    assert small.replay.bank.entries == 2
    for _ in range(120):
        full.step(np.zeros((4, 1, 2)))
        small.step(np.zeros((2, 1, 2)))
        for name in ("human_pos", "human_vel", "human_mask", "human_model"):
            np.testing.assert_array_equal(
                getattr(small.state, name), getattr(full.state, name)[keep], err_msg=name
            )
    for kept, whole in zip(
        small.replay.summaries([0, 1], [np.nan] * 2), full.replay.summaries(keep, [np.nan] * 2), strict=True
    ):
        assert kept == pytest.approx(whole, nan_ok=True, rel=0, abs=0)


def _plain_scenario() -> Scenario:
    """A scenario without recorded people: one person walking 2 m in the arena."""
    return Scenario(
        map_name="arena", seed=5, robot_starts=[[0.0, 0.0, 0.0]], robot_goals=[[4.0, 0.0, 0.0]],
        human_spawn=[[1.0, 1.0]], human_start_index=[-1], human_goal_index=[-1],
        human_routes=(np.array([[1.0, 1.0], [3.0, 1.0]]),), human_speed=[1.0],
    )  # fmt: skip


def test_a_row_reset_from_a_recording_to_a_plain_scenario_gets_the_tasks_budget(
    family: RecordedScene,
) -> None:
    plain = _plain_scenario()
    recorded = family.make(1000)
    core = _core([recorded, plain], "sf")
    assert core.time_limit[0] == recorded.recorded.time_limit and core.time_limit[1] == np.inf
    core.reset_rows(np.array([0]), [plain])
    assert core.time_limit[0] == np.inf


@pytest.mark.parametrize("env_id", ["socialzoo/Recorded-v4", "socialzoo/CrowdNavRecorded-v3"])
def test_a_long_budget_is_the_episodes_whatever_the_tasks_default_limit(
    env_id: str, monkeypatch, tmp_path
) -> None:
    # A person who lingers 150 s and walks 2 m: a 300 s budget (docs/recorded.md). The recorded ids cut
    # every budget at their task's default limit (min with it): 80 s in Recorded-v3 (max_steps 3200 of
    # 0.025 s), 200 s in CrowdNavRecorded-v2; 18 of univ's and zara2's test cases have longer budgets.
    lingering = _walker(1, 0, (0.0, 0.0), (2.0, 0.0), speed=2.0 / 150.0)
    rec = Recording(
        name="lingering", dt=DT, num_frames=lingering.last_frame + 1, tracks=(lingering,), source="t"
    )
    name = "recorded_test_lingering"
    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))  # Recorded's open-area map goes there
    monkeypatch.setitem(FAMILIES, name, RecordedScene(rec, name=name))
    env = gym.make(env_id, family=name)
    env.reset(seed=0)  # the one track: the training split's
    task = env.unwrapped.task
    assert task.core.time_limit[0] == pytest.approx(300.0)
    crowdnav = "CrowdNav" in env_id
    action = np.zeros(2, dtype=np.float32) if crowdnav else 1  # CrowdNav's robot and the halting sub-policy

    def ended_at(seconds: float) -> bool:
        if crowdnav:  # CrowdNav's rule: a step starting 1 s before the limit or later ends the episode
            task.time[:] = seconds - 1.0
        else:
            task.core.state.step_count[:] = round(seconds / task.config.dt) - 1
        _, _, terminated, truncated, _ = env.step(action)
        assert not terminated
        return truncated

    assert not ended_at(250.0)
    assert ended_at(300.0)


def test_a_recorded_row_reset_beside_a_plain_one_starts_as_reset_alone(family: RecordedScene) -> None:
    """A reset of rows with and without recordings gives each recorded row its own slots' models
    (its kinds, not its neighbour's) and walks it as a reset of that row alone does."""
    plain = _plain_scenario()
    recorded = family.make(1003)
    mixed = _core([plain, recorded], "sf@0.5+orca@0.5")
    alone = _core([recorded], "sf@0.5+orca@0.5")
    for name in ("follows", "reacts", "then", "occupant", "on_track"):
        np.testing.assert_array_equal(getattr(mixed.replay, name)[1], getattr(alone.replay, name)[0], name)
    for _ in range(30):
        mixed.step(np.zeros((2, 1, 2)))
        alone.step(np.zeros((1, 1, 2)))
    for name in ("human_pos", "human_mask", "human_model"):
        np.testing.assert_array_equal(getattr(mixed.state, name)[1], getattr(alone.state, name)[0], name)
    assert not mixed.replay.recorded[0] and mixed.time_limit[0] == np.inf


def _vector_digests(family_name: str, humans: str) -> tuple[str, str]:
    """sha256 prefixes of a seeded VectorEnv rollout of the synthetic scene: (observations,
    rewards and end flags; the recorded metrics of the episodes that ended)."""
    import hashlib

    from socialzoo.env.vector import TaskVectorEnv

    env = TaskVectorEnv(8, task="crowdnav", family=family_name, humans=humans, robot_visible=True)
    obs, _ = env.reset(seed=11)
    rng = np.random.default_rng(2)
    core, metrics = hashlib.sha256(obs.tobytes()), hashlib.sha256()
    for step in range(80):
        action = rng.uniform(-1.0, 1.0, (8, 2)).astype(np.float32) * (1.0 if step % 3 == 0 else 0.3)
        obs, reward, term, trunc, info = env.step(action)
        for array in (obs, reward, term, trunc):
            core.update(np.ascontiguousarray(array).tobytes())
        if "final_info" in info:
            ended = info["final_info"]["metrics"]
            for key in ("person_path_deviation", "people_walked_into_robot", "people_reacting",
                        "reacting_time_lost", "reacting_extra_distance"):  # fmt: skip
                metrics.update(np.ascontiguousarray(ended[key]).tobytes())
    return core.hexdigest()[:16], metrics.hexdigest()[:16]


# Recorded with the numpy replay before its kernels (the metrics after the fixes of
# reacting_extra_distance, which changed nothing else: the jump of a person entering and reacting
# in one step, then the recorded distance left from where the person is, the row's own frames only,
# then the walk counted from the reaction to the step the person left in, then the people who walked
# into the robot among the contacts the CrowdNav task judges during a step, then a person who left
# counted to its route's end): the kernels keep every value bit for bit.
GOLDEN_RECORDED = {
    "replay": ("e5e46e7a1b5ade60", "6abf74028faf97ba"),
    "hybrid:orca": ("299387c2d98710da", "38f3195720842091"),
}


@pytest.mark.parametrize("humans", sorted(GOLDEN_RECORDED))
def test_recorded_rollouts_stay_bit_for_bit(family: RecordedScene, humans: str) -> None:
    assert _vector_digests(family.name, humans) == GOLDEN_RECORDED[humans]


def test_the_distance_to_the_replaced_persons_path_is_the_least_over_every_segment() -> None:
    from socialzoo.env.recording_bank import PATH_CHUNK, path_boxes
    from socialzoo.env.replay_kernels import _path_distance2

    def every_segment(px: float, py: float, path: np.ndarray) -> float:
        nearest2 = np.inf
        for (ax, ay), (bx, by) in itertools.pairwise(path):
            abx, aby = bx - ax, by - ay
            u = min(max(((px - ax) * abx + (py - ay) * aby) / max(abx * abx + aby * aby, 1e-12), 0.0), 1.0)
            cx, cy = ax + u * abx - px, ay + u * aby - py
            nearest2 = min(nearest2, cx * cx + cy * cy)
        return nearest2

    rng = np.random.default_rng(0)
    lead = np.zeros((3, 2))  # the path sits after other entries' points in the bank
    for points in (2, 3, PATH_CHUNK, PATH_CHUNK + 1, PATH_CHUNK + 2, 40, 97):
        # A walk that turns back on itself, with repeated points (a person standing still).
        steps = rng.normal(0.0, 0.5, (points, 2)) * (rng.random((points, 1)) > 0.2)
        path = np.cumsum(steps, axis=0)
        bank_path = np.concatenate((lead, path))
        boxes = np.concatenate((np.zeros((3, 4)), path_boxes(path)))
        scratch = np.empty((points - 2) // PATH_CHUNK + 1)
        for px, py in rng.uniform(path.min() - 2, path.max() + 2, (200, 2)):
            got = _path_distance2(px, py, bank_path, boxes, 3, points, PATH_CHUNK, scratch)
            assert got == every_segment(px, py, path)


def test_a_robot_whose_episode_ended_stops_counting_while_its_row_goes_on() -> None:
    # Two robots in one recorded row (ReplayRunner.account): the robot whose episode ended adds no moves
    # and no distance to the recorded path; its row's time runs on until every robot's episode ended.
    tracks = np.full((1, 30, 2), np.nan)
    tracks[0] = np.stack((np.arange(30) * 0.5, np.zeros(30)), -1)
    recorded = RecordedPeople(dt=DT, tracks=tracks, robot_track=np.array([[0.0, 2.0], [10.0, 2.0]]))
    starts = np.array([[1.0, 3.0, 0.0], [5.0, 4.0, 0.0]])
    scenario = people_scenario(recorded, starts, starts + [[1.0, 0.0, 0.0]], seed=4, family="test")
    core = BatchedCore(
        1, 2, 1, WorldConfig(dt=0.1), WallIndex(np.zeros((0, 4))), people=PeopleConfig(models="replay")
    )
    core.reset_rows(np.array([0]), [scenario])
    replay = core.replay
    for ended in ([False, False], [False, True], [True, True]):
        for _ in range(3):
            core.step(np.zeros((1, 2, 2)))
            core.end_episodes(np.array([ended]))
    assert replay.moves[0].tolist() == [7, 4]
    assert replay.elapsed[0] == pytest.approx(0.7)
    # Each robot stood 1 m and 2 m off the path on every step it counted.
    assert replay.deviation[0] == pytest.approx([7 * 1.0, 4 * 2.0])


@pytest.mark.parametrize("task", ["action_selection", "crowdnav"])
def test_a_pickled_env_of_a_family_of_ones_own_plays_on_where_it_is_not_registered(
    task: str, tmp_path, monkeypatch
) -> None:
    """A worker process that receives a pickled env (supersuit's process workers, a spawn start
    method) has not run register_family: the copy resets on and plays its fixed cases as the
    original, from the family it carries (the action-selection task looked it up by name at reset)."""
    import pickle

    from socialzoo.env.vector import TaskVectorEnv

    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))  # the action-selection task's open-area map
    name = "recorded_test_worker"
    monkeypatch.setitem(FAMILIES, name, RecordedScene(_recording(count=40), name=name))
    kwargs = (
        {"map": None, "people": {"models": "replay"}, "max_steps": 30}
        if task == "action_selection"
        else {"humans": "replay", "robot_visible": True, "time_limit": 8.0}
    )
    vec = TaskVectorEnv(2, task=task, family=name, **kwargs)
    vec.reset(seed=3)
    blob = pickle.dumps(vec)
    monkeypatch.delitem(FAMILIES, name)
    other = pickle.loads(blob)
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(80):
        action = vec.action_space.sample() if task == "crowdnav" else rng.integers(0, 4, 2)
        a, b = vec.step(action), other.step(action)
        for x, y in zip(a[:4], b[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        ended += int((a[2] | a[3]).sum())
    assert ended  # the copy drew its next episodes itself
    options = {"split": "test", "cases": [0, 1]}
    np.testing.assert_array_equal(vec.reset(options=options)[0], other.reset(options=options)[0])


def test_a_config_with_more_robots_than_a_recorded_scene_holds_is_refused_when_made(family) -> None:
    """A recorded episode has one robot (the one in a person's place): two are refused by the
    config itself, naming the field and the family, not at the env's first reset."""
    from socialzoo.env.config import EnvConfig
    from socialzoo.env.crowd_config import CrowdNavConfig

    for make in (EnvConfig, CrowdNavConfig):
        with pytest.raises(ValueError, match=rf"num_robots = 2, but scenario family '{family.name}' holds 1"):
            make(family=family.name, num_robots=2)
        assert make(family=family.name).num_robots == 1


def test_crowdnav_slots_too_few_for_a_family_are_refused_before_a_run(
    family: RecordedScene, tmp_path
) -> None:
    # `socialzoo suite --task crowdnav --scenarios recorded_eth` (socialzoo/CrowdNavSuite-v2: 20 person
    # slots; the scene's largest scenario: 44 people) stopped with a traceback at the first reset,
    # "scenario 0 has 43 humans, more than max_humans=20", after its results store was begun.
    from socialzoo.bench.suite import SuiteConfig, SuiteError, run_suite
    from socialzoo.env.crowd_config import CrowdNavConfig

    most = family.max_people
    assert most > 20
    with pytest.raises(ValueError, match=rf"max_humans \(20\) is below the {most} people of the largest"):
        CrowdNavConfig(family=family.name, max_humans=20)
    assert CrowdNavConfig(family=family.name).max_humans == most  # None: sized to the family, as before
    assert CrowdNavConfig(family=family.name, max_humans=most).max_humans == most
    config = SuiteConfig(task="crowdnav", scenarios=(family.name,), policies=("orca",), seeds=1, replays=0)
    with pytest.raises(
        SuiteError, match=rf"{family.name}: the crowdnav task cannot be built .*max_humans \(20\)"
    ):
        run_suite(config, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_the_baselines_tool_gives_the_shipped_crowdnav_learners_their_own_observation(load_tool) -> None:
    # tools/recorded_baselines.py (docs/recorded.md's baselines) read the wall rays of the id a learner
    # was trained on through gymnasium, which refuses the shipped suite_crowdnav's socialzoo/CrowdNavSuite-v1
    # as deprecated since the suite ids' bump to -v2: the tool stopped at that policy.
    tool = load_tool("recorded_baselines")
    assert tool._learned_crowd_overrides("suite_crowdnav") == {
        "action": "discrete",
        "signals": True,
        "wall_rays": 16,
        "observed_people": 20,
    }
    assert tool._learned_crowd_overrides("crowdnav") == {
        "action": "discrete",
        "wall_rays": 0,
        "observed_people": 5,
    }
    assert tool._learned_crowd_overrides("orca") == {}
