"""Trained with X, tested with Y: every robot policy among every crowd model, one table and heatmap."""

from __future__ import annotations

import hashlib
import json
import logging
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.experiment import BenchmarkConfig, hashed_people, run_benchmark
from socialzoo.bench.runner import Backend
from socialzoo.bench.stats import mean_interval, rate_interval
from socialzoo.bench.store import ResultsStore
from socialzoo.bench.tables import policy_label, remove_outputs, write_csv
from socialzoo.core.files import json_text, no_file, write_text_atomic
from socialzoo.core.metrics import axis_label, metric, registered
from socialzoo.humans.models import PeopleConfig
from socialzoo.scenarios.scenario_sets import TestSet

logger = logging.getLogger(__name__)

# Characters a column's folder name keeps (any other becomes "_"): safe in a file name everywhere.
_UNSAFE = re.compile(r"[^A-Za-z0-9._+@=-]")


def _cell_format(name: str) -> tuple[str, str, int, float]:
    """(trial metric, label, digits, scale) of a metric in the matrix, from the metric registry:
    a flag as a percentage (its share's digits less 2), any other metric as its mean."""
    m = metric(name)
    if m.kind == "bool":
        return name, axis_label(name), max(m.digits - 2, 0), 100.0
    return name, m.heading, m.digits, 1.0


# (trial metric, label, digits, scale): what a cell shows.
METRICS: tuple[tuple[str, str, int, float], ...] = tuple(
    map(
        _cell_format,
        registered(
            "success",
            "human_collisions",
            "mean_force",
            "mean_blame",
            "people_time_lost",
            "people_extra_distance",
        ),
    )
)


@dataclass(frozen=True, kw_only=True)
class MatrixConfig:
    """A policy x crowd-model matrix: every column a benchmark run, whose quick, backend, address, workers
    and batch_size are the matrix's, as BenchmarkConfig's fields of those names.

    Attributes:
        policies: robot policy specs (socialzoo.agents).
        humans: people specs, one column each.
        maps: maps whose test sets are used ("<map>-test", or "<map>-quick" with quick).
        trials: scenarios per map and cell (the first of each test set); None: all.
        env_overrides: EnvConfig fields for every cell (e.g. {"max_steps": 1600}); its "people"
            is the matrix's own.
    """

    policies: tuple[str, ...] = ("goalone", "ref")
    humans: tuple[str, ...] = ("sf", "orca", "groups")
    maps: tuple[str, ...] = ("gdc1",)
    trials: int | None = None
    quick: bool = False
    backend: Backend = "local"
    address: str | None = None
    workers: int | None = 2
    batch_size: int = 64
    env_overrides: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "policies", tuple(self.policies))
        object.__setattr__(self, "humans", tuple(self.humans))
        object.__setattr__(self, "maps", tuple(self.maps))
        if not self.humans:
            raise ValueError("MatrixConfig.humans is empty")
        if len(set(self.humans)) != len(self.humans):
            raise ValueError(f"MatrixConfig.humans has duplicates: {list(self.humans)!r}")
        if "people" in self.env_overrides:
            raise ValueError(
                "MatrixConfig.env_overrides must not set people: the matrix sets them per column"
            )
        for spec in self.humans:
            self.benchmark(spec)  # a bad spec, policy, map, file or count fails here, naming it
        folders = [column_folder(spec) for spec in self.humans]
        if len(set(folders)) != len(folders):
            raise ValueError(
                f"MatrixConfig.humans names the same people twice (one learned file twice?): {list(self.humans)!r}"
            )

    def benchmark(self, humans: str) -> BenchmarkConfig:
        """The benchmark run of one column: the env drives the people, with counterfactual rows."""
        path = PeopleConfig(models=humans).learned_path
        if path is not None and not Path(path).is_file():
            raise ValueError(f"MatrixConfig.humans: {no_file(path, 'learned policy file')}")
        # Every other field of the matrix is the benchmark's field of the same name.
        shared = {
            f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("humans", "env_overrides")
        }
        people = {"models": humans, "counterfactual": True}
        return BenchmarkConfig(**shared, env_overrides={**dict(self.env_overrides), "people": people})


@dataclass
class Matrix:
    """What crowd_matrix found.

    Attributes:
        out_dir: the output folder (one sub-folder per crowd model).
        rows: one dict per (policy, model, map): trials and each metric's mean, low, high.
        files: the files written.
    """

    out_dir: Path
    rows: list[dict[str, Any]]
    files: list[Path]


def column_label(spec: str) -> str:
    """A column's heading: the spec with each learned file named by its file name."""
    parts = []
    for part in spec.split("+"):
        name, sep, rest = part.strip().partition(":")
        if name == "learned" and sep:
            path, at, share = rest.rpartition("@") if "@" in rest else (rest, "", "")
            parts.append(f"learned:{Path(path).name}{at}{share}")
        else:
            parts.append(part.strip())
    return "+".join(parts)


def column_folder(spec: str) -> str:
    """The folder of a column, named by its people spec alone, so that reordering --humans finds each
    column's results: the spec itself when it is a safe file name ("sf", "sf@0.5+orca@0.5"), else its
    heading (column_label) made safe, with 8 hex digits of the sha256 of the spec as the config hash
    reads it (hashed_people: a learned model by its file's contents, wherever the file lies) to keep it
    unique ("learned_humans.safetensors-" and the 8 digits)."""
    safe = _UNSAFE.sub("_", column_label(spec))
    if safe == spec:
        return spec
    digest = hashlib.sha256(hashed_people(spec).encode()).hexdigest()[:8]
    return f"{safe}-{digest}"


def _positional_folder_names(spec: str) -> str:
    """The model names that ended a column's folder before folders were named by spec ("2-learned")."""
    return "-".join(part.strip().split("@")[0].split(":")[0] for part in spec.split("+"))


def adopt_positional_folder(out: Path, spec: str) -> Path:
    """out/column_folder(spec), renamed from the folder an older version named by the column's
    position ("<index>-<model names>") when that folder's config.json records this spec and the new
    one does not exist yet, so that an interrupted or earlier matrix resumes from its stores; the
    lowest such index wins, any other is left alone."""
    folder = out / column_folder(spec)
    if folder.exists():
        return folder
    tail = "-" + _positional_folder_names(spec)
    candidates = sorted(
        (int(p.name[: -len(tail)]), p)
        for p in (out.iterdir() if out.is_dir() else ())
        if p.is_dir() and p.name.endswith(tail) and p.name[: -len(tail)].isdigit()
    )
    for _, old in candidates:
        try:
            record = json.loads((old / "config.json").read_text(encoding="utf-8"))
            models = record["benchmark"]["env_overrides"]["people"]["models"]
        except (OSError, ValueError, KeyError, TypeError):
            continue  # no run of a known column recorded there
        if models == spec:
            old.rename(folder)
            logger.info("crowd matrix: %s renamed %s (folders are named by people spec)", old, folder.name)
            return folder
    return folder


def crowd_matrix(
    config: MatrixConfig,
    out_dir: str | Path,
    *,
    test_sets: Mapping[str, TestSet] | None = None,
    progress: bool = True,
    figures: bool = True,
) -> Matrix:
    """Run every column and write matrix.csv, matrix.md and matrix.png.

    Runs the benchmark once per crowd model (a people spec of socialzoo.humans.models: "sf", "orca", "groups",
    "learned:PATH", mixes), each into its own folder with its own results store (a rerun reads its trials
    back, whatever the columns' order: the folder is named by the spec, column_folder; a folder an older
    version named by position, "1-orca", is renamed to it), the env driving the people (EnvConfig.people)
    with counterfactual rows, so that every cell also says what the robot cost the people. matrix.csv
    holds every policy x model x map: trials, and the mean with its 90% interval of each metric;
    matrix.md one table per map and metric, policies as rows, crowd models as columns; matrix.png a
    heatmap per metric.

    Metrics: success rate, human collisions per episode (steps with a person within 0.4 m), mean force and
    blame per step (SPEC section 9), and the people's time lost and extra distance walked because of the robot
    (socialzoo.env.people), means per person.

    Args:
        config: the matrix.
        out_dir: output folder.
        test_sets: test sets to use instead of the registry's (keyed by map name), for tests.
        progress: show progress bars.
        figures: draw matrix.png (needs matplotlib).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    for spec in config.humans:
        result = run_benchmark(
            config.benchmark(spec),
            adopt_positional_folder(out, spec),
            test_sets=test_sets,
            progress=progress,
            figures=False,
        )
        trials = run_trials(result.out_dir)
        for policy in config.policies:
            for map_name in dict.fromkeys(t["map"] for t in trials):
                group = [t for t in trials if t["policy"] == policy and t["map"] == map_name]
                row: dict[str, Any] = {
                    "policy": policy,
                    "humans": spec,
                    "map": map_name,
                    "trials": len(group),
                }
                for key, _, _, scale in METRICS:
                    values = np.array([np.nan if t.get(key) is None else float(t[key]) for t in group])
                    if metric(key).kind == "bool":
                        ci = rate_interval(int(np.nansum(values)), len(values), 0.9)  # Wilson
                    else:
                        ci = mean_interval(values, 0.9)
                    row[f"{key}_mean"] = ci.value * scale
                    row[f"{key}_low"] = ci.low * scale
                    row[f"{key}_high"] = ci.high * scale
                rows.append(row)
    files = [write_matrix_csv(rows, out / "matrix.csv"), write_matrix_md(rows, config, out / "matrix.md")]
    files.append(write_text_atomic(out / "matrix.json", json_text(rows, indent=1, default=float) + "\n"))
    if figures:
        files.append(plot_matrix(rows, config, out / "matrix.png"))
    else:  # an older run's heatmaps would not match these tables
        remove_outputs(out, ["matrix"], ["png"])
    return Matrix(out, rows, files)


def run_trials(run_dir: Path) -> list[dict[str, Any]]:
    """The trials of the benchmark run recorded in run_dir/config.json: its config hashes and its
    first `trials` scenarios of each test set (a store may hold more)."""
    record = json.loads((run_dir / "config.json").read_text())
    hashes = set(record["config_hashes"].values())
    counts = {name: entry["trials"] for name, entry in record["test_sets"].items()}
    with ResultsStore(run_dir / "results.sqlite") as store:
        rows = store.rows()
    return [
        r for r in rows if r["config_hash"] in hashes and r["scenario_index"] < counts.get(r["test_set"], 0)
    ]


def write_matrix_csv(rows: list[dict[str, Any]], path: Path) -> Path:
    """Every column of the matrix rows."""
    columns = ["policy", "humans", "map", "trials"] + [
        f"{key}_{s}" for key, _, _, _ in METRICS for s in ("mean", "low", "high")
    ]
    return write_csv(rows, path, columns, blank_nan=False, lineterminator="\n")


def interval_cell(row: Mapping[str, Any] | None, key: str, digits: int, bounds: str = "") -> str:
    """A metric's mean with its interval, "0.12 [0.10, 0.14]", from a row's KEY_mean, KEY_{bounds}low and
    KEY_{bounds}high; the mean alone where the interval is missing, "-" where the mean (or the row) is."""
    keys = (f"{key}_mean", f"{key}_{bounds}low", f"{key}_{bounds}high")
    mean, low, high = (np.nan if row is None or row.get(k) is None else float(row[k]) for k in keys)
    if not np.isfinite(mean):
        return "-"
    if not (np.isfinite(low) and np.isfinite(high)):
        return f"{mean:.{digits}f}"
    return f"{mean:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"


def write_matrix_md(rows: list[dict[str, Any]], config: MatrixConfig, path: Path) -> Path:
    """One table per map and metric: policies as rows, crowd models as columns."""
    lines = [
        "# Robot policies x crowd models",
        "",
        "Means over trials with 90% intervals (Wilson for success, Student-t otherwise); the env drives the "
        "people of each column (EnvConfig.people) and runs every scenario also without the robot (the "
        "people's time lost and extra distance).",
        "",
    ]
    by = {(r["policy"], r["humans"], r["map"]): r for r in rows}
    for map_name in dict.fromkeys(r["map"] for r in rows):
        trials = {r["trials"] for r in rows if r["map"] == map_name}
        lines += [f"## {map_name} ({', '.join(map(str, sorted(trials)))} trials per cell)", ""]
        for key, label, digits, _ in METRICS:
            lines += [f"### {label}", "", "| policy | " + " | ".join(map(column_label, config.humans)) + " |"]
            lines.append("|---|" + "---|" * len(config.humans))
            for policy in config.policies:
                cells = [
                    interval_cell(by.get((policy, spec, map_name)), key, digits) for spec in config.humans
                ]
                lines.append(f"| {policy_label(policy)} | " + " | ".join(cells) + " |")
            lines.append("")
    return write_text_atomic(path, "\n".join(lines))


def plot_matrix(rows: list[dict[str, Any]], config: MatrixConfig, path: Path) -> Path:
    """A heatmap per metric (the first map): policies as rows, crowd models as columns."""
    from socialzoo.bench.figures import pyplot, save_figure

    plt = pyplot()
    map_name = rows[0]["map"] if rows else ""
    by = {(r["policy"], r["humans"]): r for r in rows if r["map"] == map_name}
    columns = [column_label(spec) for spec in config.humans]
    fig, axes = plt.subplots(2, 3, figsize=(4.2 * 3, 0.5 * len(config.policies) * 2 + 3.2))
    for ax, (key, label, digits, _) in zip(axes.ravel(), METRICS, strict=False):
        grid = np.array(
            [[by.get((p, s), {}).get(f"{key}_mean", np.nan) for s in config.humans] for p in config.policies]
        )
        # Better is brighter (viridis runs dark to bright), whichever way the metric improves.
        better = metric(key).higher_is_better
        image = ax.imshow(grid, cmap="viridis" if better else "viridis_r", aspect="auto")
        for (i, j), value in np.ndenumerate(grid):
            if np.isfinite(value):
                red, green, blue, _ = image.cmap(image.norm(value))
                ink = "k" if 0.299 * red + 0.587 * green + 0.114 * blue > 0.5 else "w"
                ax.text(j, i, f"{value:.{min(digits, 2)}f}", ha="center", va="center", color=ink, fontsize=8)
        ax.set_xticks(range(len(columns)), columns, rotation=30, ha="right", fontsize=8)
        ax.set_yticks(range(len(config.policies)), [policy_label(p) for p in config.policies], fontsize=8)
        ax.set_title(label, fontsize=9)
        fig.colorbar(image, ax=ax, shrink=0.8)
    fig.suptitle(f"robot policies x crowd models ({map_name})")
    fig.tight_layout()
    return save_figure(fig, path.parent, path.stem, (path.suffix[1:],), dpi=110)[0]
