"""The protocol's seed results: which stored trials belong to which seed, aggregated by socialzoo.studies.seeds, and
which checkpoint each RL run kept (chosen on validation scenarios)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from socialzoo.reproduce.paper import EXPERIMENT_MAPS, PAPER_SUCCESS, paper_lfd
from socialzoo.reproduce.runs import (
    SEEDS_DIR,
    SEEDS_FOLDER,
    Context,
    finished,
    lfd_eval_dir,
    lfd_items,
    rl_items,
)

SELECTION_CSV = "selection.csv"
# Probability-of-improvement pairs (X, Y): P(a seed of X succeeds more often than one of Y).
IMPROVEMENT_PAIRS: tuple[tuple[str, str], ...] = (
    ("ppo", "ref"),
    ("dqn", "ref"),
    ("bc", "ref"),
    ("gail", "ref"),
    ("pips", "ref"),
    ("ppo", "dqn"),
    ("bc", "gail"),
)
ENGINEERED = ("goalone", "ref")


def _kept_files(items: list[tuple[str, Any]]) -> list[Path | None]:
    """The kept policy of each finished item (None for a run not finished): no training here."""
    from socialzoo.train import trainer_spec
    from socialzoo.train.validation import kept_policy

    return [
        kept_policy(trainer_spec(name).policy_path(args)) if finished(name, args) else None
        for name, args in items
    ]


def _groups(ctx: Context) -> list[Any]:
    """SeedGroups of every experiment whose trials are stored for every seed."""
    from socialzoo.studies.seeds import SeedGroup, benchmark_scores

    s = ctx.settings
    groups: list[SeedGroup] = []
    learned = rl_items(ctx) + lfd_items(ctx, (s.lfd_largest,))
    files = _kept_files(learned)
    for experiment, (map_name, index) in EXPERIMENT_MAPS.items():
        folder = ctx.ledger.path(experiment)
        if not (folder / "config.json").is_file():
            continue
        try:
            for policy in ENGINEERED:
                scores = benchmark_scores(folder, policy)
                groups.append(
                    SeedGroup(
                        experiment, policy, map_name, None, (s.seed,), (scores,), PAPER_SUCCESS[policy][index]
                    )
                )
            by_policy: dict[str, list[tuple[int, dict[int, float]]]] = {}
            for (name, args), path in zip(learned, files, strict=True):
                if path is None:
                    raise KeyError(name)
                if args.seed == s.seed:
                    scores = benchmark_scores(folder, name)
                else:
                    scores = benchmark_scores(folder / SEEDS_FOLDER, f"{name}:{path}")
                by_policy.setdefault(name, []).append((int(args.seed), scores))
        except (KeyError, FileNotFoundError, ValueError):
            continue  # a part not (fully) run for every seed yet
        for name, runs in by_policy.items():
            seeds, scored = zip(*runs, strict=True)  # (seed, scores) of each run
            groups.append(
                SeedGroup(experiment, name, map_name, None, seeds, scored, PAPER_SUCCESS[name][index])
            )
    lfd: dict[tuple[str, int], list[tuple[int, dict[int, float]]]] = {}
    items = lfd_items(ctx)
    try:
        for (name, args), path in zip(items, _kept_files(items), strict=True):
            if path is None:
                raise KeyError(name)
            scores = benchmark_scores(lfd_eval_dir(ctx, int(args.seed)), f"{name}:{path}")
            lfd.setdefault((name, int(args.steps)), []).append((int(args.seed), scores))
    except (KeyError, FileNotFoundError, ValueError):
        lfd = {}
    for (name, size), runs in lfd.items():
        paper = paper_lfd(name, size)
        seeds, scored = zip(*runs, strict=True)
        groups.append(SeedGroup("lfd", name, "gdc1", size, seeds, scored, paper[0] if paper else None))
    return groups


def selection_rows(ctx: Context) -> list[dict[str, Any]]:
    """Every finished RL run that evaluated its checkpoints on validation scenarios: the kept
    checkpoint, its validation success, the last checkpoint's, and both on the curve scenarios."""
    from socialzoo.train.run_dir import RUN_FILE, read_record

    curves = _curve_success(ctx.ledger.path("rl", "curves", "rl_curves.csv"))
    rows = []
    for name, args in rl_items(ctx):
        record = read_record(Path(args.out) / RUN_FILE)
        results = (record or {}).get("results") or {}
        best = results.get("best_checkpoint")
        if not record or not record.get("finished") or not isinstance(best, dict):
            continue
        evaluations = _evaluations(Path(args.out) / "evaluations.csv")
        last = max(evaluations, key=lambda r: r["step"]) if evaluations else {}
        label = Path(args.out).name
        rows.append(
            {
                "policy": name,
                "run": label,
                "seed": int(args.seed),
                "validation_trials": int(args.eval_trials),
                "evaluated_checkpoints": len(evaluations),
                "kept_step": int(best["step"]),
                "kept_validation_success": float(best["success"]),
                "last_step": int(last.get("step", math.nan)) if last else "",
                "last_validation_success": float(last.get("success", math.nan)) if last else math.nan,
                "kept_curve_success": curves.get((label, int(best["step"])), math.nan),
                "last_curve_success": curves.get((label, int(last["step"])), math.nan) if last else math.nan,
            }
        )
    return rows


def _evaluations(path: Path) -> list[dict[str, float]]:
    from socialzoo.reproduce.results import read_csv

    rows = read_csv(path) if path.is_file() else []
    return [{"step": int(row["step"]), "success": row["success"]} for row in rows]


def _curve_success(path: Path) -> dict[tuple[str, int], float]:
    from socialzoo.reproduce.results import read_csv

    rows = read_csv(path) if path.is_file() else []
    return {(r["label"], int(r["step"])): r["success_rate"] for r in rows if math.isfinite(r["step"])}


def write_seed_results(ctx: Context) -> list[Path]:
    """selection.csv (runs that chose on validation), and with several seeds seeds.csv,
    improvement.csv and profiles.csv, into DIR/<hash>/seeds/; returns the files written.

    Written after every part, so a report between parts shows what has run:

        selection.csv     every PPO/DQN run: seed, kept checkpoint, its validation success, and its
                          success on the curve scenarios (the test-set curve, never used to choose)
        seeds.csv         with several seeds: per policy and map (and LfD size), mean and IQM with
                          95% stratified bootstrap intervals over seeds and scenarios, every seed's
                          success, where the paper's number falls among them
        improvement.csv   probability of improvement between pairs of policies (learned vs Ref, PPO vs
                          DQN, BC vs GAIL)
        profiles.csv      performance profiles (share of seeds above each success threshold)
    """
    from socialzoo.bench.tables import write_csv
    from socialzoo.studies.seeds import write_seed_study

    out = ctx.ledger.path(SEEDS_DIR)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    selection = selection_rows(ctx)
    if selection:
        files.append(write_csv(selection, out / SELECTION_CSV))
    else:
        (out / SELECTION_CSV).unlink(missing_ok=True)
    groups = _groups(ctx) if ctx.settings.seeds > 1 else []
    files += write_seed_study(groups, IMPROVEMENT_PAIRS, out)
    return files
