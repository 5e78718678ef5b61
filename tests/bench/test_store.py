"""The results store: resume after a killed run, rereads, bad files and bad names, and two
processes creating and writing the same store at once."""

import math
import multiprocessing
import shutil
import sqlite3

import pytest

from socialzoo.bench.experiment import STORE_NAME, BenchmarkConfig, run_benchmark
from socialzoo.bench.store import ResultsStore, StoreError
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet

TRIALS = 6


@pytest.fixture(scope="module")
def rooms(rooms_map_path):
    path = rooms_map_path
    return {"rooms": TestSet(str(path), 7, 20, ScenarioConfig(min_humans=2, max_humans=5), name="rooms-test")}


def config(**changes):
    base = dict(maps=("rooms",), trials=TRIALS, batch_size=4, workers=1, env_overrides={"max_steps": 150})
    base.update(changes)
    return BenchmarkConfig(**base)


def stored(out_dir):
    """Every stored trial, without its finish time."""
    with ResultsStore(out_dir / STORE_NAME) as store:
        rows = store.rows()
    for row in rows:
        del row["finished_at"]
    return rows


def same_rows(a, b):
    def key(v):
        return "nan" if isinstance(v, float) and math.isnan(v) else v

    return [{k: key(v) for k, v in r.items()} for r in a] == [{k: key(v) for k, v in r.items()} for r in b]


class Killed(Exception):
    pass


def kill_after(k):
    seen = []

    def callback(batch):
        seen.extend(batch)
        if len(seen) >= k:
            raise Killed

    return callback


@pytest.fixture(scope="module")
def uninterrupted(rooms, tmp_path_factory):
    out = tmp_path_factory.mktemp("full")
    result = run_benchmark(config(), out, test_sets=rooms, progress=False, figures=False)
    assert (result.computed, result.reused) == (2 * TRIALS, 0)
    return out


def test_rerun_reads_instead_of_recomputing(rooms, uninterrupted, tmp_path):
    out = tmp_path / "copy"
    shutil.copytree(uninterrupted, out)
    again = run_benchmark(config(), out, test_sets=rooms, progress=False, figures=False)
    assert (again.computed, again.reused) == (0, 2 * TRIALS)
    assert same_rows(stored(out), stored(uninterrupted))
    assert sorted((r["policy"], r["scenario_index"]) for r in stored(out)) == sorted(
        (p, k) for p in ("goalone", "ref") for k in range(TRIALS)
    )
    # More trials of the same test set: only the new ones run.
    more = run_benchmark(config(trials=TRIALS + 1), out, test_sets=rooms, progress=False, figures=False)
    assert (more.computed, more.reused) == (2, 2 * TRIALS)
    # Another env config is another key: nothing is reused, nothing is overwritten.
    other = run_benchmark(
        config(env_overrides={"max_steps": 100}), out, test_sets=rooms, progress=False, figures=False
    )
    assert (other.computed, other.reused) == (2 * TRIALS, 0)
    assert len(stored(out)) == 2 * (2 * TRIALS) + 2


@pytest.mark.parametrize("workers", [1, 2])
def test_resume_after_kill_gives_the_uninterrupted_rows(rooms, uninterrupted, tmp_path, workers):
    with pytest.raises(Killed):
        run_benchmark(
            config(workers=workers),
            tmp_path,
            test_sets=rooms,
            progress=False,
            figures=False,
            on_results=kill_after(3),
        )
    partial = stored(tmp_path)
    assert 3 <= len(partial) < 2 * TRIALS
    resumed = run_benchmark(config(workers=workers), tmp_path, test_sets=rooms, progress=False, figures=False)
    assert (resumed.computed, resumed.reused) == (2 * TRIALS - len(partial), len(partial))
    assert same_rows(stored(tmp_path), stored(uninterrupted))


def test_store_round_trip(tmp_path):
    path = tmp_path / "r.sqlite"
    row = {
        "policy": "ref",
        "map": "gdc1",
        "test_set": "gdc1-test",
        "scenario_index": 3,
        "seed": 2**64 - 5,
        "config_hash": "abc",
        "package_version": "0.1.0",
        "metrics": {"success": True, "steps": 12, "time_to_goal": math.nan, "mean_force": 0.25},
    }
    with ResultsStore(path) as store:
        assert store.add([row]) == 1
        assert store.add([row]) == 0  # the key is unique: a repeat is skipped
        store.register_config("abc", {"x": 1})
    with ResultsStore(path) as store:
        (back,) = store.rows(policy="ref")
        assert back["seed"] == 2**64 - 5 and back["success"] is True and back["steps"] == 12
        assert math.isnan(back["time_to_goal"]) and back["mean_force"] == 0.25
        assert store.stored_indices("ref", "gdc1-test", "abc") == {3}
        assert store.config("abc") == {"x": 1}
        assert len(store) == 1


def test_foreign_and_corrupted_files_are_refused_and_kept(tmp_path):
    text = tmp_path / "notes.sqlite"
    text.write_bytes(b"my thesis, do not delete\n" * 100)
    foreign = tmp_path / "other.sqlite"
    with sqlite3.connect(foreign) as db:
        db.execute("CREATE TABLE people (name TEXT)")
        db.execute("INSERT INTO people VALUES ('ada')")
    db.close()
    good = tmp_path / "good.sqlite"
    with ResultsStore(good) as store:
        store.add(
            [
                {
                    "policy": "ref",
                    "map": "m",
                    "test_set": "t",
                    "scenario_index": i,
                    "seed": i,
                    "config_hash": "h",
                    "package_version": "0",
                    "metrics": {"success": True, "note": 0.5},
                }
                for i in range(200)
            ]
        )
    damaged = tmp_path / "damaged.sqlite"
    data = bytearray(good.read_bytes())
    data[200:] = b"\xff" * (len(data) - 200)  # keep the SQLite header, wreck the pages
    damaged.write_bytes(bytes(data))
    for path, pattern in (
        (text, "not an SQLite database"),
        (foreign, "not a socialzoo results store"),
        (damaged, "corrupt"),
    ):
        before = path.read_bytes()
        with pytest.raises(StoreError, match=pattern) as err:
            ResultsStore(path)
        assert str(path) in str(err.value)
        assert path.read_bytes() == before


def test_run_into_a_foreign_file_fails_before_writing(rooms, tmp_path):
    (tmp_path / STORE_NAME).write_text("not a database")
    with pytest.raises(StoreError, match=str(tmp_path / STORE_NAME)):
        run_benchmark(config(), tmp_path, test_sets=rooms, progress=False, figures=False)
    assert (tmp_path / STORE_NAME).read_text() == "not a database"
    assert sorted(p.name for p in tmp_path.iterdir()) == [STORE_NAME]


def test_unknown_policy_and_map_names(rooms, tmp_path):
    with pytest.raises(ValueError, match=r"unknown policy 'nope'.*goalone.*ref"):
        config(policies=("goalone", "nope"))
    with pytest.raises(ValueError, match=r"unknown map 'atlantis'.*gdc1.*ghc3"):
        run_benchmark(config(maps=("atlantis",)), tmp_path / "out", progress=False, figures=False)
    assert not (tmp_path / "out").exists()
    with pytest.raises(ValueError, match="holds only 20"):
        run_benchmark(config(trials=21), tmp_path / "out", test_sets=rooms, progress=False, figures=False)
    with pytest.raises(ValueError, match=r"BenchmarkConfig\.backend"):
        config(backend="slurm")


# ---------------------------------------------------------------------------- two processes at once
def trial_row(index, writer):
    """A trial row whose values depend on the index only, plus a metric of the writer's own."""
    return {
        "policy": "ref",
        "map": "m",
        "test_set": "t",
        "scenario_index": index,
        "seed": 1000 + index,
        "config_hash": "h",
        "package_version": "0",
        "metrics": {"success": index % 3 == 0, "steps": 10 * index, f"only_{writer}": 0.5},
    }


def write_trials(paths, writer, indices, barrier):
    """Child process: for each path, open (create) the store at the same moment as the other
    child, then store the trials one transaction each."""
    for path in paths:
        barrier.wait(timeout=60)
        with ResultsStore(path) as store:
            store.register_config("h", {"writer": writer})
            store.set_meta("config", writer)
            for i in indices:
                store.add([trial_row(i, writer)])


def run_children(target, args_a, args_b):
    ctx = multiprocessing.get_context("spawn")
    barrier = ctx.Barrier(2)
    children = [ctx.Process(target=target, args=(*args, barrier)) for args in (args_a, args_b)]
    for child in children:
        child.start()
    for child in children:
        child.join(timeout=300)
    return [child.exitcode for child in children]


def test_two_processes_create_and_write_one_store(tmp_path):
    paths = [tmp_path / f"round{k}" / "results.sqlite" for k in range(3)]
    codes = run_children(write_trials, (paths, "a", range(0, 40)), (paths, "b", range(20, 60)))
    assert codes == [0, 0]
    for path in paths:
        with ResultsStore(path) as store:
            rows = store.rows()
            assert len(store) == 60
            assert {"only_a", "only_b"} <= set(store.metric_names)
            assert store.config("h") in ({"writer": "a"}, {"writer": "b"})
        assert [r["scenario_index"] for r in rows] == list(range(60))  # each once
        for r in rows:
            i = r["scenario_index"]
            assert (r["seed"], r["success"], r["steps"]) == (1000 + i, i % 3 == 0, 10 * i)
            # Rows 20-39 were offered by both writers; whichever stored first, one row is kept.
            assert (r["only_a"] == 0.5) or (r["only_b"] == 0.5)
        with sqlite3.connect(path) as db:
            assert db.execute("PRAGMA journal_mode").fetchone() == ("wal",)
        db.close()


def run_rooms_benchmark(out, map_path, barrier):
    """Child process: the benchmark of `config()` on the rooms test set into `out`."""
    rooms = {
        "rooms": TestSet(str(map_path), 7, 20, ScenarioConfig(min_humans=2, max_humans=5), name="rooms-test")
    }
    barrier.wait(timeout=60)
    run_benchmark(config(), out, test_sets=rooms, progress=False, figures=False)


def test_two_benchmark_runs_share_one_output_directory(rooms_map_path, uninterrupted, tmp_path):
    codes = run_children(run_rooms_benchmark, (tmp_path, rooms_map_path), (tmp_path, rooms_map_path))
    assert codes == [0, 0]
    assert same_rows(stored(tmp_path), stored(uninterrupted))  # every trial once, as a lone run stores it
    assert (tmp_path / "summary.md").read_text() == (uninterrupted / "summary.md").read_text()
    assert not list(tmp_path.glob(".*.tmp"))


def test_a_store_locked_too_long_is_reported_plainly(tmp_path):
    path = tmp_path / "r.sqlite"
    ResultsStore(path).close()
    holder = sqlite3.connect(path)
    holder.execute("BEGIN IMMEDIATE")  # another process writing, for longer than we wait
    try:
        with ResultsStore(path, timeout=0.2) as store:
            with pytest.raises(StoreError, match=r"another process has held the results store's write lock"):
                store.add([trial_row(0, "a")])
            assert len(store) == 0  # reading still works meanwhile (WAL)
    finally:
        holder.rollback()
        holder.close()


def test_policy_named_with_its_file(rooms, tmp_path):
    """ "NAME:PATH" runs the policy NAME loaded from PATH, is stored under that name, and its
    trials are recomputed when the file changes. A PIPS program without transitions keeps the
    first action (GoAlone), so it must reproduce GoAlone trial for trial."""
    from socialzoo.agents.pips import Atom, Compare, Program, Transition

    path = tmp_path / "Prog.json"
    Program({}).save(path)
    name = f"pips:{path}"
    with pytest.raises(ValueError, match="no such file"):
        config(policies=(f"pips:{tmp_path / 'missing.json'}",))
    with pytest.raises(ValueError, match="'goalone' is not loaded from a file"):
        config(policies=(f"goalone:{path}",))
    out = tmp_path / "out"
    run_benchmark(config(policies=(name, "goalone")), out, test_sets=rooms, progress=False, figures=False)
    rows = stored(out)
    by_policy = {p: [r for r in rows if r["policy"] == p] for p in (name, "goalone")}
    assert len(by_policy[name]) == TRIALS
    for a, b in zip(by_policy[name], by_policy["goalone"], strict=True):
        assert a["scenario_index"] == b["scenario_index"] and a["steps"] == b["steps"]
        assert a["success"] == b["success"]
    halt_always = Program({0: (Transition(1, Compare(Atom("robot_v"), ">=", -1.0)),)})
    halt_always.save(path)
    result = run_benchmark(config(policies=(name,)), out, test_sets=rooms, progress=False, figures=False)
    assert result.computed == TRIALS  # another program: nothing read back
    first_hash = by_policy[name][0]["config_hash"]
    halted = [r for r in stored(out) if r["policy"] == name and r["config_hash"] != first_hash]
    assert len(halted) == TRIALS and not any(r["success"] for r in halted)


def test_the_summary_has_what_the_robot_cost_the_people_when_the_run_records_it(
    rooms, uninterrupted, tmp_path
):
    # Without --counterfactual the summary keeps the paper's columns.
    assert "people_time_lost_mean" not in (uninterrupted / "summary.csv").read_text()
    result = run_benchmark(
        config(policies=("goalone",), trials=2, counterfactual=True), tmp_path, test_sets=rooms, progress=False,
        figures=False,
    )  # fmt: skip
    header = (tmp_path / "summary.csv").read_text().splitlines()[0].split(",")
    for name in ("people_time_lost", "people_time_lost_max", "people_extra_distance"):
        assert f"{name}_mean" in header and f"{name}_ci_low" in header
        assert math.isfinite(result.summary[0][f"{name}_mean"])
    assert "## People's time lost (mean per person), s" in (tmp_path / "summary.md").read_text()


def test_a_bad_policy_file_or_store_is_refused_before_a_test_set_is_made(rooms_map_path, tmp_path):
    """A map without a registered test set gets one generated (2000 scenarios: minutes) before the
    run: a policy file that cannot be read, or an unusable store, was refused only after that."""
    bad = tmp_path / "bad.safetensors"
    bad.write_text("garbage")
    out = tmp_path / "out"
    with pytest.raises(ValueError, match="not a safetensors policy file"):
        run_benchmark(
            config(maps=(str(rooms_map_path),), policies=("goalone", f"ppo:{bad}"), trials=2),
            out,
            progress=False,
            figures=False,
        )
    assert not out.exists()
    out.mkdir()
    (out / STORE_NAME).write_text("not a database")
    with pytest.raises(StoreError, match="not an SQLite database"):
        run_benchmark(config(maps=(str(rooms_map_path),), trials=2), out, progress=False, figures=False)
    assert sorted(p.name for p in out.iterdir()) == [STORE_NAME]  # no test_sets/ made


def test_a_learned_policy_of_another_observation_layout_is_refused_before_any_trial(tmp_path):
    """The shipped PPO reads the default layout's 107 numbers; on a benchmark whose env config reads the
    social_gym 1.0 layout (another size) it was refused only when it first acted, after the run had
    begun and the store was made ("2 trials to run"). It is refused with the sizes before any trial."""
    from socialzoo.agents import PolicyTaskError

    out = tmp_path / "out"
    layout = {"observation": {"layout": "socialgym1"}}
    with pytest.raises(
        PolicyTaskError, match=r"policy 'ppo' reads observations of 107 numbers .* have (?!107)\d+"
    ):
        run_benchmark(
            config(maps=("open_room",), policies=("goalone", "ppo"), trials=2, env_overrides=layout),
            out,
            progress=False,
            figures=False,
        )
    assert not (out / STORE_NAME).exists()
