"""The paper's figures from the loaded results (socialzoo.reproduce.results.load), PNG and PDF: success, metrics,
RL curves, LfD and, with several training seeds, performance profiles."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from socialzoo.bench.tables import policy_label

FORMATS: tuple[str, ...] = ("png", "pdf")


def figures_allowed(results: Mapping[str, Any]) -> set[str]:
    """The names of the figures that `results` can draw (draw_figures): a figure file of another name
    in the folder is an earlier run's."""
    allowed = set()
    allowed |= {"success", "metrics"} if results.get("performance") or results.get("transfer") else set()
    allowed |= {"rl_curves"} if results.get("rl_curves") else set()
    allowed |= {"lfd"} if results.get("lfd") else set()
    allowed |= {"profiles"} if results.get("profiles") else set()
    return allowed


# Every figure draw_figures may draw, by name.
FIGURE_NAMES: tuple[str, ...] = ("success", "metrics", "rl_curves", "lfd", "profiles")


def plot_lfd(rows: Sequence[Mapping[str, Any]], out_dir: str | Path) -> list[Path]:
    """lfd.{png,pdf}: success % of each LfD policy against its demonstration steps (log scale),
    with 90% intervals, and the paper's numbers as black crosses."""
    from socialzoo.bench.figures import pyplot, save_figure, series_color

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for i, policy in enumerate(dict.fromkeys(str(r["policy"]) for r in rows)):
        points = sorted((r for r in rows if r["policy"] == policy), key=lambda r: r["demonstration_steps"])
        x = [r["demonstration_steps"] for r in points]
        y = [100 * r["success_rate"] for r in points]
        low = [100 * (r["success_rate"] - r["success_ci_low"]) for r in points]
        high = [100 * (r["success_ci_high"] - r["success_rate"]) for r in points]
        color = series_color(i)
        ax.errorbar(x, y, yerr=[low, high], color=color, marker="o", capsize=3, label=policy_label(policy))
        paper = [(r["demonstration_steps"], r["paper_success_pct"]) for r in points]
        paper = [(px, py) for px, py in paper if isinstance(py, float) and math.isfinite(py)]
        if paper:
            ax.scatter(*zip(*paper, strict=True), marker="x", color=color, s=50, zorder=3)
    ax.scatter([], [], marker="x", color="black", label="paper")
    ax.set_xscale("log")
    ax.set_xlabel("demonstration steps")
    ax.set_ylabel("success, %")
    ax.set_ylim(-2, 102)
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    return save_figure(fig, out_dir, "lfd", FORMATS)


def draw_figures(results: Mapping[str, Any], out_dir: str | Path) -> dict[str, list[Path]]:
    """Every figure the results allow, into out_dir; returns name -> files ("success",
    "metrics", "rl_curves", "lfd").

    - success.{png,pdf}, metrics.{png,pdf}: success rates with the paper's marks, and force, blame and
      time to goal, per policy on the training and transfer maps (socialzoo.bench.figures);
    - rl_curves.{png,pdf}: success, time and reward of every checkpoint with 90% bands
      (socialzoo.studies.rl_curves.plot_curves);
    - lfd.{png,pdf}: LfD success against demonstration steps with 90% intervals and the paper's marks;
    - profiles.{png,pdf}: with several training seeds, performance profiles per map
      (socialzoo.studies.seeds.plot_profiles).

    The files of the other FIGURE_NAMES are removed: an earlier run's in the same folder (a run of
    other settings, of parts these results lack) would be shown and published as this run's.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    drawn: dict[str, list[Path]] = {}
    summary = [*results.get("performance", []), *results.get("transfer", [])]
    if summary:
        from socialzoo.bench.figures import plot_metrics, plot_success

        drawn["success"] = plot_success(summary, out, FORMATS)
        drawn["metrics"] = plot_metrics(summary, out, FORMATS)
    curves = results.get("rl_curves", [])
    if curves:
        from socialzoo.studies.rl_curves import plot_curves

        points = [r for r in curves if math.isfinite(r["step"])]
        refs = [r for r in curves if not math.isfinite(r["step"])]
        drawn["rl_curves"] = plot_curves(points, out, refs, FORMATS)
    if results.get("lfd"):
        drawn["lfd"] = plot_lfd(results["lfd"], out)
    if results.get("profiles"):
        from socialzoo.studies.seeds import plot_profiles

        profiles = plot_profiles(results["profiles"], out, FORMATS)
        if profiles:
            drawn["profiles"] = profiles
    from socialzoo.bench.tables import remove_outputs

    remove_outputs(out, set(FIGURE_NAMES) - set(drawn), FORMATS)
    return drawn
