"""One learned policy's rows of a published reproduction replaced by a re-run of its seeds (`replace_policy_rows`),
for a trainer that changed after the full run while every other policy's runs stay valid."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from socialzoo.bench.tables import summarize, write_csv
from socialzoo.core.files import write_json
from socialzoo.reproduce.paper import EXPERIMENT_MAPS, PAPER_SUCCESS, paper_lfd
from socialzoo.reproduce.results import CSV_FILES, RESULTS_DIR, RUN_FILE, TRAINING_FILE
from socialzoo.reproduce.seeds import IMPROVEMENT_PAIRS
from socialzoo.studies.seeds import SeedGroup, benchmark_rows, improvement_rows, profile_rows, seed_rows

# The policies with a row in the LfD table (PPO and DQN have none).
LFD_POLICIES = ("bc", "gail", "pips")
# The summary columns of an LfD row (lfd.csv's name: the summary's).
LFD_COLUMNS = {
    "trials": "trials",
    "success_rate": "success_rate",
    "success_ci_low": "success_ci_low",
    "success_ci_high": "success_ci_high",
    "average_step_reward": "average_step_reward_mean",
    "average_step_reward_ci_low": "average_step_reward_ci_low",
    "average_step_reward_ci_high": "average_step_reward_ci_high",
}


class RerunError(ValueError):
    """A re-run that cannot replace the published rows; the message names what is missing."""


@dataclass(frozen=True)
class PolicyRerun:
    """A re-run of one learned policy's seeds.

    Attributes:
        policy: the registry name ("pips").
        seed_specs: training seed -> the policy spec its benchmark folders hold ("pips:/x/s0.json");
            the seeds of the published run, every one.
        performance: a benchmark folder with every seed on gdc1-test (at least the published
            trials, the first ones).
        transfer: the same on ghc3-test.
        ref: a benchmark folder with "ref" on both maps (the same trials).
        commands: the commands that made the policy files and the folders (for the record).
        commit: the repository commit they ran at.
        training: training.json records of the re-run trainings (replacing the policy's).
        why: one sentence: why the rows were re-run.
        ref_tolerance: how many scenarios Ref's successes may differ by from the published run's
            on each map (0: none). Evaluations before commit ca3fa96 depended slightly on how the
            trials were batched (docs/reproduce.md, "What a re-run may differ by"), so a re-run
            of an older published run may differ by a few; run.json records both counts.
    """

    policy: str
    seed_specs: Mapping[int, str]
    performance: Path
    transfer: Path
    ref: Path
    commands: Sequence[str] = ()
    commit: str = ""
    training: Sequence[Mapping[str, Any]] = field(default_factory=tuple)
    why: str = ""
    ref_tolerance: int = 0


def _raw_csv(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    """(header, rows as the text cells): rows not replaced are written back unchanged."""
    reader = csv.DictReader(io.StringIO(path.read_text(), newline=""))
    rows = list(reader)
    return list(reader.fieldnames or []), rows


def _trials(folder: Path, spec: str, map_name: str, trials: int) -> list[dict[str, Any]]:
    """The first `trials` scenarios of `spec` on `map_name` in a benchmark folder."""
    try:
        rows = [
            r for r in benchmark_rows(folder, spec) if r["map"] == map_name and r["scenario_index"] < trials
        ]
    except (KeyError, FileNotFoundError) as err:
        raise RerunError(f"{folder}: no trials of {spec} ({err})") from None
    if len(rows) < trials:
        raise RerunError(f"{folder}: {spec} has {len(rows)} of the first {trials} {map_name} scenarios")
    return rows


def _summary(rows: list[dict[str, Any]], policy: str) -> dict[str, Any]:
    """The summary entry of trial rows under the published label (its bootstrap streams are
    seeded by the label, socialzoo.bench.aggregates.cell_generator)."""
    return summarize([{**r, "policy": policy} for r in rows])[0]


def _scores(rows: list[dict[str, Any]]) -> dict[int, float]:
    return {int(r["scenario_index"]): float(bool(r["success"])) for r in rows}


def _replace(path: Path, key: Any, new: list[dict[str, Any]]) -> None:
    """Rewrite a CSV with every row whose `key(row)` is a key of `new`'s rows replaced by the new
    rows of that key, in the old rows' place (new keys last); other rows unchanged."""
    header, rows = _raw_csv(path)
    groups: dict[Any, list[dict[str, Any]]] = {}
    for row in new:
        groups.setdefault(key(row), []).append(row)
    out: list[dict[str, Any]] = []
    for row in rows:
        k = key(row)
        if k not in groups:
            out.append(row)
        elif groups[k]:
            out += groups[k]
            groups[k] = []  # the group is in; its other old rows go
    out += [row for rows_left in groups.values() for row in rows_left]
    write_csv(out, path, header)


def replace_policy_rows(base_dir: str | Path, rerun: PolicyRerun) -> list[Path]:
    """Put a re-run's trials into base_dir/results/ in place of the policy's published rows;
    returns the files rewritten. Tables, figures and reports are then drawn again from the folder
    (socialzoo.reproduce.publish.regenerate_report, write_report).

    Raises:
        RerunError: a seed missing or extra, trials missing, or Ref's trials not the published ones.
    """
    results = Path(base_dir) / RESULTS_DIR
    run = json.loads((results / RUN_FILE).read_text())
    settings = run["settings"]
    seeds = list(range(int(settings["seed"]), int(settings["seed"]) + int(settings["seeds"])))
    if sorted(rerun.seed_specs) != seeds:
        raise RerunError(f"the published run has seeds {seeds}; the re-run names {sorted(rerun.seed_specs)}")
    name = rerun.policy
    groups: list[SeedGroup] = []
    written: list[Path] = []
    ref_check: dict[str, dict[str, int]] = {}
    for experiment, (map_name, index) in EXPERIMENT_MAPS.items():
        folder = rerun.performance if experiment == "performance" else rerun.transfer
        trials = int(settings[f"{experiment}_trials"])
        published = {r["policy"]: r for r in _raw_csv(results / CSV_FILES[experiment])[1]}
        ref_rows = _trials(rerun.ref, "ref", map_name, trials)
        ref_wins = sum(bool(r["success"]) for r in ref_rows)
        published_wins = round(float(published["ref"]["success_rate"]) * trials)
        if abs(ref_wins - published_wins) > rerun.ref_tolerance:
            raise RerunError(
                f"{rerun.ref}: Ref succeeds in {ref_wins} of {trials} {map_name} scenarios, the published "
                f"run in {published_wins} (tolerance {rerun.ref_tolerance}): not the published evaluation"
            )
        ref_check[map_name] = {"rerun": ref_wins, "published": published_wins, "trials": trials}
        groups.append(SeedGroup(experiment, "ref", map_name, None, (seeds[0],), (_scores(ref_rows),)))
        per_seed = {seed: _trials(folder, spec, map_name, trials) for seed, spec in rerun.seed_specs.items()}
        path = results / CSV_FILES[experiment]
        entry = _summary(per_seed[seeds[0]], name)
        _replace(path, lambda r: r["policy"], [{**published[name], **entry}])
        written.append(path)
        scores = tuple(_scores(per_seed[s]) for s in seeds)
        groups.append(
            SeedGroup(experiment, name, map_name, None, tuple(seeds), scores, PAPER_SUCCESS[name][index])
        )
        if experiment == "performance" and name in LFD_POLICIES:
            groups.append(_lfd(results, rerun, settings, per_seed, seeds))
            written.append(results / CSV_FILES["lfd"])
    mine = [g for g in groups if g.policy == name]
    pairs = [p for p in IMPROVEMENT_PAIRS if p[0] == name]
    for table, rows, key in (
        ("seeds", seed_rows(mine), lambda r: (r["experiment"], r["policy"])),
        ("improvement", improvement_rows(groups, pairs), lambda r: (r["experiment"], r["x"], r["y"])),
        ("profiles", profile_rows(mine), lambda r: (r["experiment"], r["policy"])),
    ):
        _replace(results / CSV_FILES[table], key, rows)
        written.append(results / CSV_FILES[table])
    written += _records(results, run, rerun, ref_check)
    return written


def _lfd(
    results: Path,
    rerun: PolicyRerun,
    settings: Mapping[str, Any],
    per_seed: Mapping[int, list[dict[str, Any]]],
    seeds: list[int],
) -> SeedGroup:
    """Rewrite the policy's lfd.csv row from the first `lfd_trials` gdc1-test trials; returns its
    LfD seed group."""
    # The LfD size of the performance experiments' policy: PIPS's own, BC's and GAIL's largest.
    size = int(settings["pips_steps"] if rerun.policy == "pips" else max(settings["lfd_sizes"]))
    trials = int(settings["lfd_trials"])
    first = {s: [r for r in per_seed[s] if r["scenario_index"] < trials] for s in seeds}
    entry = _summary(first[seeds[0]], rerun.policy)

    def rewrite(row: dict[str, str]) -> dict[str, Any]:
        return {**row, **{column: entry[source] for column, source in LFD_COLUMNS.items()}}

    path = results / CSV_FILES["lfd"]
    header, rows = _raw_csv(path)
    mine = [r for r in rows if r["policy"] == rerun.policy and float(r["demonstration_steps"]) == size]
    if len(mine) != 1:
        raise RerunError(f"{path}: {len(mine)} rows of {rerun.policy} at {size} steps, not one")
    write_csv([rewrite(r) if r is mine[0] else r for r in rows], path, header)
    paper = paper_lfd(rerun.policy, size)
    scores = tuple(_scores(first[s]) for s in seeds)
    return SeedGroup("lfd", rerun.policy, "gdc1", size, tuple(seeds), scores, paper[0] if paper else None)


def _records(
    results: Path, run: dict[str, Any], rerun: PolicyRerun, ref_check: Mapping[str, Any]
) -> list[Path]:
    """training.json without the policy's old trainings and with the re-run's; run.json's
    `reruns` entry."""
    path = results / TRAINING_FILE
    training = [t for t in json.loads(path.read_text()) if t.get("trainer") != rerun.policy]
    training += [dict(t) for t in rerun.training]
    write_json(path, training)
    entry = {
        "policy": rerun.policy,
        "commit": rerun.commit,
        "commands": list(rerun.commands),
        "why": rerun.why,
        "ref_successes": dict(ref_check),
    }
    run["reruns"] = [r for r in run.get("reruns", []) if r.get("policy") != rerun.policy] + [entry]
    write_json(results / RUN_FILE, run)
    return [path, results / RUN_FILE]


def replace_reference_rows(base_dir: str | Path, reference_results: str | Path) -> list[Path]:
    """Put a later `--reference` run's rows into base_dir/results/: its reference.csv (every quirk set
    it holds, the sets it kept from earlier runs of its work folder included) in place of the
    published one, its trainings under reference/ in place of the published ones in training.json,
    and its reference part's timing in timings.json. The run must share the published run's settings
    (the same hash: the same protocol, seeds and trials); returns the files rewritten.

    Raises:
        RerunError: no reference rows in `reference_results`, or another settings hash.
    """
    from socialzoo.reproduce.ledger import TIMINGS_FILE
    from socialzoo.reproduce.plan import REFERENCE_PART

    results, theirs = Path(base_dir) / RESULTS_DIR, Path(reference_results)
    source = theirs / CSV_FILES["reference"]
    if not source.is_file():
        raise RerunError(f"{source}: no reference rows (run `socialzoo reproduce --reference` first)")
    ours_hash = json.loads((results / RUN_FILE).read_text()).get("settings_hash")
    their_hash = json.loads((theirs / RUN_FILE).read_text()).get("settings_hash")
    if ours_hash != their_hash:
        raise RerunError(f"{theirs}: settings {their_hash}, the published run's are {ours_hash}")
    target = results / CSV_FILES["reference"]
    target.write_bytes(source.read_bytes())
    path = results / TRAINING_FILE
    training = [t for t in json.loads(path.read_text()) if not str(t.get("run", "")).startswith("reference/")]
    training += [
        t for t in json.loads((theirs / TRAINING_FILE).read_text()) if str(t["run"]).startswith("reference/")
    ]
    write_json(path, training)
    timings_path = results / TIMINGS_FILE
    timings = json.loads(timings_path.read_text())
    timings[REFERENCE_PART] = json.loads((theirs / TIMINGS_FILE).read_text())[REFERENCE_PART]
    write_json(timings_path, timings)
    return [target, path, timings_path]
