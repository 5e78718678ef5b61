"""Benchmark tables, one writer (`write_tables`) for every benchmark: summary entries as NAME.csv and NAME.md in a
`TableLayout`, the paper's (summary.md) or a task id's (one table, a column per metric)."""

from __future__ import annotations

import csv
import io
import math
import numbers
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.aggregates import cell_generator
from socialzoo.bench.stats import (
    BOOTSTRAP_RESAMPLES,
    CONFIDENCE,
    count_interval,
    mean_interval,
    rate_interval,
)
from socialzoo.core.files import read_text, write_text_atomic
from socialzoo.core.metrics import METRICS, metric, registered, table_heading
from socialzoo.env.metrics import failure_cause

# Metrics of the tables, in order: (column, heading), the headings from the metric registry
# (socialzoo.core.metrics). time_to_goal is averaged over successful episodes only (the paper's
# figure); every other metric over all episodes with a finite value.
TABLE_METRICS: tuple[tuple[str, str], ...] = tuple(
    (name, table_heading(name))
    for name in registered(
        "mean_force",
        "mean_blame",
        "time_to_goal",
        "average_step_reward",
        "human_collisions",
        "wall_collisions",
        "min_human_distance",
        "personal_space_intrusion_time",
        "path_irregularity",
        "path_length_ratio",
        "jerk",
        "distance_travelled",
        "max_force",
        "max_blame",
        "stuck",
    )
)
# Why episodes fail (socialzoo.env.metrics.failure_cause), each a share of all episodes with a
# Wilson interval: columns failure_<cause>_rate, _ci_low, _ci_high; labels for the tables.
FAILURE_LABELS: dict[str, str] = {
    "human_collision": "human collision",
    "wall_collision": "wall collision",
    "stuck": "stuck",
    "timeout": "timeout while moving",
}
# The table's metrics averaged over successful episodes only, and its counts per episode (skewed,
# mostly zero, never negative: their means get a bootstrap interval), as the registry flags them.
SUCCESS_ONLY = tuple(name for name, _ in TABLE_METRICS if metric(name).success_only)
COUNT_METRICS = tuple(name for name, _ in TABLE_METRICS if metric(name).count)
# Seed of the bootstrap resamples: with the cell's names it seeds one generator per table cell,
# so a table is reproducible and a cell does not change when other policies or maps are added.
BOOTSTRAP_SEED = 0

# The paper's success rates in percent (SPEC section 10): policy -> (training map, transfer map).
PAPER_SUCCESS: dict[str, tuple[float, float]] = {
    "goalone": (97.5, 97.3),
    "ref": (89.4, 92.4),
    "bc": (92.3, 49.9),
    "gail": (83.3, 18.9),
    "pips": (88.9, 89.2),
    "dqn": (54.1, 8.8),
    "ppo": (55.1, 47.2),
}
# The paper's maps: training ("test" column of its table) and transfer.
MAP_ROLES: dict[str, str] = {"gdc1": "test", "ghc3": "transfer"}
POLICY_LABELS: dict[str, str] = {
    "goalone": "GoAlone",
    "ref": "Ref",
    "bc": "BC",
    "gail": "GAIL",
    "pips": "PIPS",
    "dqn": "DQN",
    "ppo": "PPO",
    "dagger": "DAgger",
}


# The footer of summary.md: which interval each kind of number has.
INTERVALS_NOTE = (
    "Two-sided 90% confidence intervals. Success rates: Wilson score intervals. Counts per episode "
    f"({', '.join(d.split(' (')[0] for n, d in TABLE_METRICS if n in COUNT_METRICS)}): "
    "bias-corrected and accelerated (BCa) bootstrap of the mean over episodes "
    f"({BOOTSTRAP_RESAMPLES:,} resamples, seeded per table cell), so they never go below 0; with "
    "no count at all the interval is [0, 3.0 / n], the exact Poisson bound for zero events. Every "
    "other mean: Student-t intervals. Time to goal is averaged over successful episodes only (n "
    "given)."
)


def policy_label(policy: str) -> str:
    """Display name of a policy name ("goalone" -> "GoAlone", "pips:runs/a.json" -> "PIPS (a.json)")."""
    key, sep, path = policy.partition(":")
    if sep:
        return f"{POLICY_LABELS.get(key.lower(), key)} ({Path(path).name})"
    return POLICY_LABELS.get(policy, policy)


def policy_labels(policies: Sequence[str]) -> dict[str, str]:
    """policy_label of each policy, told apart where two would read the same: files of one name in
    different folders get as much of their paths as differs ("DAgger (s1/dagger.safetensors)",
    "DAgger (s2/dagger.safetensors)")."""
    labels = {p: policy_label(p) for p in policies}
    counts = Counter(labels.values())
    for label in [v for v, n in counts.items() if n > 1]:
        same = [p for p in labels if labels[p] == label and ":" in p]
        paths = {p: Path(p.partition(":")[2]).parts for p in same}
        tails = {p: "/".join(parts) for p, parts in paths.items()}
        for depth in range(2, max((len(v) for v in paths.values()), default=0) + 1):
            shorter = {p: "/".join(parts[-depth:]) for p, parts in paths.items()}
            if len(set(shorter.values())) == len(shorter):
                tails = shorter
                break
        for p in same:
            key = p.partition(":")[0]
            labels[p] = f"{POLICY_LABELS.get(key.lower(), key)} ({tails[p]})"
    return labels


def paper_success(policy: str, map_name: str) -> float | None:
    """The paper's success rate (%) of a policy on a map, or None where the paper has none."""
    role = MAP_ROLES.get(map_name)
    numbers = PAPER_SUCCESS.get(policy.partition(":")[0].lower())
    if role is None or numbers is None:
        return None
    return numbers[0] if role == "test" else numbers[1]


@dataclass(frozen=True)
class TableLayout:
    """What a benchmark's tables show, for the one writer (`write_tables`): the metrics, in order,
    and how they are laid out. Headings, units and digits come from the metric registry
    (socialzoo.core.metrics); every layout reads the same summary entries (`value_key`).

    Attributes:
        metrics: registered metric names, in the tables' order.
        paper: the paper's layout (`PAPER_LAYOUT`, summary.md): a success table with the paper's
            numbers beside ours, the failures by cause, one table per metric with a column per
            map, and a note on the intervals. Otherwise one table with a column per metric, as a
            task id's benchmark writes (`task_layout`).
    """

    metrics: tuple[str, ...]
    paper: bool = False

    def csv_columns(self) -> list[str]:
        """Columns of the CSV, in order: the entry's names, then each metric's value and interval
        (the paper's layout: success, the failures by cause, and n where a metric is averaged over
        successful episodes only)."""
        columns = ["policy", "map", "test_set", "trials", "success_rate", "success_ci_low", "success_ci_high"]
        if self.paper:
            for cause in FAILURE_LABELS:
                columns += [f"failure_{cause}_rate", f"failure_{cause}_ci_low", f"failure_{cause}_ci_high"]
        for name in self.metrics:
            if name != "success":
                columns += [value_key(name), f"{name}_ci_low", f"{name}_ci_high"]
            if self.paper and metric(name).success_only:
                columns.append(f"{name}_n")
        return columns


def value_key(name: str) -> str:
    """The key of a metric's value in a summary entry: "success_rate", else "<name>_mean" (a
    flag's mean is its rate); its interval is "<name>_ci_low", "<name>_ci_high"."""
    return "success_rate" if name == "success" else f"{name}_mean"


PAPER_LAYOUT = TableLayout(tuple(name for name, _ in TABLE_METRICS), paper=True)


def task_layout(summary: Sequence[Mapping[str, Any]], guidelines: bool = False) -> TableLayout:
    """The layout of a task id's benchmark: every registered metric its entries all hold, in
    registry order, one table with a column per metric; the guidelines' Table I metrics (`gl_*`,
    in the store and its CSVs) only with `guidelines` (they would double the table's width)."""
    return TableLayout(
        tuple(
            n
            for n in METRICS
            if summary
            and all(value_key(n) in e for e in summary)
            and (guidelines or "guidelines" not in METRICS[n].sources)
        )
    )


def ordered(values: Sequence[str], order: Sequence[str] | None) -> list[str]:
    """The distinct values, those of `order` first in its order, the others as they first appear."""
    seen = list(dict.fromkeys(values))
    if order is None:
        return seen
    return [v for v in order if v in seen] + [v for v in seen if v not in order]


def ordered_groups(
    rows: Sequence[Mapping[str, Any]], policies: Sequence[str] | None, maps: Sequence[str] | None
) -> Iterator[tuple[str, str, list[Mapping[str, Any]]]]:
    """(policy, map, its rows) of every pair the rows hold, policies and maps `ordered`."""
    groups: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["policy"], row["map"]), []).append(row)
    for policy in ordered([k[0] for k in groups], policies):
        for map_name in ordered([k[1] for k in groups], maps):
            if (policy, map_name) in groups:
                yield policy, map_name, groups[(policy, map_name)]


def summarize(
    rows: Sequence[Mapping[str, Any]],
    *,
    policies: Sequence[str] | None = None,
    maps: Sequence[str] | None = None,
    confidence: float = CONFIDENCE,
    seed: int = BOOTSTRAP_SEED,
    metrics: Sequence[str] = PAPER_LAYOUT.metrics,
) -> list[dict[str, Any]]:
    """One summary per (policy, map) of stored trial rows (ResultsStore.rows).

    Args:
        rows: trial dicts with policy, map, test_set, success and the `metrics`.
        policies: display order of the policies (others follow in order of appearance).
        maps: display order of the maps (likewise).
        confidence: two-sided level of the intervals.
        seed: seed of the count intervals' bootstrap resamples, one generator per cell with its names
            (socialzoo.bench.aggregates.cell_generator).
        metrics: the registered metrics to average (default the paper layout's, TABLE_METRICS).

    Returns:
        Dicts keyed by `TableLayout(metrics, paper=True).csv_columns()`: success rate with a Wilson
        interval, mean counts (the registry's counts) with bootstrap (BCa) intervals, other metric
        means with Student-t intervals (NaN where a metric is missing or has fewer than 2 finite values).
    """
    out = []
    for policy, map_name, group in ordered_groups(rows, policies, maps):
        success = np.array([bool(r["success"]) for r in group])
        rate = rate_interval(int(success.sum()), len(group), confidence)
        entry: dict[str, Any] = {
            "policy": policy,
            "map": map_name,
            "test_set": ",".join(sorted({str(r["test_set"]) for r in group})),
            "trials": len(group),
            **rate.entry("success", "rate"),
        }
        causes = [failure_cause(r) for r in group]
        for cause in FAILURE_LABELS:
            entry |= rate_interval(causes.count(cause), len(group), confidence).entry(
                f"failure_{cause}", "rate"
            )
        for name in metrics:
            values = np.array(
                [math.nan if r.get(name) is None else float(r[name]) for r in group], dtype=np.float64
            )
            if metric(name).success_only:
                values = values[success]
            if metric(name).count:
                ci = count_interval(values, confidence, rng=cell_generator(seed, policy, map_name, name))
            else:
                ci = mean_interval(values, confidence)
            entry |= ci.entry(name)
            if metric(name).success_only:
                entry[f"{name}_n"] = ci.n
        out.append(entry)
    return out


def write_summary_csv(
    summary: Sequence[Mapping[str, Any]], path: str | Path, layout: TableLayout = PAPER_LAYOUT
) -> Path:
    """Write summary entries as CSV (columns `layout.csv_columns()`, NaN written as an empty cell)."""
    columns = layout.csv_columns()
    rows = [{c: _csv_value(entry.get(c, math.nan)) for c in columns} for entry in summary]
    return write_csv(rows, path, columns)


def write_csv(
    rows: Iterable[Mapping[str, Any]],
    path: str | Path,
    columns: Sequence[str] | None = None,
    *,
    blank_nan: bool = True,
    lineterminator: str = "\r\n",
) -> Path:
    """Write rows as CSV, whole or not at all (`write_text_atomic`): the CSV writer of every table.

    Args:
        rows: dicts; keys outside `columns` are left out, a missing key is an empty cell.
        path: the file.
        columns: the columns, in order; None: every key of the rows, in order of appearance.
        blank_nan: write None and NaN as an empty cell (else NaN as "nan").
        lineterminator: the line ending (the csv module's CR LF by default, or a newline).
    """
    rows = list(rows)
    if columns is None:
        columns = list(dict.fromkeys(k for row in rows for k in row))
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=columns, lineterminator=lineterminator)
    writer.writeheader()
    for row in rows:
        cells = {c: row.get(c) for c in columns}
        if blank_nan:
            cells = {c: "" if isinstance(v, float) and math.isnan(v) else v for c, v in cells.items()}
        writer.writerow(cells)
    return write_text_atomic(path, text.getvalue())


def remove_outputs(folder: str | Path, stems: Iterable[str], suffixes: Sequence[str]) -> None:
    """Delete folder/STEM.SUFFIX for each stem and suffix where present: the files a writer owns
    but did not write this run (a figure skipped by --no-figures, a metric left out of --metrics),
    so that its folder never shows an older run's output beside this run's tables. Only the named
    files are touched, never anything else in the folder."""
    for stem in stems:
        for suffix in suffixes:
            (Path(folder) / f"{stem}.{suffix}").unlink(missing_ok=True)


class SummaryError(ValueError):
    """A summary.csv that cannot be read back: not UTF-8 CSV, without the summary's key columns,
    or with a row of the wrong width or a cell that is not a number; the message names the file."""


# Columns without which a CSV is not a summary (older files may lack some metric columns).
SUMMARY_KEY_COLUMNS = ("policy", "map", "test_set", "trials")


def read_summary_csv(path: str | Path) -> list[dict[str, Any]]:
    """Read summary.csv back (numbers as float or int, empty cells as NaN).

    Raises:
        FileNotFoundError: no such file.
        SummaryError: not a summary CSV (random bytes, a file of another kind, a row cut short);
            the message names the file and the line.
    """
    return read_csv_rows(path, "summary CSV", SummaryError, _summary_cell, SUMMARY_KEY_COLUMNS)


def _summary_cell(key: str, cell: str) -> Any:
    if key in ("policy", "map", "test_set"):
        return cell
    try:
        if key == "trials" or key.endswith("_n"):
            return int(cell)
        return float(cell) if cell != "" else math.nan
    except ValueError:
        raise ValueError(f"{key} is {cell!r}, not a number") from None


def read_csv_rows(
    path: str | Path,
    what: str,
    error: type[Exception],
    cell: Callable[[str, str], Any],
    required: Sequence[str] = (),
) -> list[dict[str, Any]]:
    """The rows of a CSV file (`what` and `error` as socialzoo.core.files.read_text), each cell as
    cell(column, text), whose ValueError says what is wrong with it; the header must hold the
    `required` columns. The reader of every table read back.

    Raises:
        FileNotFoundError: no such file.
        `error`: not UTF-8 CSV (a NUL byte, a quote left open), a header without a `required`
            column, a row whose cells do not match the header, or a cell `cell` refuses; the
            message names the file and the line.
    """
    path = Path(path)
    reader = csv.DictReader(io.StringIO(read_text(path, what, error), newline=""))
    out = []
    try:
        header = reader.fieldnames or []
        missing = [c for c in required if c not in header]
        if missing:
            raise error(f"{path}: not a {what} (no column {', '.join(missing)} in its header)")
        for raw in reader:
            where = f"{path}:{reader.line_num}"
            if None in raw or None in raw.values():  # DictReader's marks of too many or too few cells
                raise error(f"{where}: the row's cells do not match the {len(header)} columns")
            try:
                out.append({key: cell(key, text) for key, text in raw.items()})
            except ValueError as err:
                raise error(f"{where}: {err}") from None
    except csv.Error as err:  # a NUL byte or a quote left open
        raise error(f"{path}:{reader.line_num}: not a {what} ({err})") from None
    return out


def _csv_value(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return ""
    if isinstance(value, float):
        return repr(value)
    return value


def number_text(value: Any, digits: int) -> str:
    """`value` with `digits` decimals; "n/a" for None, NaN, an infinity or anything not a number
    (a cell of every table's Markdown)."""
    if not isinstance(value, numbers.Real) or not math.isfinite(value):
        return "n/a"
    return f"{value:.{digits}f}"


def _fmt_ci(mean: float, low: float, high: float, digits: int) -> str:
    if math.isinf(mean):  # a mean over values one of which is infinite (a time to collision: never)
        return "inf" if mean > 0 else "-inf"
    if not math.isfinite(mean):
        return "n/a"
    if not (math.isfinite(low) and math.isfinite(high)):
        return number_text(mean, digits)
    return f"{mean:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"


def _map_header(map_name: str) -> str:
    role = MAP_ROLES.get(map_name)
    return f"{role} ({map_name})" if role else map_name


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """The lines of a Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return lines + ["| " + " | ".join(cells) + " |" for cells in rows]


def interval_text(entry: Mapping[str, Any] | None, name: str, digits: int, scale: float = 1.0) -> str:
    """A metric's value in a summary entry (`value_key`) with its interval, times `scale`:
    "0.12 [0.10, 0.14]"; the value alone where the interval is missing, "inf" where it is infinite,
    "n/a" where it is missing, "-" where the table has no entry."""
    if entry is None:
        return "-"
    keys = (value_key(name), f"{name}_ci_low", f"{name}_ci_high")
    value, low, high = (math.nan if entry.get(k) is None else scale * float(entry[k]) for k in keys)
    return _fmt_ci(value, low, high, digits)


def summary_markdown(
    summary: Sequence[Mapping[str, Any]],
    *,
    title: str = "Benchmark results",
    layout: TableLayout = PAPER_LAYOUT,
) -> str:
    """The Markdown report of summary entries in a layout.

    The paper's layout: the success table, with one row per policy and, for each map, our success
    rate (%) with its 90% interval and, for the paper's maps, the paper's number beside it (SPEC
    section 10); the failures by cause; one table per metric; the intervals. Otherwise the title
    and one table: each flag's rate and each number's mean, success with its interval.
    """
    policies = list(dict.fromkeys(e["policy"] for e in summary))
    labels = policy_labels(policies)
    if not layout.paper:
        header = ["policy"] + [_column_heading(n) for n in layout.metrics]
        rows = [[labels[e["policy"]]] + [_column_cell(e, n) for n in layout.metrics] for e in summary]
        return "\n".join([title, "", *markdown_table(header, rows)]) + "\n"
    maps = list(dict.fromkeys(e["map"] for e in summary))
    by_key = {(e["policy"], e["map"]): e for e in summary}
    paper_maps = [m for m in maps if m in MAP_ROLES]
    trials = sorted({int(e["trials"]) for e in summary})
    lines = [
        f"# {title}",
        "",
        f"Trials per policy and map: {', '.join(map(str, trials))}. Success: goal reached within the "
        "time limit with no human and no wall collision. Values in brackets are two-sided 90% "
        "confidence intervals (which ones: see the end).",
        "",
        "## Success rate (%)",
        "",
    ]
    header = ["policy"]
    for m in maps:
        header += [_map_header(m)] + ([f"paper {MAP_ROLES[m]}"] if m in paper_maps else [])
    rows = []
    for p in policies:
        cells = [labels[p]]
        for m in maps:
            cells.append(interval_text(by_key.get((p, m)), "success", 1, 100.0))
            if m in paper_maps:
                paper = paper_success(p, m)
                cells.append("-" if paper is None else f"{paper:.1f}")
        rows.append(cells)
    lines += markdown_table(header, rows)
    lines += _failure_table(summary, labels)
    for name in layout.metrics:
        heading = table_heading(name)
        lines += ["", f"## {heading[0].upper() + heading[1:]}", ""]
        rows = []
        for p in policies:
            cells = [labels[p]]
            for m in maps:
                e = by_key.get((p, m))
                n = f" (n={e[f'{name}_n']})" if e is not None and metric(name).success_only else ""
                cells.append(interval_text(e, name, metric(name).digits) + n)
            rows.append(cells)
        lines += markdown_table(["policy", *(_map_header(m) for m in maps)], rows)
    lines += ["", "## Intervals", "", INTERVALS_NOTE]
    return "\n".join(lines) + "\n"


def _column_heading(name: str) -> str:
    m = metric(name)
    return f"{m.label} (rate)" if m.kind == "bool" else m.heading


def _column_cell(entry: Mapping[str, Any], name: str) -> str:
    digits = 3 if metric(name).kind == "bool" else metric(name).digits
    if name == "success":
        return interval_text(entry, name, digits)
    return number_text(entry[value_key(name)], digits)


def _failure_table(summary: Sequence[Mapping[str, Any]], labels: Mapping[str, str]) -> list[str]:
    """Markdown lines of the failures by cause: one row per policy and map, each cause's share of
    the episodes (%), in the order of precedence of socialzoo.env.metrics.failure_cause."""
    rows = [
        [labels[e["policy"]], str(e["map"]), number_text(100 * e["success_rate"], 1)]
        + [number_text(100 * e.get(f"failure_{c}_rate", math.nan), 1) for c in FAILURE_LABELS]
        for e in summary
    ]
    return [
        "",
        "## Failures by cause (% of episodes)",
        "",
        "Each failed episode counts once, for the first that applies: wall collision (it ends the "
        "episode), human collision, stuck (no progress for 10 s while not halting), else timeout while "
        "moving (socialzoo.env.metrics).",
        "",
        *markdown_table(["policy", "map", "success", *FAILURE_LABELS.values()], rows),
    ]


def write_tables(
    summary: Sequence[Mapping[str, Any]],
    out: str | Path,
    *,
    name: str = "summary",
    title: str = "Benchmark results",
    layout: TableLayout = PAPER_LAYOUT,
) -> list[Path]:
    """The one table writer: out/NAME.csv (`write_summary_csv`) and out/NAME.md
    (`summary_markdown`) of summary entries in a layout, each written whole or not at all."""
    out = Path(out)
    return [
        write_summary_csv(summary, out / f"{name}.csv", layout),
        write_text_atomic(out / f"{name}.md", summary_markdown(summary, title=title, layout=layout)),
    ]
