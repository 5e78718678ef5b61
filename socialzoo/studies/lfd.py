"""Experiment 2 (SPEC section 10, LfD data efficiency), evaluation half: the policies of socialzoo.studies.lfd_training
on the same fixed scenarios; a table of success % and average step reward beside the paper's."""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark
from socialzoo.bench.runner import Backend
from socialzoo.bench.tables import interval_text, policy_label, write_csv
from socialzoo.core.files import write_text_atomic

logger = logging.getLogger(__name__)

# The paper's training-set sizes, in demonstration steps, largest first (its table's order).
LFD_SIZES: tuple[int, ...] = (155_400, 116_600, 77_700, 38_800, 3_500)
LFD_ALGOS: tuple[str, ...] = ("bc", "gail")
# The map whose test set the LfD policies are evaluated on (the paper's training map).
LFD_MAP = "gdc1"
# Scenarios per policy: the first LFD_TRIALS of the gdc1 test set (the paper's LfD percentages are whole
# numbers, as from 100 scenarios).
LFD_TRIALS = 100
# The paper's LfD table: (policy, demonstration steps) -> (success %, average step reward).
PAPER_LFD: dict[tuple[str, int], tuple[float, float]] = {
    ("bc", 155_400): (84.0, 0.12),
    ("bc", 116_600): (16.0, 0.01),
    ("bc", 77_700): (37.0, 0.04),
    ("bc", 38_800): (70.0, 0.08),
    ("bc", 3_500): (49.0, 0.05),
    ("gail", 155_400): (59.0, 0.06),
    ("gail", 116_600): (40.0, 0.04),
    ("gail", 77_700): (38.0, 0.02),
    ("gail", 38_800): (21.0, 0.02),
    ("gail", 3_500): (27.0, 0.01),
}
# A benchmark summary entry's success columns (socialzoo.bench.tables.summarize), as the study tables keep them.
SUCCESS_COLUMNS = ("trials", "success_rate", "success_ci_low", "success_ci_high")
TABLE_CSV = "lfd.csv"
TABLE_MD = "lfd.md"
CSV_COLUMNS = (
    "policy",
    "demonstration_steps",
    "trials",
    "success_rate",
    "success_ci_low",
    "success_ci_high",
    "average_step_reward",
    "average_step_reward_ci_low",
    "average_step_reward_ci_high",
    "paper_success_pct",
    "paper_average_step_reward",
    "policy_file",
)


def lfd_run_dir(root: str | Path, policy: str, size: int) -> Path:
    """The training run folder of `policy` ("bc", "gail") trained on `size` demonstration steps."""
    return Path(root) / f"{policy}_{size}"


def lfd_policy_file(root: str | Path, policy: str, size: int) -> Path:
    """The policy file that run writes (<root>/<policy>_<size>/<policy>.safetensors)."""
    return lfd_run_dir(root, policy, size) / f"{policy}.safetensors"


def find_lfd_policies(
    root: str | Path, policies: Sequence[str] = LFD_ALGOS, sizes: Sequence[int] | None = None
) -> dict[tuple[str, int], Path]:
    """The trained LfD policy files under `root`, keyed (policy, size).

    Args:
        root: the experiment folder (<root>/<policy>_<size>/<policy>.safetensors).
        policies: policy names to look for.
        sizes: demonstration sizes to look for; None: every size found.
    """
    found = study_files(root, rf"({'|'.join(map(re.escape, policies))})_(\d+)", lfd_policy_file)
    return {key: path for key, path in found.items() if sizes is None or key[1] in sizes}


def study_files(root: str | Path, folder: str, file_of: Callable[..., Path]) -> dict[tuple[Any, ...], Path]:
    """The files of a study's runs under `root`: for each folder whose name matches the regular expression
    `folder`, keyed by its groups (digits as ints), file_of(root, *key) where that file exists."""
    root = Path(root)
    found = {}
    for path in sorted(root.iterdir()) if root.is_dir() else ():
        if match := re.fullmatch(folder, path.name):
            key = tuple(int(g) if g.isdigit() else g for g in match.groups())
            if (file := file_of(root, *key)).is_file():
                found[key] = file
    return found


@dataclass(frozen=True)
class LfdResult:
    """What the LfD evaluation produced.

    Attributes:
        rows: one dict per (policy, size), keyed by CSV_COLUMNS.
        files: the table files (lfd.csv, lfd.md) and the benchmark's store and summaries.
        computed: trials run by this call.
        reused: trials read back from the store.
    """

    rows: list[dict[str, Any]]
    files: list[Path]
    computed: int
    reused: int


def run_lfd_evaluation(
    policies: Mapping[tuple[str, int], str | Path],
    out_dir: str | Path,
    *,
    trials: int = LFD_TRIALS,
    workers: int | None = 2,
    batch_size: int = 64,
    env_overrides: Mapping[str, Any] | None = None,
    progress: bool = True,
    backend: Backend = "local",
) -> LfdResult:
    """Evaluate LfD policy files on the first `trials` gdc1 test scenarios and write the table.

    The evaluation scenarios are the first `trials` of the gdc1 test set (base seed 20220001): they are only
    ever evaluated on, never used to train, tune or choose anything. Trials go to a results store as they
    finish, so an interrupted evaluation resumes and a repeated one is read back.

    Args:
        policies: (policy name, demonstration steps) -> policy file, e.g. from `find_lfd_policies`.
            Names are policy registry names ("bc", "gail", later "pips").
        out_dir: output folder: results.sqlite (every trial), lfd.csv, lfd.md, config.json.
        trials: scenarios per policy (the first of gdc1-test, the same for every policy).
        workers: local evaluation processes.
        batch_size: env rows stepped together per worker.
        env_overrides: EnvConfig.replace keywords for the evaluation env (plain JSON), e.g.
            {"max_steps": 400} for a quick look; None: the benchmark as it is.
        progress: show a progress bar.
        backend: "local" (`workers` processes) or "ray" (Ray tasks; a running Ray is used).

    Raises:
        ValueError: no policies, a file that does not exist, or too many trials.
    """
    if not policies:
        raise ValueError("run_lfd_evaluation: no policies to evaluate")
    specs = {}
    for (name, size), path in policies.items():
        if not Path(path).is_file():
            raise ValueError(f"run_lfd_evaluation: {name} ({size} steps): no policy file {path}")
        specs[(name, int(size))] = f"{name}:{path}"
    config = BenchmarkConfig(
        policies=tuple(specs.values()),
        maps=(LFD_MAP,),
        trials=trials,
        workers=workers,
        batch_size=batch_size,
        env_overrides=dict(env_overrides or {}),
        backend=backend,
    )
    out = Path(out_dir)
    result = run_benchmark(config, out, progress=progress, figures=False)
    by_spec = {entry["policy"]: entry for entry in result.summary}
    rows = []
    for (name, size), spec in sorted(specs.items(), key=lambda kv: (_order(kv[0][0]), -kv[0][1])):
        entry = by_spec[spec]
        paper = PAPER_LFD.get((name, size))
        rows.append(
            {
                "policy": name,
                "demonstration_steps": size,
                **{k: entry[k] for k in SUCCESS_COLUMNS},
                "average_step_reward": entry["average_step_reward_mean"],
                "average_step_reward_ci_low": entry["average_step_reward_ci_low"],
                "average_step_reward_ci_high": entry["average_step_reward_ci_high"],
                "paper_success_pct": paper[0] if paper else None,
                "paper_average_step_reward": paper[1] if paper else None,
                "policy_file": str(policies[(name, size)]),
            }
        )
    files = [
        write_csv(rows, out / TABLE_CSV, CSV_COLUMNS, blank_nan=False),
        write_lfd_md(rows, out / TABLE_MD, trials),
    ]
    return LfdResult(rows, files + list(result.files), result.computed, result.reused)


def _order(name: str) -> tuple[int, str]:
    known = (*LFD_ALGOS, "pips")
    return (known.index(name) if name in known else len(known), name)


def number_cell(value: Any, fmt: str) -> str:
    """A table cell: `value` in format `fmt` (".2f", ","), empty where it is None or NaN."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    return format(value, fmt)


def write_lfd_md(rows: Sequence[Mapping[str, Any]], path: str | Path, trials: int) -> Path:
    """Write the LfD table as Markdown: ours (success with its 90% interval, average step reward)
    beside the paper's numbers."""
    lines = [
        f"# LfD data efficiency (first {trials} scenarios of the {LFD_MAP} test set)",
        "",
        "| policy | demonstration steps | success % [90% CI] | paper success % | average step reward "
        "| paper reward |",
        "|---|---:|---|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {policy_label(r['policy'])} | {r['demonstration_steps']:,} "
            f"| {interval_text(r, 'success', 1, 100.0)} "
            f"| {number_cell(r['paper_success_pct'], '.0f')} | {number_cell(r['average_step_reward'], '.3f')} "
            f"| {number_cell(r['paper_average_step_reward'], '.2f')} |"
        )
    return write_text_atomic(path, "\n".join(lines) + "\n")
