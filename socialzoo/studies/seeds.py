"""Training seeds as an axis: the same learner trained with K seeds, each seed's policy evaluated on the same
scenarios, and the aggregates over the seeds (socialzoo.bench.aggregates)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.bench.aggregates import (
    PROFILE_TAUS,
    SEED_CONFIDENCE,
    SEED_RESAMPLES,
    aggregate,
    cell_generator,
    performance_profile,
    probability_of_improvement,
    score_matrix,
    where_in,
)
from socialzoo.bench.tables import write_csv

SEEDS_CSV = "seeds.csv"
IMPROVEMENT_CSV = "improvement.csv"
PROFILES_CSV = "profiles.csv"
PROFILES_STEM = "profiles"
# Seed of every bootstrap generator (with the cell's names).
BOOTSTRAP_SEED = 0


@dataclass(frozen=True)
class SeedGroup:
    """One policy in one setting, over its seeds.

    A setting is a map of the performance or transfer experiment, or an LfD demonstration size. Engineered
    policies (GoAlone, Ref) have one "seed": they are deterministic.

    Attributes:
        experiment: "performance", "transfer" or "lfd".
        policy: the policy's registry name ("ppo").
        map: the map its scenarios are on.
        demonstration_steps: the LfD training size (None outside the LfD experiment).
        seeds: the training seeds (one entry, 0, for an engineered policy).
        scores: per seed, {scenario index: success (0 or 1)}.
        paper_pct: the paper's number for this policy and setting (success %), or None.
    """

    experiment: str
    policy: str
    map: str
    demonstration_steps: int | None
    seeds: tuple[int, ...]
    scores: tuple[Mapping[int, float], ...]
    paper_pct: float | None = None

    @property
    def key(self) -> tuple[str, ...]:
        """Names that seed this group's bootstrap generator."""
        return (self.experiment, self.policy, self.map, str(self.demonstration_steps or ""))


def benchmark_rows(folder: str | Path, policy: str) -> list[dict[str, Any]]:
    """The stored trials (ResultsStore.rows) of `policy` in a benchmark folder
    (socialzoo.bench.experiment's config.json and results.sqlite): those of the config hashes the
    folder's last run used, its first `trials` scenarios of each test set.

    Raises:
        FileNotFoundError: the folder holds no benchmark run.
        KeyError: the policy was not in its last run.
    """
    from socialzoo.bench.experiment import CONFIG_NAME, STORE_NAME
    from socialzoo.bench.store import ResultsStore
    from socialzoo.core.files import read_json

    folder = Path(folder)
    config = read_json(folder / CONFIG_NAME, "benchmark record", ValueError, kind=dict)
    out: list[dict[str, Any]] = []
    found = False
    with ResultsStore(folder / STORE_NAME) as store:
        for name, config_hash in config.get("config_hashes", {}).items():
            spec, _, test_set = name.rpartition("/")
            if spec != policy:
                continue
            found = True
            trials = int(config["test_sets"][test_set]["trials"])
            out += store.rows(policy=spec, test_set=test_set, config_hash=config_hash, indices=range(trials))
    if not found:
        raise KeyError(f"{folder}: policy {policy!r} is not in its benchmark run")
    return out


def benchmark_scores(folder: str | Path, policy: str, key: str = "success") -> dict[int, float]:
    """{scenario index: score} of `policy` in a benchmark folder (`benchmark_rows`); success as
    0 or 1.

    Raises:
        FileNotFoundError: the folder holds no benchmark run.
        KeyError: the policy was not in its last run.
    """
    return {
        int(row["scenario_index"]): float(bool(row[key])) if key == "success" else float(row[key])
        for row in benchmark_rows(folder, policy)
    }


def _pct(value: float) -> float:
    return 100.0 * value if math.isfinite(value) else math.nan


def seed_rows(
    groups: Sequence[SeedGroup],
    *,
    confidence: float = SEED_CONFIDENCE,
    resamples: int = SEED_RESAMPLES,
) -> list[dict[str, Any]]:
    """One row per group: seeds, scenarios, mean and IQM success (%) with stratified bootstrap
    intervals over seeds and scenarios, each seed's success (%) and the paper's number with where
    it falls among the seeds."""
    rows = []
    for g in groups:
        matrix = score_matrix(list(g.scores))
        agg = aggregate(
            matrix, confidence=confidence, resamples=resamples, rng=cell_generator(BOOTSTRAP_SEED, *g.key)
        )
        per_seed = [100.0 * v for v in agg.seed_scores]
        paper = g.paper_pct
        rows.append(
            {
                "experiment": g.experiment,
                "policy": g.policy,
                "map": g.map,
                "demonstration_steps": g.demonstration_steps if g.demonstration_steps is not None else "",
                "seeds": len(g.seeds),
                "scenarios": agg.scenarios,
                "mean_pct": _pct(agg.mean.value),
                "mean_ci_low_pct": _pct(agg.mean.low),
                "mean_ci_high_pct": _pct(agg.mean.high),
                "iqm_pct": _pct(agg.iqm.value),
                "iqm_ci_low_pct": _pct(agg.iqm.low),
                "iqm_ci_high_pct": _pct(agg.iqm.high),
                "min_pct": min(per_seed),
                "max_pct": max(per_seed),
                "seed_list": ";".join(str(s) for s in g.seeds),
                "seed_success_pct": ";".join(f"{v:.2f}" for v in per_seed),
                "paper_pct": paper if paper is not None else math.nan,
                "paper_where": where_in(paper, per_seed) if paper is not None else "",
                "paper_in_interval": (
                    bool(agg.mean.low * 100 <= paper <= agg.mean.high * 100) if paper is not None else ""
                ),
            }
        )
    return rows


def improvement_rows(
    groups: Sequence[SeedGroup],
    pairs: Sequence[tuple[str, str]],
    *,
    confidence: float = SEED_CONFIDENCE,
    resamples: int = SEED_RESAMPLES,
) -> list[dict[str, Any]]:
    """Probability of improvement P(X > Y) for each (X, Y) in `pairs` in every setting where both
    were evaluated (same experiment, map and LfD size), on the scenarios both ran."""
    index = {(g.experiment, g.map, g.demonstration_steps, g.policy): g for g in groups}
    rows = []
    for (experiment, map_name, steps, policy), gx in index.items():
        for x, y in pairs:
            gy = index.get((experiment, map_name, steps, y))
            if policy != x or gy is None:
                continue
            common = set.intersection(*(set(s) for s in (*gx.scores, *gy.scores)))
            mx = score_matrix([{i: s[i] for i in common} for s in gx.scores])
            my = score_matrix([{i: s[i] for i in common} for s in gy.scores])
            rng = cell_generator(BOOTSTRAP_SEED, experiment, map_name, str(steps or ""), x, y)
            p = probability_of_improvement(mx, my, confidence=confidence, resamples=resamples, rng=rng)
            rows.append(
                {
                    "experiment": experiment,
                    "map": map_name,
                    "demonstration_steps": steps if steps is not None else "",
                    "x": x,
                    "y": y,
                    "seeds_x": len(gx.seeds),
                    "seeds_y": len(gy.seeds),
                    "scenarios": mx.shape[1],
                    "probability": p.value,
                    "ci_low": p.low,
                    "ci_high": p.high,
                }
            )
    return rows


def profile_rows(
    groups: Sequence[SeedGroup],
    taus: Sequence[float] = PROFILE_TAUS,
    *,
    confidence: float = SEED_CONFIDENCE,
    resamples: int = SEED_RESAMPLES,
) -> list[dict[str, Any]]:
    """The performance profile of each group: for each tau, the share of its seeds whose success
    exceeds tau, with bootstrap bands."""
    rows = []
    for g in groups:
        matrix = score_matrix(list(g.scores))
        rng = cell_generator(BOOTSTRAP_SEED, "profile", *g.key)
        for tau, p in zip(
            taus,
            performance_profile(matrix, taus, confidence=confidence, resamples=resamples, rng=rng),
            strict=True,
        ):
            rows.append(
                {
                    "experiment": g.experiment,
                    "policy": g.policy,
                    "map": g.map,
                    "demonstration_steps": g.demonstration_steps if g.demonstration_steps is not None else "",
                    "tau": tau,
                    "share": p.value,
                    "ci_low": p.low,
                    "ci_high": p.high,
                }
            )
    return rows


def _no_size(value: Any) -> bool:
    """True for an empty demonstration-size cell (as written, or NaN as read back)."""
    return value in ("", None) or (isinstance(value, float) and math.isnan(value))


def plot_profiles(
    rows: Sequence[Mapping[str, Any]], out_dir: str | Path, formats: Sequence[str] = ("png", "pdf")
) -> list[Path]:
    """profiles.{png,pdf}: one panel per (experiment, map): each policy's share of seeds whose
    success exceeds tau, against tau, with its bootstrap band."""
    from socialzoo.bench.figures import pyplot, save_figure, series_color
    from socialzoo.bench.tables import policy_label

    rows = [r for r in rows if _no_size(r["demonstration_steps"])]  # the LfD sizes are not drawn
    panels = list(dict.fromkeys((str(r["experiment"]), str(r["map"])) for r in rows))
    if not panels:
        return []
    plt = pyplot()
    fig, axes = plt.subplots(1, len(panels), figsize=(4.4 * len(panels), 3.4), squeeze=False)
    for ax, (experiment, map_name) in zip(axes[0], panels, strict=True):
        mine = [r for r in rows if r["experiment"] == experiment and r["map"] == map_name]
        for i, policy in enumerate(dict.fromkeys(str(r["policy"]) for r in mine)):
            points = [r for r in mine if r["policy"] == policy]
            x = [100 * float(r["tau"]) for r in points]
            color = series_color(i)
            ax.step(x, [r["share"] for r in points], where="post", color=color, label=policy_label(policy))
            ax.fill_between(
                x,
                [r["ci_low"] for r in points],
                [r["ci_high"] for r in points],
                step="post",
                color=color,
                alpha=0.15,
            )
        ax.set_title(f"{experiment} ({map_name})", fontsize=10)
        ax.set_xlabel("success tau, %")
        ax.set_ylabel("share of seeds with success > tau")
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, out_dir, PROFILES_STEM, formats)


def write_seed_study(
    groups: Sequence[SeedGroup],
    pairs: Sequence[tuple[str, str]],
    out_dir: str | Path,
    *,
    resamples: int = SEED_RESAMPLES,
) -> list[Path]:
    """seeds.csv, improvement.csv and profiles.csv of the groups into out_dir (empty groups: none
    is written and earlier ones are removed).

    seeds.csv: one row per group: mean and IQM with their 95% intervals, every seed's success, and where the
    paper's single-run number falls in the seed distribution. improvement.csv: probability of improvement
    between pairs of policies per map. profiles.csv with profiles.{png,pdf}: performance profiles per map.
    """
    out = Path(out_dir)
    names = (SEEDS_CSV, IMPROVEMENT_CSV, PROFILES_CSV)
    if not groups:
        for name in names:
            (out / name).unlink(missing_ok=True)
        return []
    tables = (
        seed_rows(groups, resamples=resamples),
        improvement_rows(groups, pairs, resamples=resamples),
        profile_rows(groups, resamples=resamples),
    )
    return [write_csv(rows, out / name) for rows, name in zip(tables, names, strict=True)]
