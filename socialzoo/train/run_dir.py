"""A training run's folder: its resolved arguments, command and seed, progress, logs and checkpoints."""

from __future__ import annotations

import dataclasses
import logging
import os
import re
import shlex
import shutil
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from socialzoo.core.files import read_json, write_json

logger = logging.getLogger(__name__)

RUN_FILE = "run.json"


class RunDirError(Exception):
    """A run folder that holds another run."""


def plain(value: Any) -> Any:
    """`value` as plain JSON (dataclasses as dicts, paths and tuples as strings and lists)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    return value


class RunDir:
    """The folder of one training run.

    Every trainer writes into one folder (through its skeleton, socialzoo.train.skeleton):

        run.json          algorithm, resolved arguments, command line, seed, package version, times,
                          and the sha256 of the training map's contents (map_digest)
        tensorboard/      TensorBoard event files (when the tensorboard package is installed)
        checkpoints/      the policy every `checkpoint_every` steps (step_000002000.<ext>, ...)
        <policy file>     the final policy

    Paths in run.json are relative to the run folder, never the machine's absolute ones: the path arguments (those
    holding a Path, `out`, and the files the trainer's `inputs` name: "ref" or "eth" are names), those same paths
    and any absolute path on the command line and in the results (`recorded`). A folder already holding a run of
    other arguments is refused, so two runs never mix; a finished run of the same arguments is reported as done, so
    a rerun repeats nothing; an unfinished run of the same arguments (an interrupted one, which trains again from its
    first step) gets a new record of this run. An argument added to a trainer after a run was recorded does not count
    against it while it has its default value. A path argument that lies where it lay relative to the run folder
    names the same file, so a work folder moved or copied whole together with its inputs (a `socialzoo reproduce`
    folder) holds the same runs; so does an input file (a trainer's `inputs`, such as imitation's demonstrations)
    of a record written before paths were relative, when it lies where it lay relative to the run's `out`.

    Args:
        path: the folder (created).
        algo: the trainer's name, e.g. "ppo".
        args: the trainer's argument dataclass (its plain form is the run's identity; fields
            named in `volatile` are recorded but do not count, e.g. the progress bar switch).
        volatile: argument names that do not change the result.
        record_name: the record's file name (run.json; PIPS keeps NAME.train.json beside its program).
        inputs: argument names that name input files; one counts as unchanged when it lies at the
            same place relative to `out` as in the record (the folder moved with its inputs).

    Raises:
        RunDirError: the folder holds a run of another algorithm or other arguments.
    """

    def __init__(
        self,
        path: str | Path,
        algo: str,
        args: Any,
        volatile: tuple[str, ...] = (),
        record_name: str = RUN_FILE,
        inputs: tuple[str, ...] = (),
    ) -> None:
        from socialzoo import __version__

        self.path = Path(path)
        self.file = self.path / record_name
        existing = self.read()
        # Before the folder is made: a map that does not load (MapError) leaves no folder behind.
        # (The record of a finished run is kept as it is; any other is this run's, with its digest.)
        digest = {} if existing is not None and existing.get("finished") else map_digest(args)
        self._made = not self.path.exists()
        self.path.mkdir(parents=True, exist_ok=True)
        self.algo = algo
        self._paths = given_paths(args, inputs)
        self._fields = path_fields(args, inputs)
        # What the folder held before this run's record (None: the record was there already).
        self._before = None if existing is not None else {p.name for p in self.path.iterdir()}
        if existing is not None:
            changed = differing_args(existing, algo, args, volatile, inputs, self.path)
            if changed is not None:
                # The record, not its folder, is the run: PIPS keeps NAME.train.json beside each
                # program, so one folder holds any number of them.
                raise RunDirError(
                    f"{self.file}: a {existing.get('algo')} run with other arguments "
                    f"({', '.join(changed) or 'algorithm'} differ); choose another --out"
                )
        if existing is not None and not existing.get("finished"):
            # An interrupted run trains again from its first step and logs its curves anew: the first
            # attempt's TensorBoard events showed beside them, the same steps twice.
            shutil.rmtree(self.path / "tensorboard", ignore_errors=True)
        resolved = recorded_args(plain(args), self.path, self._paths, self._fields)
        # A finished run is kept as recorded; an interrupted one trains again from its first step, so
        # its record is this command's: its command line, start and volatile arguments (--progress).
        self.record: dict[str, Any] = (
            existing
            if existing is not None and existing.get("finished")
            else {
                "algo": algo,
                "args": resolved,
                "command": recorded_command(
                    [program_name(sys.argv[0]), *sys.argv[1:]], self.path, self._paths, self._fields
                ),
                "seed": resolved.get("seed"),
                **digest,
                "package_version": __version__,
                "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                "finished": None,
            }
        )
        write_json(self.file, self.record)

    def read(self) -> dict[str, Any] | None:
        """The record of this folder, or None."""
        return read_record(self.file)

    def discard(self) -> None:
        """Undo a run that wrote nothing but its new record (one stopped at a missing input file or an
        argument its trainer refuses): the record goes, and the folder when the run made it, so the
        corrected command may use the folder. A run that wrote anything else is kept as it is."""
        if self._before is None or not self.path.is_dir():
            return
        if {p.name for p in self.path.iterdir()} - self._before == {self.file.name}:
            self.file.unlink()
            if self._made and not any(self.path.iterdir()):
                self.path.rmdir()

    @property
    def finished(self) -> bool:
        """True once `finish` was called for these arguments."""
        return bool(self.record.get("finished"))

    def finish(self, **results: Any) -> None:
        """Mark the run finished and record `results` (plain JSON: wall time, final metrics, files)."""
        self.record["finished"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        self.record["results"] = recorded(plain(results), self.path, self._paths)
        write_json(self.file, self.record)

    def recorded(self, value: Any) -> Any:
        """`value` as plain JSON with every absolute path in it (alone or inside a spec such as
        "ppo:PATH") written relative to the run folder, as run.json holds paths: for what the run
        writes besides run.json, such as the training record in its policy files' headers. Relative
        strings are left as they are: there a name ("gdc1") and a path cannot be told apart."""
        return recorded(plain(value), self.path, set())

    def checkpoint_path(self, step: int, suffix: str) -> Path:
        """checkpoints/step_<step>.<suffix> (folder created)."""
        folder = self.path / "checkpoints"
        folder.mkdir(exist_ok=True)
        return folder / f"step_{step:09d}{suffix}"

    def checkpoints(self, suffix: str) -> list[tuple[int, Path]]:
        """The checkpoints written so far, as (step, path), by step."""
        folder = self.path / "checkpoints"
        found = []
        for file in folder.glob(f"step_*{suffix}") if folder.exists() else ():
            stem = file.name[len("step_") : -len(suffix)] if suffix else file.name[len("step_") :]
            if stem.isdigit():
                found.append((int(stem), file))
        return sorted(found)

    @contextmanager
    def tensorboard(self) -> Iterator[Any]:
        """A TensorBoard SummaryWriter in tensorboard/, or a writer that drops everything when
        the tensorboard package is missing."""
        try:
            from torch.utils.tensorboard import SummaryWriter
        except ImportError:
            logger.warning("tensorboard is not installed: no TensorBoard logs for %s", self.path)
            yield _NullWriter()
            return
        writer = SummaryWriter(str(self.path / "tensorboard"))
        try:
            yield writer
        finally:
            writer.close()


def differing_args(
    record: dict[str, Any],
    algo: str,
    args: Any,
    volatile: tuple[str, ...],
    inputs: tuple[str, ...] = (),
    folder: str | Path | None = None,
) -> list[str] | None:
    """None when `record` is a run of `algo` with these arguments (fields in `volatile` aside,
    fields the record does not have yet at their defaults, path arguments at the same place
    relative to the run folder as recorded, and, in a record of absolute or working-folder paths,
    `inputs` files at the same place relative to `out`); else the differing argument names (empty
    when only the algorithm differs). `folder`: the run folder (default args.out)."""
    given, fields = given_paths(args, inputs), path_fields(args, inputs)
    folder = Path(args.out) if folder is None else Path(folder)
    as_given, theirs_all = plain(args), record.get("args", {})
    ours_all = recorded_args(as_given, folder, given, fields)
    identity = {k: v for k, v in ours_all.items() if k not in volatile}
    theirs = {k: v for k, v in theirs_all.items() if k not in volatile}
    for name, default in recorded_args(_defaults(args), folder, given, fields).items():
        if name not in theirs and name in identity and identity[name] == default:
            theirs[name] = default
    # A record of working-folder or absolute paths: its out is not as the run folder sees it.
    old_record = theirs_all.get("out") != ours_all.get("out")
    for name in inputs if old_record else ():
        if name in theirs and name in identity and theirs[name] != identity[name]:
            if _same_place(theirs[name], theirs_all.get("out"), as_given[name], as_given.get("out")):
                theirs[name] = identity[name]
    if record.get("algo") == algo and theirs == identity:
        return None
    return sorted(k for k in set(theirs) | set(identity) if theirs.get(k) != identity.get(k))


def map_digest(args: Any) -> dict[str, str]:
    """{"map_sha256": the sha256 of the contents of the map that args.map names} (map_sha256, as test
    sets and benchmark folders record it), so a record tells which map a run trained on after the file
    changed; {} for arguments without a map (and records written before the key: read as they are)."""
    name = getattr(args, "map", None)
    if not isinstance(name, (str, Path)) or not str(name):
        return {}
    from socialzoo.maps.map_file import load_map, map_sha256

    return {"map_sha256": map_sha256(load_map(name))}


def read_record(file: Path) -> dict[str, Any] | None:
    """A run record (JSON object), or None when the file does not exist.

    Raises:
        RunDirError: the file is not a run record (naming it).
    """
    if not file.exists():
        return None
    record = read_json(file, "run record", RunDirError, kind=dict)
    if not isinstance(record.get("algo"), str) or not isinstance(record.get("args"), dict):
        raise RunDirError(f"{file}: not a run record (no trainer name 'algo' and arguments 'args')")
    return record


def _same_place(before: Any, before_out: Any, current: Any, current_out: Any) -> bool:
    """Whether input path `current` lies where `before` lay, both seen from their run's `out`:
    the run folder and its inputs were moved or copied together (records written before paths
    were relative to the run folder)."""
    values = (before, before_out, current, current_out)
    if not all(isinstance(v, str) and v for v in values):
        return False
    return os.path.relpath(before, before_out) == os.path.relpath(current, current_out)


def path_fields(args: Any, inputs: tuple[str, ...] = ()) -> set[str]:
    """The names of the arguments of dataclass `args` that name paths: `out`, the `inputs` and the
    fields holding a Path."""
    names = {"out", *inputs}
    if dataclasses.is_dataclass(args):
        names |= {f.name for f in dataclasses.fields(args) if isinstance(getattr(args, f.name), Path)}
    return names


def given_paths(args: Any, inputs: tuple[str, ...] = ()) -> set[str]:
    """The paths that argument dataclass `args` names, as given: the values of its fields that hold
    a Path and of `out`, and the paths inside the `inputs` fields, each a spec (normalised; None and
    empty ones left out)."""
    found = set()
    for name in path_fields(args, inputs):
        value = getattr(args, name, None)
        items = [_spec_item(item) for item in value.split(",")] if isinstance(value, str) else []
        if name in inputs and items:
            # An input is a spec that may name files ("ppo:PATH", "eth,NAME=PATH,PATH", "ref"): its
            # "NAME:" or "NAME=" paths, and its bare items that are files (not names, such as a
            # scene's "eth" or the robot policy "ref", even when given alone).
            found |= {
                os.path.normpath(path) for prefix, path in items if path and (prefix or os.path.isfile(path))
            }
        elif isinstance(value, (str, Path)) and str(value):
            found.add(os.path.normpath(value))
    return found


def _spec_item(item: str) -> tuple[str, str]:
    """(prefix, path) of one item of a spec naming a file: "ppo:PATH" -> ("ppo:", PATH), "NAME=PATH"
    -> ("NAME=", PATH), "learned:PATH" likewise; an item without such a prefix is all path."""
    match = _SPEC_PREFIX.match(item)
    return (match.group(0), item[match.end() :]) if match else ("", item)


# One or more "name:" or "name=" in front of a path in a spec ("hybrid:learned:PATH").
_SPEC_PREFIX = re.compile(r"(?:[A-Za-z][A-Za-z0-9_.\-]*[:=])+")


def relative_path(path: str, folder: str | Path) -> str:
    """`path` (absolute, or relative to the working folder) seen from `folder`."""
    return os.path.relpath(os.path.abspath(path), os.path.abspath(folder))


def recorded(value: Any, folder: str | Path, given: set[str]) -> Any:
    """Plain JSON `value` as a run record holds it: every string that is one of the `given` paths
    or an absolute path written relative to the run `folder`."""
    if isinstance(value, dict):
        return {k: recorded(v, folder, given) for k, v in value.items()}
    if isinstance(value, list):
        return [recorded(v, folder, given) for v in value]
    if isinstance(value, str) and value and (os.path.isabs(value) or os.path.normpath(value) in given):
        return relative_path(value, folder)
    if isinstance(value, str) and any(mark in value for mark in ",:="):
        # A spec naming files ("ppo:PATH", "eth,NAME=PATH"): its paths as run records hold paths.
        items = [_spec_item(item) for item in value.split(",")]
        return ",".join(prefix + _recorded_path(path, folder, given) for prefix, path in items)
    return value


def recorded_args(
    args: dict[str, Any], folder: str | Path, given: set[str], fields: set[str]
) -> dict[str, Any]:
    """Plain arguments as a run record holds them (`recorded`), the `given` paths rewritten only in
    the path arguments `fields`: an argument that merely spells the same as a path (`--family crossing
    --out crossing`) stays as it is. Absolute paths are rewritten in every argument."""
    return {k: recorded(v, folder, given if k in fields else set()) for k, v in args.items()}


def _recorded_path(path: str, folder: str | Path, given: set[str]) -> str:
    """A path inside a spec as a run record holds it: relative to the run `folder` when it is one of
    the `given` paths or absolute ("//", as in "ray://host", is an address, not a path)."""
    if path and not path.startswith("//") and (os.path.isabs(path) or os.path.normpath(path) in given):
        return relative_path(path, folder)
    return path


def program_name(argv0: str) -> str:
    """The program as a run record names it: argv[0]'s file name, and `socialzoo` for
    `python -m socialzoo`, whose argv[0] is the package's __main__.py (not a command one can run)."""
    path = Path(argv0)
    if path.name == "__main__.py" and path.parent.name == "socialzoo":
        return "socialzoo"
    return path.name


def recorded_command(argv: list[str], folder: str | Path, given: set[str], fields: set[str]) -> str:
    """The command line as a run record holds it: each value of an option of a path argument
    `fields` ("--out DIR", "--demos=FILE", a spec naming files) that is one of the `given` paths,
    and any absolute path, written relative to the run `folder`. The words before the options
    (program, subcommand, trainer) and other options' values are no paths given, even when they
    spell the same (`socialzoo train bc --out bc`)."""
    words = []
    field = None  # the argument the words after an option are values of; None: command words
    for word in argv:
        if not word.startswith("-"):
            words.append(recorded(word, folder, given if field in fields else set()))
            continue
        option, equals, value = word.partition("=")
        name = option.lstrip("-").replace("-", "_")
        field = None if equals else name
        words.append(
            option + equals + recorded(value, folder, given if name in fields else set()) if equals else word
        )
    return shlex.join(words)


def _defaults(args: Any) -> dict[str, Any]:
    """The plain default of each field of an argument dataclass that has one."""
    if not dataclasses.is_dataclass(args):
        return {}
    found = {}
    for f in dataclasses.fields(args):
        if f.default is not dataclasses.MISSING:
            found[f.name] = plain(f.default)
        elif f.default_factory is not dataclasses.MISSING:
            found[f.name] = plain(f.default_factory())
    return found


class _NullWriter:
    def add_scalar(self, *args: Any, **kwargs: Any) -> None:
        pass


def checkpoint_steps(total: int, every: int) -> list[int]:
    """The steps at which to checkpoint: every `every` steps up to `total`, and `total` itself."""
    if every < 1 or total < 1:
        raise ValueError(f"checkpoint_steps needs total >= 1 and every >= 1, got {total!r}, {every!r}")
    steps = list(range(every, total + 1, every))
    if not steps or steps[-1] != total:
        steps.append(total)
    return steps
