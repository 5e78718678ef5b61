"""The realism study (socialzoo.studies.realism) and the calibration (socialzoo.studies.calibration)
on synthetic recordings of a few straight-line walkers: the protocol where the answer is known, the
metrics, and the commands on a synthetic cache."""

import hashlib
import json

import numpy as np
import pytest

from socialzoo.data import fetch
from socialzoo.data.fetch import SceneFile
from socialzoo.data.tracks import Recording, Track
from socialzoo.studies import calibration, realism_metrics
from socialzoo.studies.realism_cases import (
    OBS_FRAMES,
    PRED_FRAMES,
    SceneTracks,
    constant_velocity,
    track_cases,
    truth,
    window_cases,
)
from socialzoo.studies.realism_metrics import (
    COLLISION_DISTANCE,
    contact_rate,
    displacement,
    evaluate_model,
    nearest_other,
    wasserstein,
)
from socialzoo.studies.realism_simulation import Rollout, model_spec, realism_world, simulate

DT = 0.4


def _walkers(frames=30, lanes=((0.0, 0.0, 1.0, 0.0), (0.0, 20.0, 1.2, 0.0)), start=(0, 2)):
    """A recording of straight walkers: (x0, y0, vx, vy) per lane, entering at `start` frames."""
    tracks = []
    for person, ((x0, y0, vx, vy), first) in enumerate(zip(lanes, start, strict=True), start=1):
        t = np.arange(frames - first) * DT
        tracks.append(Track(person, first, np.stack((x0 + vx * t, y0 + vy * t), 1)))
    return Recording("synthetic", DT, frames, tuple(tracks), "test")


def test_windows_follow_the_prediction_protocol():
    scene = SceneTracks.of(_walkers(frames=30))
    cases = window_cases(scene)
    # Person 0 seen on frames 0..29: windows at t0 = 7 .. 17 (8 observed, 12 predicted).
    mine = cases.start[cases.person == 0]
    assert mine.min() == OBS_FRAMES - 1 and mine.max() == 29 - PRED_FRAMES
    assert (cases.frames == PRED_FRAMES).all()


def test_constant_velocity_on_a_straight_walk_is_exact():
    scene = SceneTracks.of(_walkers())
    for cases in (window_cases(scene), track_cases(scene)):
        ade, fde = displacement(constant_velocity(scene, cases), truth(scene, cases))
        assert ade == pytest.approx(0.0, abs=1e-9) and fde == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("model", ["sf", "orca", "sf-eth-ucy", "orca-eth-ucy"])
def test_a_model_person_alone_walks_its_track(model):
    # Two walkers 20 m apart: nobody in the way, each walks straight to its exit at its recorded speed,
    # as the recorded person did, and leaves there on the track's last frame. Its route used to end at the
    # exit, so it left within the 1 m waypoint radius of it and was held there while the recorded person
    # walked on: ADE 0.037 m and FDE 0.264 m over 4.8 s, a track FDE of 1.32 m, where cv is exact.
    scene = SceneTracks.of(_walkers())
    for cases in (window_cases(scene), track_cases(scene)):
        rollout = simulate(scene, cases, model_spec(model))
        ade, fde = displacement(rollout.pos, truth(scene, cases))
        assert ade == pytest.approx(0.0, abs=1e-9) and fde == pytest.approx(0.0, abs=1e-9)
        assert rollout.present[np.arange(len(cases)), cases.frames].all()


def test_a_model_person_avoids_a_replayed_one_coming_at_it():
    # Head on along one line: constant velocity walks through the other, the models step aside.
    rec = _walkers(frames=30, lanes=((0.0, 0.0, 1.0, 0.0), (20.0, 0.0, -1.0, 0.0)), start=(0, 0))
    scene = SceneTracks.of(rec)
    tracks = track_cases(scene)
    cv = evaluate_model(scene, window_cases(scene), tracks, model_spec("cv"))
    orca = evaluate_model(scene, window_cases(scene), tracks, model_spec("orca"))
    assert cv.metrics["contact_rate"] == 1.0
    assert orca.metrics["contact_rate"] == 0.0


def test_the_distributions_compare_the_frames_the_model_walks(monkeypatch):
    # Two people pass each other 1 m apart; a model's person walks its track exactly but leaves 3 frames
    # before its track ends (held there), as one that walks faster than its recorded person does. The
    # recorded speeds and nearest-neighbour distances of the frames it never walks counted against it:
    # NN W1 1.18 m for a perfect walk.
    rec = _walkers(frames=10, lanes=((0.0, 0.0, 1.0, 0.0), (10.0, 1.0, -1.0, 0.0)), start=(0, 0))
    scene = SceneTracks.of(rec)

    def leaves_early(scene, cases, model, base=None, progress=None):
        true = truth(scene, cases)
        f = np.arange(true.shape[1])[None, :]
        last = np.maximum(cases.frames - 3, 0)[:, None]
        pos = np.take_along_axis(true, np.minimum(f, last)[..., None], axis=1)
        pos = np.where(np.isnan(true), np.nan, pos)
        present = (f <= last) & ~np.isnan(true[..., 0])
        return Rollout(pos, present, np.where(present, nearest_other(scene, cases, pos), np.inf))

    monkeypatch.setattr(realism_metrics, "simulate", leaves_early)
    result = evaluate_model(scene, window_cases(scene), track_cases(scene), model_spec("orca"))
    assert result.metrics["track_ade"] == pytest.approx(0.0, abs=1e-6)
    assert result.metrics["nn_w1"] == pytest.approx(0.0, abs=1e-6)
    assert result.metrics["speed_w1"] == pytest.approx(0.0, abs=1e-6)


def test_everyone_seen_during_a_case_replays_beside_the_subject():
    # The subject walks frames 0..29; a walker 1 m beside it enters at frame 10. It is seen during
    # the subject's track case, so it replays there (it was left out: only people present on every
    # frame of the case were).
    rec = _walkers(frames=30, lanes=((0.0, 0.0, 1.0, 0.0), (4.0, 1.0, 1.0, 0.0)), start=(0, 10))
    scene = SceneTracks.of(rec)
    cases = track_cases(scene, np.array([0]))
    others = simulate(scene, cases, model_spec("sf")).others[0]
    assert np.isinf(others[:10]).all()
    assert np.isfinite(others[10:25]).all() and (others[10:25] < 2.0).all()


def test_metrics():
    pred = np.zeros((2, 3, 2))
    true = np.zeros((2, 3, 2))
    true[0, 1:, 0] = [1.0, 2.0]  # ADE 1.5, FDE 2
    ade, fde = displacement(pred, true)
    assert ade == pytest.approx(0.75) and fde == pytest.approx(1.0)
    assert wasserstein(np.array([0.0, 1.0]), np.array([1.0, 2.0])) == pytest.approx(1.0)
    assert contact_rate(np.array([[1.0, COLLISION_DISTANCE / 2]]), np.array([[True, True]])) == 1.0
    assert contact_rate(np.array([[1.0, COLLISION_DISTANCE / 2]]), np.array([[True, False]])) == 0.0


def test_model_names_and_presets():
    assert model_spec("groups").groups and model_spec("groups").people == "sf"
    with pytest.raises(ValueError, match="unknown realism model"):
        model_spec("nope")
    values = calibration.from_unit("sf", [0.5] * len(calibration.PARAMETERS["sf"]))
    assert calibration.to_unit("sf", values) == pytest.approx([0.5] * len(values))
    spec = calibration.spec_of(
        "orca", {"orca.radius": 0.2, "orca.time_horizon": 1.0, "orca.neighbor_dist": 3.0}
    )
    world = spec.world(realism_world())
    assert world.orca.radius == 0.2 and world.orca.time_horizon == 1.0
    for name, preset in calibration.PRESETS.items():
        assert model_spec(name).people == preset["model"]


def test_a_learned_model_that_cannot_be_loaded_is_refused_before_any_scene_is_walked(tmp_path):
    # `humans realism --models sf,orca,learned:PATH` with a mistyped PATH walked every scene by sf and
    # orca first (8.8 s for zara1 and hotel, minutes for all five) and only then stopped at the file.
    from socialzoo.studies.realism import RealismConfig

    with pytest.raises(ValueError, match=r"RealismConfig\.models: learned:.*no such learned policy file"):
        RealismConfig(models=("sf", f"learned:{tmp_path / 'none.safetensors'}"))
    with pytest.raises(
        ValueError, match=r"RealismConfig\.models: learned:.*is a folder, not a learned policy"
    ):
        RealismConfig(models=(f"learned:{tmp_path}",))
    robot = tmp_path / "robot.safetensors"
    robot.write_bytes(b"not a policy")
    with pytest.raises(ValueError, match=r"RealismConfig\.models: learned:"):
        RealismConfig(models=(f"learned:{robot}",))


def _trajectron(rec):
    rows = [
        f"{(t.first_frame + i) * 10}\t{t.person}\t{p[0]:.3f}\t{p[1]:.3f}"
        for t in rec.tracks
        for i, p in enumerate(t.positions)
    ]
    return "\n".join(sorted(rows, key=lambda r: int(r.split("\t")[0]))) + "\n"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A synthetic cache of two scenes in the trajectron layout, SCENES replaced by them."""
    table = {}
    for name, lanes in (
        ("one", ((0.0, 0.0, 1.0, 0.0), (0.0, 20.0, 1.2, 0.0))),
        ("two", ((0.0, 0.0, 0.0, 1.0),)),
    ):
        text = _trajectron(_walkers(lanes=lanes, start=(0, 2)[: len(lanes)]))
        path = f"{name}/test/{name}.txt"
        (tmp_path / f"{name}.txt").write_text(text)  # the cache keeps the file's name only
        table[name] = (SceneFile(path, hashlib.sha256(text.encode()).hexdigest()),)
    monkeypatch.setattr(fetch, "SCENES", table)
    return tmp_path


def test_realism_command_on_a_synthetic_cache(cache, tmp_path, capsys):
    from socialzoo.cli import main

    out = tmp_path / "out"
    args = ["humans", "realism", "--scenes", "one,two", "--models", "cv,orca", "--cache", str(cache)]
    assert main([*args, "--out", str(out), "--no-progress", "--no-figures"]) == 0
    assert (
        capsys.readouterr().out.rstrip().endswith(f"results in {out}: realism.md, realism.csv, realism.json")
    )
    drawn = tmp_path / "drawn"  # the figures are said too (they were written but not listed)
    assert main([*args, "--out", str(drawn), "--no-progress"]) == 0
    listed = capsys.readouterr().out.rstrip().rpartition(": ")[2].split(", ")
    assert listed[3:] == ["ade.png", "speeds.png"] and all((drawn / name).is_file() for name in listed)
    table = (out / "realism.md").read_text()
    assert "| one | cv |" in table and "| overall | orca |" in table
    record = json.loads((out / "realism.json").read_text(), parse_constant=pytest.fail)
    assert record["seed"] == 0 and "numpy" in record["versions"]
    assert main(["humans", "realism", "--scenes", "nowhere", "--cache", str(cache), "--out", str(out)]) == 2
    # A model named twice ran twice, its rows twice in every table.
    assert main([*args[:5], "orca,cv,orca", "--out", str(tmp_path / "twice"), "--no-progress"]) == 2
    assert "RealismConfig.models has duplicates: ['orca', 'cv', 'orca']" in capsys.readouterr().err
    # A track file of your own beside a scene, named after the file or NAME=PATH.
    own = tmp_path / "mine.txt"
    own.write_text((cache / "two.txt").read_text())
    for spec, name in ((str(own), "mine"), (f"walkway={own}", "walkway")):
        args = ["humans", "realism", "--scenes", f"one,{spec}", "--models", "cv", "--cache", str(cache)]
        assert main([*args, "--out", str(tmp_path / name), "--no-progress", "--no-figures"]) == 0
        table = (tmp_path / name / "realism.md").read_text()
        assert f"| {name} | cv |" in table and "| one | cv |" in table


def test_calibrate_command_on_a_synthetic_cache(cache, tmp_path):
    pytest.importorskip("cma")
    from socialzoo.cli import main

    out = tmp_path / "cal"
    args = ["humans", "calibrate", "--model", "orca", "--scenes", "one,two", "--cache", str(cache)]
    tiny = ["--persons", "2", "--windows", "1", "--generations", "1", "--popsize", "2", "--no-progress"]
    assert main([*args, *tiny, "--out", str(out)]) == 0
    record = json.loads((out / "calibration.json").read_text(), parse_constant=pytest.fail)
    assert [f["held_out"] for f in record["folds"]] == ["one", "two"]
    assert json.loads((out / "orca-eth-ucy.json").read_text())["model"] == "orca"


def test_calibrate_refuses_a_population_of_one(tmp_path, capsys):
    # cma refuses it, after the recordings were read: 'number of weights must be >=2, was 1'.
    from socialzoo.cli import main

    out = tmp_path / "cal"
    args = ["humans", "calibrate", "--model", "sf", "--popsize", "1", "--no-folds", "--out", str(out)]
    assert main(args) == 2 and not out.exists()
    assert "CalibrationConfig.popsize must be >= 2 (CMA-ES), got 1" in capsys.readouterr().err


def test_calibrate_names_a_scene_without_a_window(cache, tmp_path, capsys):
    # A scene whose sampled people are all too short for a 4.8 s window dropped out of the fit's
    # objective silently, and as the held-out scene it gave an ADE of nan, counted "not better".
    pytest.importorskip("cma")
    from socialzoo.cli import main

    short = tmp_path / "short.txt"
    short.write_text(_trajectron(_walkers(frames=OBS_FRAMES + PRED_FRAMES - 1, start=(0, 0))))
    args = ["humans", "calibrate", "--model", "orca", "--scenes", f"one,{short}", "--cache", str(cache)]
    tiny = ["--persons", "2", "--windows", "1", "--generations", "1", "--popsize", "2", "--no-progress"]
    assert main([*args, *tiny, "--out", str(tmp_path / "cal")]) == 2
    err = capsys.readouterr().err
    assert "scene 'short': none of the 2 people of its fit sample has a 4.8 s window" in err
    assert "Traceback" not in err


def test_the_recorded_reference_is_blank_where_the_models_are_not_measured():
    """The realism table's "recorded" row read ADE 0.000 on a scene without a 4.8 s window, where every
    model's row is blank (no windowed error): it now has no windowed error either."""
    from socialzoo.studies.realism_metrics import recorded_reference

    short = SceneTracks.of(_walkers(frames=OBS_FRAMES + PRED_FRAMES - 1, start=(0, 0)))
    windows, tracks = window_cases(short), track_cases(short)
    assert len(windows) == 0 and len(tracks) > 0
    model = evaluate_model(short, windows, tracks, model_spec("cv"))
    reference = recorded_reference(short, windows, tracks)
    for name in ("ade", "fde"):
        assert np.isnan(model.metrics[name]) and np.isnan(reference.metrics[name])
    assert reference.metrics["track_ade"] == 0.0 and np.isfinite(model.metrics["track_ade"])
    full = SceneTracks.of(_walkers())
    assert recorded_reference(full, window_cases(full), track_cases(full)).metrics["ade"] == 0.0
