"""PIPS beyond the paper, evaluation half: success against the number of demonstration steps (500 / 1,000 / 3,500 /
10,000), with the paper's windowing around changes of action and without it, on validation scenarios."""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark
from socialzoo.bench.tables import interval_text, policy_label, write_csv
from socialzoo.core.files import write_text_atomic
from socialzoo.scenarios.scenario_sets import TestSet
from socialzoo.studies.lfd import SUCCESS_COLUMNS, number_cell, study_files
from socialzoo.studies.rl_curves import VALIDATION_SET

logger = logging.getLogger(__name__)

# Demonstration steps of the study's cells (the paper's 3,500 among them), and the windows:
# the paper's 20 steps (0.5 s) around each change of action, and 0 (every step an example).
STUDY_STEPS: tuple[int, ...] = (500, 1_000, 3_500, 10_000)
STUDY_WINDOWS: tuple[int, ...] = (20, 0)
STUDY_TRIALS = 200
# Policies evaluated on the same scenarios for reference: the demonstrator.
STUDY_BASELINES: tuple[str, ...] = ("ref",)
TABLE_CSV = "pips_study.csv"
TABLE_MD = "pips_study.md"
FIGURE = "pips_study.png"
CSV_COLUMNS = (
    "policy",
    "demonstration_steps",
    "window",
    "trials",
    "success_rate",
    "success_ci_low",
    "success_ci_high",
    "synthesis_seconds",
    "examples",
    "changes_of_action",
    "comparisons",
    "heldout_agreement",
    "seed",
    "program_file",
)


def study_run_dir(root: str | Path, steps: int, window: int) -> Path:
    """The folder of the cell synthesised from `steps` demonstration steps with `window`."""
    return Path(root) / f"pips_{steps}_w{window}"


def study_program_file(root: str | Path, steps: int, window: int) -> Path:
    """The program file of that cell (<root>/pips_<steps>_w<window>/pips.json)."""
    return study_run_dir(root, steps, window) / "pips.json"


def find_study_programs(root: str | Path) -> dict[tuple[int, int], Path]:
    """The synthesised programs under `root`, keyed (steps, window)."""
    return study_files(root, r"pips_(\d+)_w(\d+)", study_program_file)


def _comparisons(program: str | Path) -> int:
    """Comparisons in a program's guards (its size)."""
    from socialzoo.agents.pips import load_program, predicate_size

    return sum(predicate_size(t.guard) for ts in load_program(program).transitions.values() for t in ts)


@dataclass(frozen=True)
class StudyResult:
    """What the study's evaluation produced.

    Attributes:
        rows: one dict per (steps, window), keyed by CSV_COLUMNS.
        baselines: one dict per baseline policy (policy, trials, success_rate, success_ci_low,
            success_ci_high; the cell columns None).
        files: the table, the figure, and the benchmark's store and summaries.
        computed: trials run by this call.
        reused: trials read back from the store.
    """

    rows: list[dict[str, Any]]
    baselines: list[dict[str, Any]]
    files: list[Path]
    computed: int
    reused: int


def run_pips_study(
    programs: Mapping[tuple[int, int], str | Path],
    out_dir: str | Path,
    *,
    trials: int = STUDY_TRIALS,
    test_set: TestSet = VALIDATION_SET,
    baselines: Sequence[str] = STUDY_BASELINES,
    workers: int | None = 1,
    batch_size: int = 64,
    env_overrides: Mapping[str, Any] | None = None,
    progress: bool = True,
    figure: bool = True,
) -> StudyResult:
    """Evaluate the study's programs on the first `trials` validation scenarios; write the table
    (and the figure).

    Each program is evaluated on the first `trials` scenarios of the gdc1 validation set
    (socialzoo.studies.rl_curves.VALIDATION_SET: our own base seed, apart from the test sets and the quick
    sets, which are never looked at here) through run_benchmark, so trials go to its store as they finish and
    an interrupted evaluation resumes. pips_study.md gives success with its 90% interval, the synthesis time
    and the program's size.

    Args:
        programs: (demonstration steps, window) -> program file, e.g. from `find_study_programs`
            or socialzoo.studies.pips_study_training.train_pips_study.
        out_dir: output folder: results.sqlite (every trial), pips_study.csv, pips_study.md,
            pips_study.png, config.json.
        trials: scenarios per program (the same first ones of `test_set` for every program).
        test_set: the scenarios; gdc1's validation set unless a test gives a smaller one. Never a
            benchmark test set: the study chooses nothing, but it must not be tuned on them either.
        baselines: registered policies evaluated on the same scenarios, for reference.
        workers: local evaluation processes.
        batch_size: env rows stepped together per worker.
        env_overrides: EnvConfig.replace keywords for the evaluation env, e.g. {"max_steps": 40}.
        progress: show a progress bar.
        figure: draw pips_study.png (needs matplotlib).

    Raises:
        ValueError: no programs, a file that does not exist, a registered test set, or the
            demonstrations' own scenarios.
    """
    from socialzoo.bench.demonstrations import DEMO_BASE_SEED
    from socialzoo.scenarios.scenario_sets import TEST_SETS
    from socialzoo.train.pips import read_program_record

    if not programs:
        raise ValueError("run_pips_study: no programs to evaluate")
    if any(test_set.base_seed == ts.base_seed for ts in TEST_SETS.values()):
        raise ValueError(f"run_pips_study: {test_set.name or test_set.map_name!r} is a benchmark test set")
    if test_set.base_seed == DEMO_BASE_SEED:
        raise ValueError(
            f"run_pips_study: {test_set.name or test_set.map_name!r} has the demonstrations' base seed "
            f"{DEMO_BASE_SEED}: the programs were learned on those scenarios"
        )
    specs = {}
    for (steps, window), path in sorted(programs.items()):
        if not Path(path).is_file():
            raise ValueError(f"run_pips_study: {steps} steps, window {window}: no program file {path}")
        specs[(int(steps), int(window))] = f"pips:{path}"
    config = BenchmarkConfig(
        policies=(*specs.values(), *baselines),
        maps=(test_set.map_name,),
        trials=trials,
        workers=workers,
        batch_size=batch_size,
        env_overrides=dict(env_overrides or {}),
    )
    out = Path(out_dir)
    result = run_benchmark(
        config, out, test_sets={test_set.map_name: test_set}, progress=progress, figures=False
    )
    by_spec = {entry["policy"]: entry for entry in result.summary}
    rows = []
    for (steps, window), spec in specs.items():
        entry = by_spec[spec]
        record = read_program_record(programs[(steps, window)])
        demos = record.get("demonstrations", {})
        held = (record.get("agreement") or {}).get("held_out") or {}
        rows.append(
            {
                "policy": "pips",
                "demonstration_steps": steps,
                "window": window,
                **{k: entry[k] for k in SUCCESS_COLUMNS},
                "synthesis_seconds": record.get("synthesis_seconds"),
                "examples": demos.get("examples"),
                "changes_of_action": demos.get("changes_of_action"),
                "comparisons": _comparisons(programs[(steps, window)]),
                "heldout_agreement": held.get("agreement"),
                "seed": record.get("seed"),
                "program_file": str(programs[(steps, window)]),
            }
        )
    base_rows = [
        {
            **dict.fromkeys(CSV_COLUMNS),
            **{k: by_spec[b][k] for k in SUCCESS_COLUMNS},
            "policy": b,
        }
        for b in baselines
    ]
    name = test_set.name or test_set.map_name
    files = [
        write_csv([*rows, *base_rows], out / TABLE_CSV, CSV_COLUMNS, blank_nan=False),
        write_study_md(rows, out / TABLE_MD, trials, name, base_rows),
    ]
    if figure:
        files.append(plot_study(rows, out / FIGURE, trials, name, base_rows))
    return StudyResult(rows, base_rows, files + list(result.files), result.computed, result.reused)


def _window_label(window: int) -> str:
    return "none (every step)" if window == 0 else f"{window} steps"


def write_study_md(
    rows: Sequence[Mapping[str, Any]],
    path: str | Path,
    trials: int,
    test_set: str,
    baselines: Sequence[Mapping[str, Any]] = (),
) -> Path:
    """Write the study as a Markdown table: per cell, success with its 90% interval, the
    examples, the synthesis time, the program's comparisons and its held-out agreement; the
    baselines' success on the same scenarios below it."""
    lines = [
        f"# PIPS: success against demonstration steps, with and without windowing "
        f"(first {trials} scenarios of {test_set})",
        "",
        "| demonstration steps | window | success % [90% CI] | examples | changes of action "
        "| synthesis, s | comparisons | held-out agreement % |",
        "|---:|---|---|---:|---:|---:|---:|---:|",
    ]
    for r in sorted(rows, key=lambda r: (-r["window"], r["demonstration_steps"])):
        success = interval_text(r, "success", 1, 100.0)
        agree = r.get("heldout_agreement")
        lines.append(
            f"| {r['demonstration_steps']:,} | {_window_label(r['window'])} | {success} "
            f"| {number_cell(r.get('examples'), ',')} | {number_cell(r.get('changes_of_action'), 'd')} "
            f"| {number_cell(r.get('synthesis_seconds'), '.1f')} | {number_cell(r.get('comparisons'), 'd')} "
            f"| {number_cell(None if agree is None else 100 * agree, '.1f')} |"
        )
    if baselines:
        lines.append("")
        lines += [
            f"{policy_label(b['policy'])} on the same scenarios: {interval_text(b, 'success', 1, 100.0)} "
            "% success."
            for b in baselines
        ]
    return write_text_atomic(path, "\n".join(lines) + "\n")


def plot_study(
    rows: Sequence[Mapping[str, Any]],
    path: str | Path,
    trials: int,
    test_set: str,
    baselines: Sequence[Mapping[str, Any]] = (),
) -> Path:
    """Success (with 90% intervals) against demonstration steps, one line per window (PNG)."""
    from socialzoo.bench.figures import pyplot, save_figure, series_color

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.0, 3.8))
    windows = sorted({r["window"] for r in rows}, reverse=True)
    for i, window in enumerate(windows):
        cells = sorted((r for r in rows if r["window"] == window), key=lambda r: r["demonstration_steps"])
        x = [r["demonstration_steps"] for r in cells]
        y = [100 * r["success_rate"] for r in cells]
        err = [
            [100 * (r["success_rate"] - r["success_ci_low"]) for r in cells],
            [100 * (r["success_ci_high"] - r["success_rate"]) for r in cells],
        ]
        ax.errorbar(
            x, y, yerr=err, marker="o", capsize=3, color=series_color(i),
            label=f"window: {_window_label(window)}",
        )  # fmt: skip
    for b in baselines:
        ax.axhspan(100 * b["success_ci_low"], 100 * b["success_ci_high"], color="grey", alpha=0.2, lw=0)
        ax.axhline(
            100 * b["success_rate"], color="grey", label=f"{policy_label(b['policy'])} (same scenarios)"
        )
    ax.axhline(88.9, color="black", linestyle=":", label="paper's PIPS, 3,500 steps (gdc1 test)")
    ax.set_xscale("log")
    steps = sorted({r["demonstration_steps"] for r in rows})
    ax.set_xticks(steps, [f"{s:,}" for s in steps])
    ax.minorticks_off()
    ax.set_xlabel("demonstration steps of Ref")
    ax.set_ylabel("success, % (90% CI)")
    ax.set_title(f"PIPS on {trials} {test_set} scenarios", fontsize=10)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    path = Path(path)
    return save_figure(fig, path.parent, path.stem, (path.suffix[1:],), dpi=120)[0]
