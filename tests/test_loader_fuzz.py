"""Every loader a user can point at a file refuses damaged and foreign files with its own named
error, and that error names the file: random bytes, a valid head with a random tail, truncated
copies, an empty file, a missing file, a folder in the file's place, and every other kind of file the
package reads or writes.

One table (LOADERS) lists each loader with a maker of a small valid sample, the kind of that
sample, and the error class it must raise; the corrupted files are derived from the samples, so
adding a loader to the table fuzzes it against every other kind too.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from socialzoo.agents import SHIPPED_DIR, make_policy
from socialzoo.agents.demonstrations import (
    DEMO_FORMAT,
    DemonstrationError,
    load_demonstrations,
    read_metadata,
    read_parts,
)
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.agents.pips import PipsPolicy, ProgramError, load_program
from socialzoo.bench import test_sets
from socialzoo.bench.episode_log import EpisodeLogError, make_episode_log, read_episode_log, write_episode_log
from socialzoo.bench.store import ResultsStore, StoreError
from socialzoo.bench.tables import PAPER_LAYOUT, SummaryError, read_summary_csv, write_summary_csv
from socialzoo.env.human_policy import LearnedHumanPolicy
from socialzoo.env.policy_file import PolicyFileError, read_policy_file
from socialzoo.maps.importers import (
    read_amrl_nav_graph,
    read_pedsim_scene,
    read_table,
    read_vector_map,
    write_vector_map,
)
from socialzoo.maps.map_file import MapError, load_map, read_map
from socialzoo.reproduce import results
from socialzoo.reproduce.ledger import Ledger, LedgerError
from socialzoo.reproduce.plan import quick_settings, settings_hash
from socialzoo.scenarios.cards import CardError, card_path, load_card
from socialzoo.scenarios.generator import generate_scenario
from socialzoo.scenarios.scenario import Scenario, ScenarioError
from socialzoo.train.demo_data import load_demo_steps
from socialzoo.train.run_dir import RunDir, RunDirError

MAP = "open_room"  # the smallest shipped map: samples stay a few kB
SETTINGS = quick_settings()


@dataclass(frozen=True)
class Loader:
    """One loader of the table.

    Attributes:
        name: the test id.
        load: reads the file at the path it is given (the path ends in `filename`).
        make: writes a small valid sample at that path (and any files beside it that it needs).
        error: the named exception the loader raises for a bad file.
        kind: what kind of file the sample is; the samples of other kinds are its wrong kinds.
        filename: where the file lives, relative to a fresh folder.
        accepts: other kinds the loader reads as valid (a learned human file is a policy file).
        missing_ok, empty_ok: a missing or empty file starts a new one (stores, run records).
        line_based: a text format without an end marker: a truncation at a line end is a valid,
            shorter file, so a truncated copy is either refused or read.
    """

    name: str
    load: Callable[[Path], Any]
    make: Callable[[Path], Any]
    error: type[Exception]
    kind: str
    filename: str
    accepts: frozenset[str] = frozenset()
    missing_ok: bool = False
    empty_ok: bool = False
    line_based: bool = False


# ------------------------------------------------------------------------------ sample makers
def _copy(source: Path) -> Callable[[Path], Any]:
    return lambda path: shutil.copyfile(source, path)


def _write_demos(path: Path) -> None:
    n = 6
    np.savez_compressed(
        path,
        obs=np.zeros((n, 3), np.float32),
        action=np.arange(n, dtype=np.int64) % 4,
        next_obs=np.ones((n, 3), np.float32),
        reward=np.zeros(n, np.float32),
        terminated=np.zeros(n, bool),
        truncated=np.zeros(n, bool),
        episode=np.repeat(np.arange(2, dtype=np.int64), 3),
        episode_ids=np.arange(2, dtype=np.int64),
        episode_seeds=np.arange(2, dtype=np.uint64) + 7,
        episode_lengths=np.full(2, 3, np.int64),
        metadata=np.array(json.dumps({"format": DEMO_FORMAT, "config_hash": "abc", "env_config": {}})),
    )


def _write_parts(path: Path) -> None:
    """A recording in progress: `path` is its index.json or its one chunk."""
    parts = path.parent
    _write_demos(parts / "chunk_00000.npz")
    index = {"metadata": {"format": DEMO_FORMAT}, "chunks": {"chunk_00000.npz": {"steps": 6}}}
    (parts / "index.json").write_text(json.dumps(index, indent=1) + "\n")


def _write_store(path: Path) -> None:
    with ResultsStore(path) as store:
        store.register_config("h", {"env": {}})
        row = {"policy": "ref", "map": MAP, "test_set": "t", "scenario_index": 0, "seed": 1}
        store.add([{**row, "config_hash": "h", "package_version": "0", "metrics": {"success": True}}])


def _write_summary(path: Path) -> None:
    entry = {c: 0.25 for c in PAPER_LAYOUT.csv_columns()}
    entry.update(policy="ref", map=MAP, test_set="t", trials=4)
    entry.update({c: 4 for c in PAPER_LAYOUT.csv_columns() if c.endswith("_n")})
    write_summary_csv([entry, {**entry, "policy": "goalone"}], path)


def _write_results_run(path: Path) -> None:
    run = {
        "settings": SETTINGS.to_json(),
        "settings_hash": settings_hash(SETTINGS),
        "command": "socialzoo reproduce --out DIR --quick",
        "machine": {},
        "parts_last_run": [],
        "demo_steps": None,
    }
    path.write_text(json.dumps(run, indent=1) + "\n")


def _write_timings(path: Path) -> None:
    ledger = Ledger(path.parent.parent, SETTINGS)
    with ledger.timed("demos", "local") as session:
        session["computed"] = 0


def _write_episode_log(path: Path) -> None:
    people = np.array([[[3.0, 3.0]], [[3.0, 3.2]], [[3.0, 3.4]]])
    log = make_episode_log(
        dt=0.5,
        robot_pos=[[0, 0], [0.5, 0], [1, 0]],
        goal=[1, 0],
        robot_radius=0.3,
        goal_radius=0.2,
        people_pos=people,
        walls=[[0, 1, 2, 1]],
        label="fuzz",
    )
    write_episode_log(path, log)


@dataclass(frozen=True)
class _Args:
    seed: int = 0


def _pips_spec(path: Path) -> Any:
    return make_policy(f"pips:{path}")


def _ppo_spec(path: Path) -> Any:
    return make_policy(f"ppo:{path}")


def _stored_test_set(path: Path) -> Any:
    return test_sets.stored_test_set(MAP, path.parent.parent, 2, quick=True)


_HASH = settings_hash(SETTINGS)
LOADERS = [
    # Policies.
    Loader("read_policy_file", read_policy_file, _copy(SHIPPED_DIR / "ppo.safetensors"), PolicyFileError,
           "policy-mlp", "p.safetensors", accepts=frozenset({"policy-humans"})),
    Loader("MlpPolicy.load", MlpPolicy.load, _copy(SHIPPED_DIR / "ppo.safetensors"), PolicyFileError,
           "policy-mlp", "p.safetensors"),
    Loader("make_policy(ppo:FILE)", _ppo_spec, _copy(SHIPPED_DIR / "ppo.safetensors"), PolicyFileError,
           "policy-mlp", "p.safetensors"),
    Loader("LearnedHumanPolicy.load", LearnedHumanPolicy.load, _copy(SHIPPED_DIR / "humans.safetensors"),
           PolicyFileError, "policy-humans", "h.safetensors"),
    Loader("load_program", load_program, _copy(SHIPPED_DIR / "pips.json"), ProgramError, "pips", "p.json"),
    Loader("PipsPolicy.load", PipsPolicy.load, _copy(SHIPPED_DIR / "pips.json"), ProgramError, "pips", "p.json"),
    Loader("make_policy(pips:FILE)", _pips_spec, _copy(SHIPPED_DIR / "pips.json"), PolicyFileError,
           "pips", "p.json"),
    # Maps and what the importers read.
    Loader("read_map", read_map, lambda p: load_map(MAP).save(p), MapError, "map", "m.json"),
    Loader("load_map(path)", load_map, lambda p: load_map(MAP).save(p), MapError, "map", "m.json"),
    Loader("read_vector_map", read_vector_map,
           lambda p: write_vector_map(p, np.array([[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, 3.5]])),
           MapError, "vector-map", "walls.txt", line_based=True),
    Loader("read_table", lambda p: read_table(p, 4, "x1, y1, x2, y2"),
           lambda p: write_vector_map(p, np.array([[0, 0, 4, 0], [4, 0, 4, 3]])),
           MapError, "vector-map", "walls.txt", line_based=True, empty_ok=True),
    Loader("read_amrl_nav_graph", read_amrl_nav_graph,
           lambda p: p.write_text(json.dumps({
               "nodes": [{"id": 3, "loc": {"x": 0.0, "y": 0.0}}, {"id": 7, "loc": {"x": 1.0, "y": 0.5}}],
               "edges": [{"s0_id": 3, "s1_id": 7}],
           }, indent=1) + "\n"),
           MapError, "amrl-nav", "nav.json"),
    Loader("read_pedsim_scene", read_pedsim_scene,
           lambda p: p.write_text(
               '<?xml version="1.0"?>\n<scenario>\n  <obstacle x1="0" y1="0" x2="5" y2="0"/>\n'
               '  <waypoint id="a" x="1" y="1" r="0.5"/>\n</scenario>\n'
           ),
           MapError, "pedsim", "scene.xml"),
    Loader("Scenario.load", Scenario.load, lambda p: generate_scenario(load_map(MAP), 0).save(p),
           ScenarioError, "scenario", "s.json"),
    Loader("load_card", load_card, _copy(card_path("frontal_approach")), CardError, "card",
           "frontal_approach.toml"),
    # Demonstrations.
    Loader("read_metadata", read_metadata, _write_demos, DemonstrationError, "demos", "d.npz"),
    Loader("load_demonstrations", load_demonstrations, _write_demos, DemonstrationError, "demos", "d.npz"),
    Loader("load_demo_steps", load_demo_steps, _write_demos, DemonstrationError, "demos", "d.npz"),
    Loader("load_demonstrations(index.json)", lambda p: load_demonstrations(p.parent.with_suffix("")),
           _write_parts, DemonstrationError, "demo-index", "d.npz.parts/index.json"),
    Loader("read_parts(chunk)", lambda p: read_parts(p.parent), _write_parts, DemonstrationError,
           "demos", "d.npz.parts/chunk_00000.npz"),
    # Results.
    Loader("ResultsStore", lambda p: ResultsStore(p).close(), _write_store, StoreError, "store",
           "results.sqlite", missing_ok=True, empty_ok=True),
    Loader("stored_test_set", _stored_test_set, _stored_test_set, test_sets.TestSetError, "test-set",
           f"test_sets/{MAP}-quick.json", missing_ok=True),
    Loader("read_summary_csv", read_summary_csv, _write_summary, SummaryError, "summary-csv", "summary.csv",
           line_based=True),
    Loader("read_episode_log", read_episode_log, _write_episode_log, EpisodeLogError, "episode-log", "e.json"),
    # Records of runs and reproductions.
    Loader("reproduce results.load(run.json)", lambda p: results.load(p.parent), _write_results_run,
           results.ResultsError, "results-run", "results/run.json"),
    Loader("Ledger(settings.json)", lambda p: Ledger(p.parent.parent, SETTINGS),
           lambda p: Ledger(p.parent.parent, SETTINGS), LedgerError, "ledger-settings",
           f"{_HASH}/settings.json", missing_ok=True),
    Loader("Ledger.timings", lambda p: Ledger(p.parent.parent, SETTINGS).timings(), _write_timings,
           LedgerError, "ledger-timings", f"{_HASH}/timings.json", missing_ok=True,
           accepts=frozenset({"json-empty-object"})),
    Loader("RunDir(run.json)", lambda p: RunDir(p.parent, "ppo", _Args()),
           lambda p: RunDir(p.parent, "ppo", _Args()), RunDirError, "run-record", "run/run.json",
           missing_ok=True),
]  # fmt: skip

# Files of kinds no loader above reads: they are wrong kinds for every loader.
EXTRA_KINDS: dict[str, bytes] = {
    "json-list": b"[1, 2, 3]\n",
    "json-string": b'"socialzoo"\n',
    "json-empty-object": b"{}\n",
    "text": b"hello world\n",
    # JSON that json.loads refuses with RecursionError and with ValueError (not JSONDecodeError).
    "json-deep-nesting": b"[" * 100_000,
    "json-huge-number": b"[" + b"7" * 5000 + b"]",
}


def _npy_bytes(value: np.ndarray, allow_pickle: bool = False) -> bytes:
    import io

    buffer = io.BytesIO()
    np.save(buffer, value, allow_pickle=allow_pickle)
    return buffer.getvalue()


def _npz_bytes(**arrays: np.ndarray) -> bytes:
    import io

    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    return buffer.getvalue()


EXTRA_KINDS["npy"] = _npy_bytes(np.arange(5.0))
EXTRA_KINDS["npy-pickled"] = _npy_bytes(np.array([{"a": 1}], dtype=object), allow_pickle=True)
EXTRA_KINDS["foreign-npz"] = _npz_bytes(x=np.zeros(3))


# ------------------------------------------------------------------------------ fixtures
@pytest.fixture(scope="module")
def samples(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Each loader's valid sample, in a folder of its own (made once, copied for every case)."""
    root = tmp_path_factory.mktemp("samples")
    out = {}
    for i, loader in enumerate(LOADERS):
        folder = root / f"{i:02d}"
        path = folder / loader.filename
        path.parent.mkdir(parents=True)
        loader.make(path)
        out[loader.name] = folder
    return out


@pytest.fixture(scope="module")
def kinds(samples: dict[str, Path]) -> dict[str, bytes]:
    """The bytes of one sample of every kind, plus EXTRA_KINDS."""
    out: dict[str, bytes] = {}
    for loader in LOADERS:
        out.setdefault(loader.kind, (samples[loader.name] / loader.filename).read_bytes())
    return {**out, **EXTRA_KINDS}


def _case(loader: Loader, samples: dict[str, Path], folder: Path, data: bytes | None) -> Path:
    """A copy of the loader's sample folder in `folder` with its file replaced by `data`
    (None: removed)."""
    shutil.copytree(samples[loader.name], folder)
    path = folder / loader.filename
    if data is None:
        path.unlink()
    else:
        path.write_bytes(data)
    return path


def _problem(
    loader: Loader,
    path: Path,
    what: str,
    error: type[Exception] | tuple[type[Exception], ...],
    *,
    may_load: bool = False,
) -> str | None:
    """What is wrong with how `loader` treats the file at `path` (None: it refused it as it should)."""
    try:
        loader.load(path)
    except Exception as err:
        text = str(err)
        if not isinstance(err, error):
            return f"{what}: {type(err).__name__}: {text[:200]}"
        # A missing index.json is named as the folder that lacks it.
        if str(path) not in text and not (str(path.parent) in text and path.name in text):
            return f"{what}: the {type(err).__name__} does not name the file: {text[:200]}"
        return None
    return None if may_load else f"{what}: loaded without an error"


def _assert_refused(loader: Loader, problems: list[str | None]) -> None:
    found = [p for p in problems if p is not None]
    assert not found, f"{loader.name} ({loader.error.__name__} expected):\n" + "\n".join(found)


def _params(gaps: dict[str, str]) -> list[Any]:
    """LOADERS as test parameters, those named in `gaps` marked as known to fail (and why)."""
    return [
        pytest.param(loader, id=loader.name, marks=pytest.mark.xfail(reason=gaps[loader.name], strict=True))
        if loader.name in gaps
        else pytest.param(loader, id=loader.name)
        for loader in LOADERS
    ]


ALL = _params({})
IDS = [loader.name for loader in LOADERS]


# ------------------------------------------------------------------------------ tests
@pytest.mark.parametrize("loader", ALL)
def test_the_valid_sample_loads(loader: Loader, samples: dict[str, Path], tmp_path: Path) -> None:
    path = _case(loader, samples, tmp_path / "case", (samples[loader.name] / loader.filename).read_bytes())
    loader.load(path)


@pytest.mark.parametrize("loader", ALL)
def test_random_bytes_are_refused(loader: Loader, samples: dict[str, Path], tmp_path: Path) -> None:
    rng = np.random.default_rng(IDS.index(loader.name))
    valid = (samples[loader.name] / loader.filename).read_bytes()
    cases = {
        "random bytes": rng.bytes(1000),
        "a few random bytes": rng.bytes(7),
        # The right magic number (zip, SQLite, safetensors length, JSON opening) then garbage.
        "a valid head and a random tail": valid[:16] + rng.bytes(1000),
    }
    problems = []
    for k, (what, data) in enumerate(cases.items()):
        path = _case(loader, samples, tmp_path / f"case{k}", data)
        problems.append(_problem(loader, path, what, loader.error))
    _assert_refused(loader, problems)


@pytest.mark.parametrize("loader", ALL)
def test_truncated_copies_are_refused(loader: Loader, samples: dict[str, Path], tmp_path: Path) -> None:
    valid = (samples[loader.name] / loader.filename).read_bytes()
    cuts = sorted({1, len(valid) // 4, len(valid) // 2, 3 * len(valid) // 4, len(valid) - 2})
    problems = []
    for cut in cuts:
        path = _case(loader, samples, tmp_path / f"cut{cut}", valid[:cut])
        what = f"truncated to {cut} of {len(valid)} bytes"
        problems.append(_problem(loader, path, what, loader.error, may_load=loader.line_based))
    _assert_refused(loader, problems)


@pytest.mark.parametrize("loader", ALL)
def test_an_empty_or_missing_file_is_refused(
    loader: Loader, samples: dict[str, Path], tmp_path: Path
) -> None:
    path = _case(loader, samples, tmp_path / "empty", b"")
    if loader.empty_ok:
        loader.load(path)
    else:
        _assert_refused(loader, [_problem(loader, path, "an empty file", loader.error)])
    path = _case(loader, samples, tmp_path / "missing", None)
    if loader.missing_ok:
        loader.load(path)
    else:
        _assert_refused(loader, [_problem(loader, path, "a missing file", (FileNotFoundError, loader.error))])


@pytest.mark.parametrize("loader", _params({}))
def test_files_of_other_kinds_are_refused(
    loader: Loader, samples: dict[str, Path], kinds: dict[str, bytes], tmp_path: Path
) -> None:
    wrong = {k: v for k, v in kinds.items() if k != loader.kind and k not in loader.accepts}
    assert len(wrong) >= 15
    problems = []
    for kind, data in wrong.items():
        path = _case(loader, samples, tmp_path / kind, data)
        problems.append(_problem(loader, path, f"a {kind} file", loader.error))
    _assert_refused(loader, problems)


@pytest.mark.parametrize("loader", ALL)
def test_a_folder_in_place_of_the_file_is_refused(
    loader: Loader, samples: dict[str, Path], tmp_path: Path
) -> None:
    path = _case(loader, samples, tmp_path / "folder", None)
    path.mkdir()  # `mkdir -p DIR/results.sqlite`, or a path typed with a slash too many
    (path / "inside.txt").write_text("a folder given where a file belongs\n")
    _assert_refused(loader, [_problem(loader, path, "a folder", loader.error)])
