"""Learned humans against social-force humans on the same scenarios: one table, one figure, the targets."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark
from socialzoo.bench.human_metrics import HUMAN_METRIC_KEYS, HUMAN_METRIC_LABELS, summarize_humans
from socialzoo.bench.tables import markdown_table, write_csv
from socialzoo.bench.test_sets import family_validation_set
from socialzoo.core.files import write_text_atomic
from socialzoo.core.metrics import metric, registered
from socialzoo.scenarios.scenario_sets import TestSet, validation_set
from socialzoo.studies.crowd_matrix import interval_cell, run_trials

POPULATIONS = ("social_force", "learned")


def _robot_row(name: str) -> tuple[str, str, int]:
    """(summary key of socialzoo.bench.tables.summarize, label, digits) of a robot metric, from the
    metric registry: a flag's rate ("success_rate"), any other metric's mean ("mean_force_mean")."""
    m = metric(name)
    if m.kind == "bool":
        return f"{name}_rate", f"robot {m.label} rate", m.digits
    return f"{name}_mean", f"robot {m.heading}", m.digits


# The robot's metrics shown beside the humans'.
ROBOT_METRICS: tuple[tuple[str, str, int], ...] = tuple(
    map(_robot_row, registered("success", "mean_force", "mean_blame"))
)
# The humans' collision counts (their targets: no more with learned humans).
COLLISION_KEYS = tuple(key for key in HUMAN_METRIC_KEYS if metric(key).count)
# Target: the learned reach rate is at least this fraction of the social-force one.
REACH_TOLERANCE = 0.10


@dataclass(frozen=True, kw_only=True)
class ComparisonConfig:
    """A comparison of learned humans with social-force humans.

    Attributes:
        humans: "learned:PATH", the learned human policy file.
        policy: the robot's policy spec (socialzoo.agents), Ref by default.
        maps: maps whose test sets are used ("<map>-test", or "<map>-quick" with quick).
        trials: scenarios per map (the first of each test set); None: all.
        quick: use the quick test sets.
        validation: use each map's validation scenarios ("<map>-val",
            socialzoo.scenarios.scenario_sets.validation_set) instead of a test set: for choosing training
            settings or checkpoints without looking at a test set.
        workers: local processes.
        batch_size: env rows stepped together per worker.
        env_overrides: EnvConfig fields for both populations (e.g. {"max_steps": 1600}).
        family: with validation, a scenario family: its validation cases on each map ("<family>-val",
            socialzoo.bench.test_sets.family_validation_set), played with EnvConfig.family, in place of
            the map's validation scenarios (for humans trained on the family).
    """

    humans: str
    policy: str = "ref"
    maps: tuple[str, ...] = ("gdc1", "ghc3")
    trials: int | None = None
    quick: bool = False
    validation: bool = False
    workers: int | None = 2
    batch_size: int = 64
    env_overrides: Mapping[str, Any] = field(default_factory=dict)
    family: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.humans, str) or not self.humans.startswith("learned:"):
            raise ValueError(f"ComparisonConfig.humans must be 'learned:PATH', got {self.humans!r}")
        object.__setattr__(self, "maps", tuple(self.maps))
        if self.quick and self.validation:
            raise ValueError("ComparisonConfig: quick (test sets) and validation exclude each other")
        if self.family is not None and not self.validation:
            raise ValueError(
                f"ComparisonConfig.family ({self.family!r}) names validation cases: set validation"
            )
        self.benchmark("social_force")  # a bad map, policy, file or count fails here, naming it
        self.benchmark(self.humans)

    def benchmark(self, humans: str) -> BenchmarkConfig:
        """The benchmark run of one population."""
        return BenchmarkConfig(
            policies=(self.policy,),
            maps=self.maps,
            trials=self.trials,
            quick=self.quick,
            workers=self.workers,
            batch_size=self.batch_size,
            env_overrides={**({} if self.family is None else {"family": self.family}), **self.env_overrides},
            humans=humans,
            human_metrics=True,
        )


@dataclass
class Comparison:
    """What compare_humans found.

    Attributes:
        out_dir: the output folder.
        rows: one dict per (map, population): trials, every human metric's mean and interval,
            the robot's success, force and blame.
        targets: per map, {"reach": bool, "collisions": bool, "met": bool}.
        files: the files written.
    """

    out_dir: Path
    rows: list[dict[str, Any]]
    targets: dict[str, dict[str, bool]]
    files: list[Path]


def compare_humans(
    config: ComparisonConfig,
    out_dir: str | Path,
    *,
    test_sets: Mapping[str, TestSet] | None = None,
    progress: bool = True,
    figures: bool = True,
) -> Comparison:
    """Run both populations and write comparison.md, comparison.csv and comparison.png.

    Runs the benchmark twice on the same test sets and robot policy (Ref by default), once among the
    social-force humans and once among the learned humans of a policy file, both with the humans' metrics
    (socialzoo.bench.human_metrics), each into its own folder (social_force/, learned/: results stores, so a
    rerun reads its trials back). comparison.md and comparison.csv hold every human metric and the robot's
    success, force and blame, side by side with 90% intervals; comparison.png the same as bars. It checks
    issue 13's targets: the learned humans' route-goal reach rate within 10% of the social-force humans' (no
    lower than 0.9 times it) and no more collisions of any kind (human-human, human-wall, human-robot, means
    per episode).

    Args:
        config: what to compare.
        out_dir: output folder (social_force/ and learned/ inside hold the two benchmark runs).
        test_sets: test sets to use instead of the registry's (keyed by map name), for tests.
        progress: show progress bars.
        figures: draw comparison.png (needs matplotlib).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if config.validation:
        test_sets = {m: _validation_set(m, config.family) for m in config.maps} | dict(test_sets or {})
    rows: list[dict[str, Any]] = []
    for population in POPULATIONS:
        humans = "social_force" if population == "social_force" else config.humans
        result = run_benchmark(
            config.benchmark(humans), out / population, test_sets=test_sets, progress=progress, figures=False
        )
        trials = run_trials(result.out_dir)
        humans_summary = summarize_humans(trials, policies=[config.policy], maps=[])
        robot = {e["map"]: e for e in result.summary}
        for entry in humans_summary:
            row = {"population": population, **entry}
            for key, _, _ in ROBOT_METRICS:
                row[key] = robot.get(entry["map"], {}).get(key, float("nan"))
            rows.append(row)
    targets = check_targets(rows)
    files = [write_comparison_csv(rows, out / "comparison.csv")]
    files.append(write_comparison_md(rows, targets, out / "comparison.md", config))
    if figures:
        files.append(plot_comparison(rows, out / "comparison.png"))
    return Comparison(out, rows, targets, files)


def _validation_set(map_name: str, family: str | None) -> TestSet:
    """The validation scenarios of a map, or a family's validation cases on it."""
    return validation_set(map_name) if family is None else family_validation_set(family, map_name)


def check_targets(rows: list[dict[str, Any]]) -> dict[str, dict[str, bool]]:
    """Per map: the learned reach rate >= (1 - REACH_TOLERANCE) x the social-force one, and no
    more collisions of any kind (means per episode)."""
    out: dict[str, dict[str, bool]] = {}
    for map_name in dict.fromkeys(r["map"] for r in rows):
        by = {r["population"]: r for r in rows if r["map"] == map_name}
        if set(by) != set(POPULATIONS):
            continue
        social, learned = by["social_force"], by["learned"]
        reach = learned["humans_goal_rate_mean"] >= (1 - REACH_TOLERANCE) * social["humans_goal_rate_mean"]
        collisions = all(learned[f"{k}_mean"] <= social[f"{k}_mean"] for k in COLLISION_KEYS)
        out[map_name] = {
            "reach": bool(reach),
            "collisions": bool(collisions),
            "met": bool(reach and collisions),
        }
    return out


def write_comparison_csv(rows: list[dict[str, Any]], path: Path) -> Path:
    """Every column of the comparison rows."""
    return write_csv(rows, path, blank_nan=False, lineterminator="\n")


def write_comparison_md(
    rows: list[dict[str, Any]], targets: dict[str, dict[str, bool]], path: Path, config: ComparisonConfig
) -> Path:
    """A table per map: metrics as rows, the two populations as columns, then the targets."""
    lines = [
        f"# Learned humans ({config.humans}) against social-force humans",
        "",
        f"Robot policy {config.policy}; the same scenarios for both populations "
        f"({'validation scenarios, not a test set' if config.validation else 'test sets'}); means over episodes "
        "with 90% intervals (bootstrap for collision counts). Human metrics: socialzoo.bench.human_metrics.",
        "",
    ]
    for map_name in dict.fromkeys(r["map"] for r in rows):
        by = {r["population"]: r for r in rows if r["map"] == map_name}
        present = [p for p in POPULATIONS if p in by]
        header = ["metric", *(f"{p.replace('_', '-')} ({by[p]['trials']})" for p in present)]
        cells = [
            [
                HUMAN_METRIC_LABELS[key][0],
                *(interval_cell(by[p], key, HUMAN_METRIC_LABELS[key][1], "ci_") for p in present),
            ]
            for key in HUMAN_METRIC_KEYS
        ]
        cells += [
            [label, *(f"{by[p][key]:.{digits}f}" for p in present)] for key, label, digits in ROBOT_METRICS
        ]
        lines += [f"## {map_name}", "", *markdown_table(header, cells), ""]
        if map_name in targets:
            t = targets[map_name]
            lines.append(
                f"Targets on {map_name}: reach rate within {REACH_TOLERANCE:.0%} "
                f"{'met' if t['reach'] else 'NOT met'}; no more collisions {'met' if t['collisions'] else 'NOT met'}."
            )
            lines.append("")
    return write_text_atomic(path, "\n".join(lines))


def plot_comparison(rows: list[dict[str, Any]], path: Path) -> Path:
    """Bars of every human metric and the robot's success, force and blame: one panel per metric,
    maps along x, the two populations side by side, 90% intervals as error bars."""
    import numpy as np

    from socialzoo.bench.figures import pyplot, save_figure

    plt = pyplot()
    panels = [(k, HUMAN_METRIC_LABELS[k][0], True) for k in HUMAN_METRIC_KEYS]
    panels += [(k, label, False) for k, label, _ in ROBOT_METRICS]
    maps = list(dict.fromkeys(r["map"] for r in rows))
    cols = 4
    fig, axes = plt.subplots(int(np.ceil(len(panels) / cols)), cols, figsize=(3.4 * cols, 2.6 * 3))
    x = np.arange(len(maps))
    for ax, (key, label, has_ci) in zip(axes.flat, panels, strict=False):
        for i, population in enumerate(POPULATIONS):
            by = {r["map"]: r for r in rows if r["population"] == population}
            name = f"{key}_mean" if has_ci else key
            means = np.array([by.get(m, {}).get(name, np.nan) for m in maps], dtype=float)
            err = None
            if has_ci:
                low = np.array([by.get(m, {}).get(f"{key}_ci_low", np.nan) for m in maps], dtype=float)
                high = np.array([by.get(m, {}).get(f"{key}_ci_high", np.nan) for m in maps], dtype=float)
                err = np.nan_to_num(np.vstack([means - low, high - means]).clip(min=0))
            ax.bar(
                x + (i - 0.5) * 0.38,
                np.nan_to_num(means),
                0.38,
                yerr=err,
                capsize=2,
                label=population.replace("_", "-"),
            )
        ax.set_xticks(x, maps)
        ax.set_title(label, fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(panels) :]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path.parent, path.stem, (path.suffix[1:],), dpi=110)[0]
