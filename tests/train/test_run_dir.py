"""A training run's folder records its arguments and refuses to mix two runs."""

import json
import os
import shlex
from dataclasses import dataclass, replace
from pathlib import Path

import pytest

from socialzoo.train.run_dir import RunDir, RunDirError, checkpoint_steps, plain


@dataclass(frozen=True, kw_only=True)
class Args:
    steps: int = 10
    seed: int = 0
    out: Path = Path("x")
    progress: bool = True


def test_run_json_records_args_command_and_seed(tmp_path):
    run = RunDir(tmp_path, "ppo", Args(seed=5, out=tmp_path))
    record = json.loads((tmp_path / "run.json").read_text())
    assert record["algo"] == "ppo" and record["seed"] == 5 and record["args"]["out"] == "."
    assert record["command"] and record["finished"] is None and not run.finished
    run.finish(wall_seconds=1.5)
    again = RunDir(tmp_path, "ppo", Args(seed=5, out=tmp_path, progress=False), volatile=("progress",))
    assert again.finished and again.record["results"] == {"wall_seconds": 1.5}


def test_other_arguments_are_refused(tmp_path):
    RunDir(tmp_path, "ppo", Args())
    with pytest.raises(RunDirError, match="seed differ"):
        RunDir(tmp_path, "ppo", replace(Args(), seed=1))
    with pytest.raises(RunDirError, match="ppo run"):
        RunDir(tmp_path, "dqn", Args())


@dataclass(frozen=True, kw_only=True)
class MapArgs:
    map: str = "open_room"
    out: Path = Path("x")


def test_run_json_records_the_training_maps_contents(tmp_path):
    """A map file's contents (not only its name) are recorded, so a record tells which walls a
    policy trained on after the file was edited; an older record without the key still reads."""
    from socialzoo.maps.map_file import MapError, load_map, map_sha256

    room = load_map("open_room").to_json()
    path = tmp_path / "room.json"
    path.write_text(json.dumps(room))
    first = RunDir(tmp_path / "a", "ppo", MapArgs(map=str(path), out=tmp_path / "a"))
    assert first.record["map_sha256"] == map_sha256(load_map("open_room"))
    path.write_text(json.dumps({**room, "walls": room["walls"][:-1]}))
    edited = RunDir(tmp_path / "b", "ppo", MapArgs(map=str(path), out=tmp_path / "b"))
    assert edited.record["map_sha256"] == map_sha256(load_map(path)) != first.record["map_sha256"]
    assert "map_sha256" not in RunDir(tmp_path / "c", "ppo", Args(out=tmp_path / "c")).record
    first.finish()
    old = json.loads((tmp_path / "a" / "run.json").read_text())
    del old["map_sha256"]  # a record written before the key
    (tmp_path / "a" / "run.json").write_text(json.dumps(old))
    assert RunDir(tmp_path / "a", "ppo", MapArgs(map=str(path), out=tmp_path / "a")).finished
    with pytest.raises(MapError, match="nope"):  # named by the map's loader, and no folder made
        RunDir(tmp_path / "d", "ppo", MapArgs(map="nope", out=tmp_path / "d"))
    assert not (tmp_path / "d").exists()


@dataclass(frozen=True, kw_only=True)
class LfdArgs:
    demos: Path
    out: Path
    seed: int = 0


def test_a_folder_moved_with_its_inputs_holds_the_same_run(tmp_path):
    """A work folder (run and demonstrations) moved elsewhere: the input at the same place
    relative to `out` is the same input; one that moved on its own is not."""
    old, new = tmp_path / "old", tmp_path / "new"
    RunDir(old / "lfd/bc", "bc", LfdArgs(demos=old / "demos/d.npz", out=old / "lfd/bc")).finish()
    old.rename(new)
    moved = LfdArgs(demos=new / "demos/d.npz", out=new / "lfd/bc")
    assert RunDir(new / "lfd/bc", "bc", moved, volatile=("out",), inputs=("demos",)).finished
    elsewhere = replace(moved, demos=tmp_path / "other/d.npz")
    with pytest.raises(RunDirError, match="demos differ"):
        RunDir(new / "lfd/bc", "bc", elsewhere, volatile=("out",), inputs=("demos",))
    # A Path argument is a path whether declared an input or not, and the seed still counts.
    assert RunDir(new / "lfd/bc", "bc", moved, volatile=("out",)).finished
    with pytest.raises(RunDirError, match="seed differ"):
        RunDir(new / "lfd/bc", "bc", replace(moved, seed=1), volatile=("out",), inputs=("demos",))


def test_a_record_of_working_folder_paths_still_names_its_inputs(tmp_path):
    """A record written before paths were relative to the run folder (absolute ones, or relative to
    the working folder, as the shipped records were): an input at the same place relative to
    `out` is the same input."""
    old, new = tmp_path / "old", tmp_path / "new"
    (old / "lfd/bc").mkdir(parents=True)
    args = {"demos": str(old / "demos/d.npz"), "out": str(old / "lfd/bc"), "seed": 0}
    (old / "lfd/bc/run.json").write_text(json.dumps({"algo": "bc", "args": args, "finished": "yes"}))
    old.rename(new)
    moved = LfdArgs(demos=new / "demos/d.npz", out=new / "lfd/bc")
    assert RunDir(new / "lfd/bc", "bc", moved, volatile=("out",), inputs=("demos",)).finished
    with pytest.raises(RunDirError, match="demos differ"):
        RunDir(
            new / "lfd/bc",
            "bc",
            replace(moved, demos=tmp_path / "d.npz"),
            volatile=("out",),
            inputs=("demos",),
        )


@dataclass(frozen=True, kw_only=True)
class FileArgs:
    demos: str
    out: str
    note: str = ""


def test_the_command_of_python_m_socialzoo_is_recorded_as_socialzoo(tmp_path, monkeypatch):
    # Found training with `python -m socialzoo train ppo ...`: run.json said "__main__.py train ppo ...".
    main_file = Path(__import__("socialzoo").__file__).with_name("__main__.py")
    monkeypatch.setattr("sys.argv", [str(main_file), "train", "x", "--seed", "5"])
    RunDir(tmp_path, "x", Args(seed=5, out=tmp_path))
    assert json.loads((tmp_path / "run.json").read_text())["command"] == "socialzoo train x --seed 5"


def test_a_fresh_run_record_holds_no_absolute_path(tmp_path, monkeypatch):
    demos = tmp_path / "demos" / "d.npz"
    program = tmp_path / "runs" / "p" / "prog.json"
    demos.parent.mkdir()
    demos.write_bytes(b"")  # an input given alone is a path when it is a file (not a name such as "ref")
    argv = ["/usr/bin/socialzoo", "train", "x", "--demos", str(demos), f"--out={program}", "--note", "a b"]
    monkeypatch.setattr("sys.argv", argv)
    args = FileArgs(demos=str(demos), out=str(program), note="/etc/passwd")  # a str argument, yet absolute
    run = RunDir(program.parent, "x", args, inputs=("demos",))
    run.finish(data={"path": str(demos), "files": [str(tmp_path / "runs" / "p" / "log.txt")]})
    record = json.loads((program.parent / "run.json").read_text())
    note = os.path.relpath("/etc/passwd", program.parent)
    assert record["args"] == {"demos": "../../demos/d.npz", "out": "prog.json", "note": note}
    assert record["command"] == "socialzoo train x --demos ../../demos/d.npz --out=prog.json --note 'a b'"
    assert record["results"] == {"data": {"path": "../../demos/d.npz", "files": ["log.txt"]}}
    assert absolute_paths(record) == []
    # Read back from another working folder, the run is the same run.
    monkeypatch.chdir(tmp_path / "demos")
    again = FileArgs(demos="d.npz", out="../runs/p/prog.json", note="/etc/passwd")
    assert RunDir(program.parent, "x", again, inputs=("demos",)).finished


def absolute_paths(value, where="record"):
    """Every string in a JSON value (or word of a command line) that is an absolute path."""
    if isinstance(value, dict):
        return [p for k, v in value.items() for p in absolute_paths(v, f"{where}.{k}")]
    if isinstance(value, list):
        return [p for k, v in enumerate(value) for p in absolute_paths(v, f"{where}[{k}]")]
    if isinstance(value, str):
        words = shlex.split(value) if where.endswith(".command") else [value]
        return [f"{where}: {w}" for w in words if os.path.isabs(w.partition("=")[2] or w)]
    return []


def test_no_shipped_run_record_holds_an_absolute_path():
    from socialzoo.agents import SHIPPED_DIR

    records = sorted([*SHIPPED_DIR.glob("*.run.json"), *SHIPPED_DIR.glob("*.train.json")])
    assert len(records) >= 8
    found = [p for file in records for p in absolute_paths(json.loads(file.read_text()), file.name)]
    assert found == []


def test_checkpoints_are_listed_by_step(tmp_path):
    run = RunDir(tmp_path, "ppo", Args())
    for step in (4000, 2000):
        run.checkpoint_path(step, ".safetensors").write_text("")
    assert [s for s, _ in run.checkpoints(".safetensors")] == [2000, 4000]


def test_checkpoint_steps():
    assert checkpoint_steps(84000, 2000)[:2] == [2000, 4000] and len(checkpoint_steps(84000, 2000)) == 42
    assert checkpoint_steps(5000, 2000) == [2000, 4000, 5000]
    with pytest.raises(ValueError):
        checkpoint_steps(0, 2000)


def test_plain_turns_dataclasses_paths_and_tuples_into_json():
    assert plain({"a": (Path("p"), Args())}) == {
        "a": ["p", {"steps": 10, "seed": 0, "out": "x", "progress": True}]
    }


@dataclass(frozen=True, kw_only=True)
class SpecArgs:
    scenes: str
    robot: str = "ref"
    ray_address: str = "ray://head:10001"
    out: str


def test_paths_inside_specs_are_recorded_relative_to_the_run_folder(tmp_path, monkeypatch):
    """Specs that name files ("NAME=PATH" scenes, "ppo:PATH" policies) keep no absolute path and,
    for input arguments, hold their paths as seen from the run folder, like plain path arguments."""
    monkeypatch.chdir(tmp_path)
    track, policy = tmp_path / "data" / "t.txt", tmp_path / "p" / "ppo.safetensors"
    track.parent.mkdir()
    (tmp_path / "data" / "u.txt").write_text("")
    scenes = f"eth,mine={track},data/u.txt"
    robot = f"hybrid:ppo:{policy}"
    argv = ["socialzoo", "train", "x", "--scenes", scenes, "--robot", robot, "--out", "runs/a"]
    monkeypatch.setattr("sys.argv", argv)
    args = SpecArgs(scenes=scenes, robot=robot, out="runs/a")
    RunDir(Path("runs/a"), "x", args, inputs=("scenes",)).finish(files=[f"log={tmp_path}/runs/a/log.txt"])
    record = json.loads((tmp_path / "runs" / "a" / "run.json").read_text())
    assert record["args"]["scenes"] == "eth,mine=../../data/t.txt,../../data/u.txt"
    assert record["args"]["robot"] == "hybrid:ppo:../../p/ppo.safetensors"
    assert record["args"]["ray_address"] == "ray://head:10001"  # an address, not a path
    assert record["results"]["files"] == ["log=log.txt"]
    assert absolute_paths(record) == []
    assert "--scenes eth,mine=../../data/t.txt,../../data/u.txt" in record["command"]
    # The same run, from the same folder: the same arguments.
    assert RunDir(Path("runs/a"), "x", args, inputs=("scenes",)).finished


def test_a_name_given_alone_to_an_input_is_no_path(tmp_path, monkeypatch):
    # Found rerunning a finished `socialzoo train humans --out DIR` (default --robot ref) from another
    # working folder: it was refused ("robot differ"), run.json holding robot "../../<cwd>/ref".
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    out = tmp_path / "runs" / "h"
    for cwd in ("a", "b"):
        monkeypatch.chdir(tmp_path / cwd)
        monkeypatch.setattr("sys.argv", ["socialzoo", "train", "x", "--scenes", "eth", "--out", str(out)])
        run = RunDir(out, "x", SpecArgs(scenes="eth", out=str(out)), inputs=("scenes", "robot"))
        if cwd == "a":
            run.finish()
    assert run.finished
    record = json.loads((out / "run.json").read_text())
    assert record["args"]["robot"] == "ref" and record["args"]["scenes"] == "eth"
    assert "--scenes eth " in record["command"]
    # A file given alone is still a path, seen from the run folder.
    (tmp_path / "b" / "eth").write_text("")
    other = tmp_path / "runs" / "f"
    RunDir(other, "x", SpecArgs(scenes="eth", out=str(other)), inputs=("scenes",))
    assert json.loads((other / "run.json").read_text())["args"]["scenes"] == "../../b/eth"


@dataclass(frozen=True, kw_only=True)
class FamilyArgs:
    family: str
    out: Path


def test_a_word_that_spells_the_run_folder_is_no_path(tmp_path, monkeypatch):
    # Found running `socialzoo train bc --out bc` in a work folder: run.json (and the policy file's
    # header) said "socialzoo train . --out .", and --family crossing --out crossing recorded family ".".
    monkeypatch.chdir(tmp_path)
    argv = ["socialzoo", "train", "bc", "--family", "bc", "--out", "bc"]
    monkeypatch.setattr("sys.argv", argv)
    RunDir("bc", "bc", FamilyArgs(family="bc", out=Path("bc")))
    record = json.loads((tmp_path / "bc" / "run.json").read_text())
    assert record["command"] == "socialzoo train bc --family bc --out ."
    assert record["args"] == {"family": "bc", "out": "."}
    assert RunDir("bc", "bc", FamilyArgs(family="bc", out=Path("bc"))).record == record
    with pytest.raises(RunDirError, match="family differ"):
        RunDir("bc", "bc", FamilyArgs(family=".", out=Path("bc")))
