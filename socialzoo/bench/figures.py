"""Benchmark figures (matplotlib, PNG and PDF): success rates by policy and map with the paper's numbers, the
failures by cause, and force, blame and time to goal with 90% confidence intervals, maps side by side."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from socialzoo.bench.tables import FAILURE_LABELS, MAP_ROLES, paper_success, policy_labels
from socialzoo.core.metrics import axis_label, registered

FIGURE_FORMATS = ("png", "pdf")
# The figures plot_summary draws: a run that draws none removes an older run's (remove_outputs).
SUMMARY_FIGURES = ("success", "failures", "metrics")
# Panels of the metrics figure: (metric, axis label), the labels from the metric registry.
METRIC_PANELS: tuple[tuple[str, str], ...] = tuple(
    (name, axis_label(name)) for name in registered("mean_force", "mean_blame", "time_to_goal")
)
# Characters per line of a policy's label (a group is about 1.2 inches wide at 10 points).
_TICK_CHARS = 14
# Paul Tol's bright palette (colour-blind safe), for every figure's series.
_COLORS = ("#4477aa", "#ee6677", "#228833", "#ccbb44", "#66ccee", "#aa3377")


def series_color(i: int) -> str:
    """The colour of a figure's i-th series (policy, window, ...), cycling through the palette."""
    return _COLORS[i % len(_COLORS)]


def pyplot() -> Any:
    """matplotlib.pyplot with the non-interactive Agg backend (matplotlib imported on first use).

    Raises:
        ModuleNotFoundError: matplotlib, the "plot" extra, is not installed (the message says how
            to install it).
    """
    try:
        import matplotlib
    except ModuleNotFoundError as err:
        raise ModuleNotFoundError(
            "the figures need matplotlib, the plot extra: pip install 'socialzoo[plot]'", name="matplotlib"
        ) from err

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _layout(
    summary: Sequence[Mapping[str, Any]],
) -> tuple[list[str], list[str], dict[tuple[str, str], Mapping]]:
    policies = list(dict.fromkeys(e["policy"] for e in summary))
    maps = list(dict.fromkeys(e["map"] for e in summary))
    return policies, maps, {(e["policy"], e["map"]): e for e in summary}


def _policy_ticks(ax: Any, policies: list[str]) -> None:
    """The policies' labels under their groups, wrapped to the group's width (a learned policy's
    label holds its file name: "PPO (final_model.safetensors)" overran its neighbours)."""
    ax.set_xticks(range(len(policies)))
    ax.set_xlim(-0.5, len(policies) - 0.5)  # every group's slot, with or without bars
    ax.set_xticklabels([_wrapped(label) for label in policy_labels(policies).values()])


def _wrapped(label: str) -> str:
    """A policy's label in lines of at most _TICK_CHARS characters."""
    return textwrap.fill(label, _TICK_CHARS, break_on_hyphens=False)


def _map_label(map_name: str) -> str:
    role = MAP_ROLES.get(map_name)
    return f"{map_name} ({'training' if role == 'test' else role})" if role else map_name


def _bars(
    ax: Any,
    policies: list[str],
    maps: list[str],
    by_key: dict[tuple[str, str], Mapping],
    key: str,
    low_key: str,
    high_key: str,
    scale: float = 1.0,
) -> float:
    """Grouped bars (policy groups, one bar per map) with interval error bars; returns the bar width."""
    width = 0.8 / max(len(maps), 1)
    for j, m in enumerate(maps):
        xs, heights, err_low, err_high = [], [], [], []
        for i, p in enumerate(policies):
            e = by_key.get((p, m))
            if e is None or not math.isfinite(e[key]):
                continue
            value = scale * e[key]
            low = scale * e[low_key] if math.isfinite(e[low_key]) else value
            high = scale * e[high_key] if math.isfinite(e[high_key]) else value
            xs.append(i + (j - (len(maps) - 1) / 2) * width)
            heights.append(value)
            err_low.append(max(value - low, 0.0))
            err_high.append(max(high - value, 0.0))
        ax.bar(
            xs,
            heights,
            width * 0.92,
            yerr=[err_low, err_high],
            capsize=3,
            color=series_color(j),
            label=_map_label(m),
        )
    _policy_ticks(ax, policies)
    return width


def save_figure(
    fig: Any, out_dir: str | Path, stem: str, formats: Sequence[str] = FIGURE_FORMATS, dpi: int = 150
) -> list[Path]:
    """Save a figure as out_dir/STEM.FORMAT for each format (the folder made if missing), close
    it, and return the files."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{stem}.{fmt}" for fmt in formats]
    for path in paths:
        fig.savefig(path, dpi=dpi, bbox_inches="tight")
    pyplot().close(fig)
    return paths


def plot_success(
    summary: Sequence[Mapping[str, Any]],
    out_dir: str | Path,
    formats: Sequence[str] = FIGURE_FORMATS,
    interval: str = "90% CI",
) -> list[Path]:
    """success.{png,pdf}: success rate (%) per policy, one bar per map with its Wilson interval
    (the benchmark's 90%; `interval` names the one given), and the paper's number as a black tick
    where the paper has one; returns the files written."""
    plt = pyplot()
    policies, maps, by_key = _layout(summary)
    fig, ax = plt.subplots(figsize=(max(4.0, 1.3 * len(policies) + 2.0), 3.6))
    width = _bars(ax, policies, maps, by_key, "success_rate", "success_ci_low", "success_ci_high", 100.0)
    labelled = False
    for j, m in enumerate(maps):
        for i, p in enumerate(policies):
            paper = paper_success(p, m)
            if paper is None:
                continue
            x = i + (j - (len(maps) - 1) / 2) * width
            ax.plot(
                [x - 0.4 * width, x + 0.4 * width],
                [paper, paper],
                color="black",
                linewidth=2,
                label=None if labelled else "paper",
            )
            labelled = True
    ax.set_ylabel(f"success rate, % ({interval})")
    ax.set_ylim(0, 105)
    ax.legend(loc="lower right", fontsize="small")
    ax.set_title("Success rate")
    return save_figure(fig, out_dir, "success", formats)


def plot_metrics(
    summary: Sequence[Mapping[str, Any]], out_dir: str | Path, formats: Sequence[str] = FIGURE_FORMATS
) -> list[Path]:
    """metrics.{png,pdf}: force, blame and time to goal (successful episodes) per policy, the
    training and transfer maps side by side, with 90% Student-t intervals; returns the files written."""
    plt = pyplot()
    policies, maps, by_key = _layout(summary)
    # A panel is wide enough for its policy groups' wrapped labels (about 0.08 inches a character at
    # the ticks' size): as wide as ever for short names, wider for learned policies' file names.
    lines = [line for label in policy_labels(policies).values() for line in _wrapped(label).split("\n")]
    panel = max(4.2, len(policies) * (0.08 * max(map(len, lines), default=0) + 0.25) + 0.6)
    fig, axes = plt.subplots(1, len(METRIC_PANELS), figsize=(panel * len(METRIC_PANELS), 3.4))
    for ax, (name, label) in zip(axes, METRIC_PANELS, strict=True):
        _bars(ax, policies, maps, by_key, f"{name}_mean", f"{name}_ci_low", f"{name}_ci_high")
        ax.set_ylabel(label)
        ax.set_ylim(bottom=0)
    axes[0].legend(fontsize="small")
    fig.tight_layout()
    return save_figure(fig, out_dir, "metrics", formats)


# Colours of the failure causes (success is white) in failures.{png,pdf}.
_CAUSE_COLORS = {
    "human_collision": "#ee6677",
    "wall_collision": "#222222",
    "stuck": "#ccbb44",
    "timeout": "#66ccee",
}


def plot_failures(
    summary: Sequence[Mapping[str, Any]], out_dir: str | Path, formats: Sequence[str] = FIGURE_FORMATS
) -> list[Path]:
    """failures.{png,pdf}: for each policy and map, a bar of the episodes that failed, stacked by
    cause (human collision, wall collision, stuck, timeout while moving; % of episodes); returns the
    files written."""
    plt = pyplot()
    policies, maps, by_key = _layout(summary)
    fig, ax = plt.subplots(figsize=(max(4.0, 1.3 * len(policies) * max(len(maps), 1) / 2 + 2.5), 3.6))
    width = 0.8 / max(len(maps), 1)
    labelled: set[str] = set()
    for j, m in enumerate(maps):
        for i, p in enumerate(policies):
            e = by_key.get((p, m))
            if e is None:
                continue
            x = i + (j - (len(maps) - 1) / 2) * width
            bottom = 0.0
            for cause, label in FAILURE_LABELS.items():
                value = 100.0 * float(e.get(f"failure_{cause}_rate", math.nan))
                if not math.isfinite(value) or value <= 0.0:
                    continue
                ax.bar(x, value, width * 0.92, bottom=bottom, color=_CAUSE_COLORS[cause],
                       label=None if cause in labelled else label)  # fmt: skip
                labelled.add(cause)
                bottom += value
            # The map's name above a short bar, inside a tall one: never out of the axes.
            inside = bottom > 50.0
            ax.text(x, bottom - 1.5 if inside else bottom + 1.5, m, ha="center", fontsize=6, rotation=90,
                    va="top" if inside else "bottom", clip_on=True,
                    bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.7, "pad": 0.5})  # fmt: skip
    _policy_ticks(ax, policies)
    ax.set_ylabel("failed episodes, % (by cause)")
    ax.set_ylim(0, 105)
    if labelled:
        ax.legend(fontsize="small")
    ax.set_title("Failures by cause")
    return save_figure(fig, out_dir, "failures", formats)


def plot_summary(
    summary: Sequence[Mapping[str, Any]], out_dir: str | Path, formats: Sequence[str] = FIGURE_FORMATS
) -> list[Path]:
    """The three figures; returns every file written."""
    return (
        plot_success(summary, out_dir, formats)
        + plot_failures(summary, out_dir, formats)
        + plot_metrics(summary, out_dir, formats)
    )
