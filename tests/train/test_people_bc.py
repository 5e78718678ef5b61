"""People cloned from recorded people: the demonstrations' actions give back the recorded motion,
and a tiny run writes a learned human policy file that walks a person in the batched core."""

import dataclasses
import json

import numpy as np
import pytest

from socialzoo.data.tracks import Recording, Track
from socialzoo.env.human_agents import action_velocities, human_observation_size
from socialzoo.env.human_policy import LearnedHumanPolicy
from socialzoo.train import people_bc
from socialzoo.train.marl_args import env_id
from socialzoo.train.people_bc import Args
from socialzoo.train.people_closed_loop import closed_loop_ade, subject_cases
from socialzoo.train.people_demos import ACTION_LIMIT, demonstrations, inverse_action, reaching_velocity
from socialzoo.train.people_replay import mean_speeds, replay_world, window_scenario


def _recording() -> Recording:
    """Four people walking straight lines at 1.0-1.3 m/s for 30 frames (12 s), two of them crossing."""
    tracks = []
    for k, (start, vel, first) in enumerate(
        [
            ((0.0, 0.0), (1.0, 0.0), 0),
            ((0.0, 3.0), (1.2, 0.0), 2),
            ((6.0, -6.0), (0.0, 1.1), 4),
            ((20.0, 8.0), (-1.3, 0.0), 0),
        ]
    ):
        t = np.arange(30)[:, None] * 0.4
        tracks.append(Track(person=k, first_frame=first, positions=np.array(start) + t * np.array(vel)))
    return Recording(name="straight", dt=0.4, num_frames=40, tracks=tuple(tracks), source="test")


@pytest.fixture(autouse=True)
def _one_thread():
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


def test_actions_invert_action_velocities():
    rec = _recording()
    scenario, _ = window_scenario(rec, 0, 10, mean_speeds(rec))
    from socialzoo.scenarios.start_state import scenarios_to_state

    state = scenarios_to_state([scenario])
    rng = np.random.default_rng(0)
    desired = rng.normal(size=state.human_pos.shape)
    slots = np.arange(state.max_humans)
    for frame in ("world", "human"):
        action = inverse_action(state, desired, frame, 1.7)
        back = action_velocities(state, slots, action, frame, 1.7)
        np.testing.assert_allclose(back[state.human_mask], desired[state.human_mask], atol=1e-12)


@pytest.mark.parametrize("tau", [None, 2.0])
def test_reaching_velocity_walks_the_recorded_displacement(tau):
    """The relaxation from v0 towards the desired velocity (at the learned people's relaxation time)
    covers the displacement."""
    world = dataclasses.replace(replay_world(relaxation_time=tau), dt=0.001)
    v0, disp, other = np.array([0.3, -0.2]), np.array([0.5, 0.1]), np.array([0.4, 0.7])
    vd = reaching_velocity(v0, disp, other, 0.4, world)
    rate = world.human.desired_factor / (tau or world.human.relaxation_time)
    v, p = v0.copy(), np.zeros(2)
    for _ in range(400):
        v = v + world.dt * (rate * (vd - v) + other)
        p = p + world.dt * v
    np.testing.assert_allclose(p, disp, atol=2e-3)


def test_demonstrations_of_straight_walkers():
    rec = _recording()
    demos = demonstrations(rec, window=12, num_neighbours=2, action_frame="human", action_scale=4.0)
    assert len(demos) > 50
    assert demos.obs.shape[1] == human_observation_size(2)
    assert np.abs(demos.action).max() <= ACTION_LIMIT
    # Own velocity is the recorded one walked into the frame (1.0 .. 1.3 m/s), never the parked robot's.
    speed = np.hypot(demos.obs[:, 2], demos.obs[:, 3])
    assert speed.min() > 0.99 and speed.max() < 1.31
    assert (demos.obs[:, 8 + 4 :: 5] == 0).all()  # no robot among the neighbours
    # Alone and straight, a walker's action (own frame, towards its exit) is forward: its speed over
    # scale x preferred speed, with no social force to undo.
    first = np.hypot(demos.obs[:, 8], demos.obs[:, 9])
    lone = (first > 10.0) | (demos.obs[:, 8:13] == 0).all(1)
    assert lone.any()
    np.testing.assert_allclose(demos.action[lone, 0], 0.25, atol=0.02)
    np.testing.assert_allclose(demos.action[lone, 1], 0.0, atol=0.02)


def test_noisy_copies_are_labelled_with_the_way_back():
    """Each noisy copy is the demonstration with its own velocity perturbed, and its action the one
    that still reaches the recorded next position from there: for a lone walker (no social force)
    the desired velocity moves by -s / (T - s) times the perturbation (reaching_velocity)."""
    t = np.arange(30)[:, None] * 0.4
    lone = Track(person=0, first_frame=0, positions=np.array([0.0, 0.0]) + t * np.array([1.1, 0.3]))
    rec = Recording(name="lone", dt=0.4, num_frames=30, tracks=(lone,), source="test")
    kwargs = dict(window=40, num_neighbours=2, action_frame="human", action_scale=4.0)
    clean = demonstrations(rec, **kwargs)
    noisy = demonstrations(rec, **kwargs, velocity_noise=0.1, noisy_copies=2, seed=3)
    # One row, one person: per frame the clean demonstration, then its two copies.
    assert len(clean) > 20 and len(noisy) == 3 * len(clean)
    np.testing.assert_array_equal(noisy.obs[0::3], clean.obs)
    np.testing.assert_array_equal(noisy.action[0::3], clean.action)
    world = replay_world()
    rate = world.human.desired_factor / world.human.relaxation_time
    s = (1.0 - np.exp(-rate * rec.dt)) / rate
    for copy in (noisy.take(np.arange(1, len(noisy), 3)), noisy.take(np.arange(2, len(noisy), 3))):
        moved = copy.obs[:, 2:4] - clean.obs[:, 2:4]  # own velocity, own frame
        assert 0.05 < np.abs(moved).mean() < 0.15  # about 0.1 m/s per axis
        np.testing.assert_array_equal(np.delete(copy.obs, [2, 3], 1), np.delete(clean.obs, [2, 3], 1))
        # action = desired / (scale x preferred speed), and d(desired) = -s / (T - s) d(v0).
        expected = clean.action - s / (rec.dt - s) * moved / (4.0 * clean.obs[:, 4:5])
        np.testing.assert_allclose(copy.action, expected, atol=1e-5)
    # The noise is seeded.
    again = demonstrations(rec, **kwargs, velocity_noise=0.1, noisy_copies=2, seed=3)
    np.testing.assert_array_equal(again.action, noisy.action)
    other = demonstrations(rec, **kwargs, velocity_noise=0.1, noisy_copies=2, seed=4)
    assert not np.array_equal(other.action, noisy.action)


def test_labels_reach_the_position_label_frames_ahead():
    """A lone walker at constant velocity is labelled alike whatever the horizon; a noisy copy's way
    back is spread over the horizon: d(desired) = -s / (K T - s) d(v0)."""
    t = np.arange(30)[:, None] * 0.4
    lone = Track(person=0, first_frame=0, positions=np.array([0.0, 0.0]) + t * np.array([1.1, 0.3]))
    rec = Recording(name="lone", dt=0.4, num_frames=30, tracks=(lone,), source="test")
    kwargs = dict(window=40, num_neighbours=2, action_frame="human", action_scale=4.0)
    one = demonstrations(rec, **kwargs)
    three = demonstrations(rec, **kwargs, label_frames=3)
    # (Its last frames, with no position three frames ahead, lie within the exit's radius anyway.)
    assert len(three) == len(one) > 20
    np.testing.assert_array_equal(three.obs, one.obs[: len(three)])
    np.testing.assert_allclose(three.action, one.action[: len(three)], atol=1e-6)
    noisy = demonstrations(rec, **kwargs, label_frames=3, velocity_noise=0.1, noisy_copies=1, seed=3)
    world = replay_world()
    rate = world.human.desired_factor / world.human.relaxation_time
    s = (1.0 - np.exp(-rate * 3 * rec.dt)) / rate
    clean, copy = noisy.take(np.arange(0, len(noisy), 2)), noisy.take(np.arange(1, len(noisy), 2))
    moved = copy.obs[:, 2:4] - clean.obs[:, 2:4]
    expected = clean.action - s / (3 * rec.dt - s) * moved / (4.0 * clean.obs[:, 4:5])
    np.testing.assert_allclose(copy.action, expected, atol=1e-5)
    with pytest.raises(ValueError, match="label_frames"):
        Args(label_frames=0)


def test_tiny_run_writes_a_policy_that_walks_a_person(tmp_path, monkeypatch):
    rec = _recording()
    monkeypatch.setattr("socialzoo.data.fetch.load_scene", lambda name, cache=None: rec)
    monkeypatch.setattr(
        "sys.argv", ["socialzoo", "train", "people-bc", "--scenes", "eth,hotel", "--max-epochs", "3"]
    )
    args = Args(
        scenes="eth,hotel", out=tmp_path / "run", seed=0, window=8, num_neighbours=2, hidden=16,
        max_epochs=3, patience=2, progress=False, relaxation_time=3.0,
    )  # fmt: skip
    path = people_bc.train(args)
    policy = LearnedHumanPolicy.load(path)
    assert policy.num_neighbours == 2 and policy.action_frame == "human" and policy.action_scale == 4.0
    assert policy.relaxation_time == 3.0 and not policy.learned_forces
    # No robot in the recordings: a robot neighbour is seen as the person its row describes.
    obs = np.random.default_rng(0).normal(size=(16, policy.input_size)).astype(np.float32)
    flags = [8 + 5 * k + 4 for k in range(2)]
    obs[:, flags] = 0.0
    robots = obs.copy()
    robots[:, flags] = 1.0
    np.testing.assert_array_equal(policy.act(robots), policy.act(obs))
    assert policy.header["training"]["algorithm"] == "people-bc"
    # The file records the command that was run (every option given), as run.json does.
    record = json.loads((tmp_path / "run" / "run.json").read_text())
    assert "--max-epochs 3" in record["command"]
    assert policy.header["training"]["command"] == record["command"]
    # The held-out time is too short here for a 12-frame closed-loop walk: measured on nothing.
    results = record["results"]
    assert results["held_out_closed_loop_ade"] == {} and results["held_out_closed_loop_ade_mean"] is None
    # `learned:PATH` drives the first person of a recorded window; the others replay.
    from socialzoo.core.walls import WallIndex
    from socialzoo.env.core import BatchedCore
    from socialzoo.humans.models import LEARNED, PeopleConfig

    scenario, _ = window_scenario(rec, 2, 14, mean_speeds(rec), subject=0)
    core = BatchedCore(
        1, 1, scenario.num_humans, replay_world(), WallIndex(np.zeros((0, 4))),
        people=PeopleConfig(models=f"learned:{path}"), robot_visible=False,
    )  # fmt: skip
    core.reset_rows([0], [scenario])
    assert core.state.human_model[0, 0] == LEARNED
    assert core.world.human.learned_tau == 3.0  # the world walks its people as they were trained
    start = core.state.human_pos[0, 0].copy()
    for _ in range(8):
        core.step(np.zeros((1, 1, 2)))
    assert np.isfinite(core.state.human_pos).all()
    assert not np.allclose(core.state.human_pos[0, 0], start)
    # The others walk exactly their tracks: 0.8 s after frame 2 is frame 4.
    other = rec.tracks[1]
    np.testing.assert_allclose(core.state.human_pos[0, 1], other.positions[4 - other.first_frame], atol=1e-9)


def test_labels_without_forces_are_the_recorded_motion_and_with_them_compensate():
    """Without forces on the learned people (the default) a label is what the relaxation alone
    needs to walk the recorded step, whoever is near; with --learned-forces the label of a person
    among others also undoes their push."""
    rec = _recording()
    kwargs = dict(window=12, num_neighbours=2, action_frame="human", action_scale=4.0)
    free = demonstrations(rec, **kwargs)
    forced = demonstrations(rec, **kwargs, world=replay_world(learned_forces=True))
    np.testing.assert_array_equal(free.obs, forced.obs)
    # The walkers' recorded velocity is constant, so without forces every label is the same
    # forward action (speed over scale x preferred speed), near others or not.
    np.testing.assert_allclose(free.action[:, 0], 0.25, atol=1e-6)
    np.testing.assert_allclose(free.action[:, 1], 0.0, atol=1e-6)
    first = np.hypot(free.obs[:, 8], free.obs[:, 9])
    near = (first < 1.5) & (free.obs[:, 8:13] != 0).any(1)
    assert near.any()
    assert np.abs(forced.action[near] - free.action[near]).max() > 0.02  # 0.08 m/s and more


def test_closed_loop_cases_keep_to_their_frames():
    rec = _recording()
    cases = subject_cases(rec, 10, 39, horizon=6)
    assert len(cases)
    for k, s in cases:
        track = rec.tracks[k]
        # The frame before the start (its velocity) and the 6 after it are recorded, inside 10..39.
        assert 10 <= s - 1 and track.first_frame <= s - 1 and s + 6 <= min(track.last_frame, 39)
    # Person 0 (frames 0..29): starts every 6 frames from frame 11.
    assert cases[cases[:, 0] == 0, 1].tolist() == [11, 17, 23]


def test_closed_loop_ade_of_a_policy_that_stops(tmp_path):
    """A policy whose action is always 0 (desired velocity 0) lets a straight walker slow down by
    the relaxation alone (no forces): each 0.1 s world step keeps 1 - dt / tau of its velocity and
    moves it by the new one (the world's semi-implicit step), against the recorded v t. (To within
    1 cm: among these others the world moves it a few millimetres off its bare relaxation, which a
    person alone follows exactly.)"""
    rec = _recording()
    size = human_observation_size(2)
    weights = [(np.zeros((8, size)), np.zeros(8)), (np.zeros((2, 8)), np.zeros(2))]
    path = LearnedHumanPolicy(weights, "tanh", np.zeros(size), np.ones(size), 2, "human", 4.0).save(
        tmp_path / "stop.safetensors", env_id(), {}
    )
    cases = np.array([[0, 1], [2, 5], [3, 20]])
    ade = closed_loop_ade(rec, cases, path, horizon=6)
    world = replay_world()
    keep = 1.0 - world.dt * world.human.desired_factor / world.human.relaxation_time
    covered = world.dt * np.cumsum(keep ** np.arange(1, 25))[3::4]  # per 1 m/s, at frames 1..6
    lag = np.arange(1, 7) * rec.dt - covered
    speed = np.array([np.hypot(*np.diff(rec.tracks[k].positions[:2], axis=0)[0]) / rec.dt for k, _ in cases])
    np.testing.assert_allclose(ade, speed * lag.mean(), atol=0.01)
    assert (ade > 0.3).all()


def test_closed_loop_ade_of_a_walker_that_leaves_at_its_exit(write_walker, tmp_path):
    """A person alone walking straight at 1 m/s, walked by a policy that walks straight at its waypoint at
    its preferred speed (its mean recorded speed), follows its track: ADE 0, on the windows that end on its
    last frame too. Its route ended at its exit, so it left within the 1 m waypoint radius of it and was held
    there while the recorded person walked on (ADE 0.1 m on that window); it ends the radius beyond the exit
    now, as in the realism study (exit_route)."""
    t = np.arange(30)[:, None] * 0.4
    walker = Track(person=0, first_frame=0, positions=t * np.array([0.6, 0.8]))
    rec = Recording(name="alone", dt=0.4, num_frames=30, tracks=(walker,), source="test")
    cases = np.array([[0, 1], [0, 9], [0, 17]])  # the last ends on frame 29, its last
    ade = closed_loop_ade(rec, cases, write_walker(tmp_path / "walker.safetensors", speed=10.0))
    np.testing.assert_allclose(ade, 0.0, atol=1e-6)


def test_scenes_with_nothing_to_clone_are_named(tmp_path, monkeypatch, capsys):
    # A scene of one frame ended in "max() arg is an empty sequence"; a scene too short for a
    # second window of --window frames (all its demonstrations held out for validation) and a
    # scene without demonstrations were a ValueError traceback out of `socialzoo train people-bc`.
    from socialzoo.cli import main

    one_frame = Recording(
        "still", 0.4, 1, (Track(person=1, first_frame=0, positions=np.zeros((1, 2))),), "test"
    )
    assert len(demonstrations(one_frame)) == 0
    scenes = {"eth": _recording(), "hotel": one_frame}
    monkeypatch.setattr("socialzoo.data.fetch.load_scene", lambda name, cache=None: scenes[name])
    tiny = ["--max-epochs", "1", "--hidden", "8", "--no-progress"]
    for names, window, says in (
        ("eth,hotel", "8", "no demonstration in still: one needs a person seen on 7 frames in a row"),
        ("eth", "40", "nothing left to train on in straight: the last of each scene's windows of 40 frames"),
    ):
        out = tmp_path / f"run{window}"
        assert (
            main(["train", "people-bc", "--scenes", names, "--window", window, "--out", str(out), *tiny]) == 2
        )
        err = capsys.readouterr().err
        assert says in err and "Traceback" not in err
