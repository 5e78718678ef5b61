"""The small result files of a reproduction, DIR/results/, from which every table, figure and number of
REPRODUCTION.md is drawn (socialzoo.reproduce.report)."""

from __future__ import annotations

import math
import shutil
from pathlib import Path
from typing import Any

from socialzoo.bench.tables import read_csv_rows, write_csv
from socialzoo.core.files import read_json, write_json
from socialzoo.reproduce.ledger import TIMINGS_FILE, Ledger, machine
from socialzoo.reproduce.paper import paper_lfd
from socialzoo.reproduce.runs import ALONE_FOLDER, DEMOS_FILE, REFERENCE_FILE, REFERENCE_FOLDER, SEEDS_DIR

RESULTS_DIR = "results"
RUN_FILE = "run.json"
TRAINING_FILE = "training.json"
CSV_FILES: dict[str, str] = {
    "rl_curves": "rl_curves.csv",
    "lfd": "lfd.csv",
    "performance": "performance.csv",
    "transfer": "transfer.csv",
    "selection": "selection.csv",
    "seeds": "seeds.csv",
    "improvement": "improvement.csv",
    "profiles": "profiles.csv",
    "reference": "reference.csv",
    "kernel_paths": "kernel_paths.csv",
}
# Columns that hold text; every other CSV cell is read as a number (empty: NaN).
TEXT_COLUMNS = frozenset(
    {
        "label",
        "policy",
        "map",
        "test_set",
        "policy_file",
        "experiment",
        "quirks",
        "run",
        "x",
        "y",
        "seed_list",
        "seed_success_pct",
        "paper_where",
        "paper_in_interval",
        "kernel_path",
        "settings",
        "first_differing_update",
    }
)


# Entries of run.json the report reads.
RUN_KEYS = ("settings", "settings_hash", "command", "machine")


class ResultsError(ValueError):
    """A file of a results folder that cannot be read: not UTF-8 JSON or CSV, of another kind, or
    cut short; the message names the file."""


def command_for(settings_name: str, seeds: int = 1) -> str:
    """The command that makes a reproduction of these settings (`seeds` training seeds)."""
    command = "socialzoo reproduce --out DIR" + (" --quick" if settings_name == "quick" else "")
    return command + (f" --seeds {seeds}" if seeds > 1 else "")


def _training_record(ledger: Ledger) -> list[dict[str, Any]]:
    """Each finished training run under the work folder: what it was and how long it took."""
    out = []
    records = [
        *ledger.work.glob("*/*/run.json"),
        *ledger.work.glob(f"{REFERENCE_FOLDER}/rl/*/run.json"),
        *ledger.work.glob(f"{REFERENCE_FOLDER}/{ALONE_FOLDER}/*/rl/*/run.json"),
    ]
    for record in sorted(records):
        data = _read_json(record, dict)
        if not data.get("finished"):
            continue
        args, res = data.get("args", {}), data.get("results", {})
        out.append(
            {
                "run": record.parent.relative_to(ledger.work).as_posix(),
                "trainer": data.get("algo"),
                "demonstration_steps": args.get("steps") if data.get("algo") in ("bc", "gail") else None,
                "env_steps": res.get("env_steps"),
                "wall_seconds": res.get("wall_seconds"),
                "seed": data.get("seed"),
                "machine": machine_summary(data.get("machine")),
            }
        )
    from socialzoo.train.pips import read_program_record

    for program in sorted(ledger.work.glob("lfd/pips_*/pips.json")):
        data = read_program_record(program)
        if not data:
            continue
        out.append(
            {
                "run": program.parent.relative_to(ledger.work).as_posix(),
                "trainer": "pips",
                "demonstration_steps": data["args"]["steps"],
                "env_steps": None,
                "wall_seconds": round(data.get("wall_seconds", data.get("total_seconds", 0.0)), 1),
                "seed": data.get("seed"),
            }
        )
    return out


def machine_summary(facts: Any) -> dict[str, Any] | None:
    """What of a run record's machine facts (socialzoo.train.machine) decides torch-trained numbers:
    CPU model and kernel flags, torch's version, CPU capability and BLAS, its threads, the thread
    and ISA variables set; None for a record without facts (written before they were recorded)."""
    if not isinstance(facts, dict):
        return None
    cpu, torch = facts.get("cpu") or {}, facts.get("torch") or {}
    build = torch.get("build") or {}
    return {
        "cpu": cpu.get("model"),
        "kernel_flags": " ".join(cpu.get("kernel_flags") or ()),
        "torch": torch.get("version"),
        "cpu_capability": build.get("cpu_capability"),
        "blas": " ".join(str(build[k]) for k in ("blas", "mkl", "onednn") if build.get(k)),
        "threads": torch.get("threads"),
        "deterministic": torch.get("deterministic_algorithms"),
        "env": " ".join(f"{k}={v}" for k, v in sorted((facts.get("env") or {}).items())),
    }


def _demo_steps(ledger: Ledger) -> int | None:
    """Steps in the run's demonstration file (None before it is recorded)."""
    import numpy as np

    path = ledger.path("demos", DEMOS_FILE)
    if not path.is_file():
        return None
    with np.load(path) as data:
        return int(data["action"].shape[0])


def _lfd_rows(path: Path) -> list[dict[str, Any]]:
    """The LfD CSV with the paper's numbers of every row (PIPS's too, SPEC section 10)."""
    rows = read_csv(path)
    for row in rows:
        paper = paper_lfd(str(row["policy"]), int(row["demonstration_steps"]))
        row["paper_success_pct"] = paper[0] if paper else math.nan
        row["paper_average_step_reward"] = paper[1] if paper else math.nan
        row.pop("policy_file", None)  # a path of this machine
    return rows


def collect(ledger: Ledger, out_dir: str | Path, parts: tuple[str, ...]) -> Path:
    """Copy the run's small results out of its work folder into out_dir/results/; returns that folder.

    Results of parts that have not run (yet) are left out, and earlier copies of them removed.

        run.json          settings, their hash, the command, the machine, the parts run
        timings.json      each part's sessions and wall time
        training.json     each trained policy: trainer, demonstration steps, wall seconds, env steps
        rl_curves.csv     every PPO/DQN checkpoint (and Ref) on the curve scenarios
        lfd.csv           the LfD table rows (ours and the paper's)
        performance.csv   the seven policies on gdc1-test (socialzoo.bench.tables summary columns)
        transfer.csv      the same on ghc3-test
        selection.csv     the checkpoint each RL run kept, chosen on validation scenarios
        seeds.csv, improvement.csv, profiles.csv    with several training seeds: the aggregates over
                          them (socialzoo.reproduce.seeds)
        reference.csv     with `--reference`: PPO and DQN with the reference code's quirks, per
                          quirk set, experiment and seed (socialzoo.reproduce.parts.run_reference)
        kernel_paths.csv  one BC training under several CPU kernel paths (tools/kernel_paths.py
                          --csv; not made by a reproduction, so `collect` leaves it as it is)

    The work folder DIR/<hash>/ is where the stores and runs are.
    """
    results = Path(out_dir) / RESULTS_DIR
    results.mkdir(parents=True, exist_ok=True)
    write_json(
        results / RUN_FILE,
        {
            "settings": ledger.settings.to_json(),
            "settings_hash": ledger.hash,
            "command": command_for(ledger.settings.name, ledger.settings.seeds),
            "machine": machine(),
            "parts_last_run": list(parts),
            "demo_steps": _demo_steps(ledger),
        },
    )
    if (ledger.work / TIMINGS_FILE).is_file():
        shutil.copyfile(ledger.work / TIMINGS_FILE, results / TIMINGS_FILE)
    write_json(results / TRAINING_FILE, _training_record(ledger))
    sources = {
        "rl_curves": ledger.path("rl", "curves", "rl_curves.csv"),
        "lfd": ledger.path("lfd", "eval", "lfd.csv"),
        "performance": ledger.path("performance", "summary.csv"),
        "transfer": ledger.path("transfer", "summary.csv"),
        "reference": ledger.path(REFERENCE_FOLDER, REFERENCE_FILE),
        **{
            key: ledger.path(SEEDS_DIR, CSV_FILES[key])
            for key in ("selection", "seeds", "improvement", "profiles")
        },
    }
    for key, source in sources.items():
        target = results / CSV_FILES[key]
        if not source.is_file():
            target.unlink(missing_ok=True)
        elif key == "lfd":
            write_csv(_lfd_rows(source), target)
        else:
            shutil.copyfile(source, target)
    return results


def _cell(column: str, value: str) -> Any:
    if column in TEXT_COLUMNS:
        return value
    if value == "":
        return math.nan
    try:
        return float(value)
    except ValueError:
        return value


def read_csv(path: str | Path) -> list[dict[str, Any]]:
    """A CSV's rows, numbers as floats (empty cells NaN), TEXT_COLUMNS as text.

    Raises:
        FileNotFoundError: no such file.
        ResultsError: not UTF-8 CSV, or a row whose cells do not match the header (a file cut
            short); the message names the file and line.
    """
    return read_csv_rows(path, "results file", ResultsError, _cell)


def _read_json(path: Path, kind: type) -> Any:
    """The JSON value of `path`, which must be a `kind` (dict or list)."""
    return read_json(path, "results file", ResultsError, kind=kind)


def load(results_dir: str | Path) -> dict[str, Any]:
    """Everything under a results folder: "run", "timings", "training" (JSON) and the CSV tables
    (lists of rows; an absent file: an empty list).

    Numbers are read back as floats, so the report never needs the big stores.

    Raises:
        FileNotFoundError: no run.json (not a reproduction's results folder).
        ResultsError: a file that cannot be read (random bytes, a truncated file, a file of
            another kind, a run.json without the entries the report reads); the message names it.
    """
    folder = Path(results_dir)
    run_file = folder / RUN_FILE
    if not run_file.exists():  # a folder there is refused by _read_json, not taken for no file
        raise FileNotFoundError(f"{folder}: no {RUN_FILE}; not the results of `socialzoo reproduce`")
    data: dict[str, Any] = {"run": _read_json(run_file, dict)}
    missing = [k for k in RUN_KEYS if k not in data["run"]]
    if missing or not isinstance(data["run"].get("settings"), dict):
        raise ResultsError(
            f"{run_file}: not the run record of a reproduction (it lacks {missing or ['settings']})"
        )
    for key, name in (("timings", TIMINGS_FILE), ("training", TRAINING_FILE)):
        file = folder / name
        kind = dict if key == "timings" else list
        data[key] = _read_json(file, kind) if file.is_file() else kind()
    for key, name in CSV_FILES.items():
        file = folder / name
        data[key] = read_csv(file) if file.is_file() else []
    return data
