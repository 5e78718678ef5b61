"""The runner of each part of the reproduction (socialzoo.reproduce.plan.PARTS), each resumable (its pieces store
their items as they finish); a part returns how many items it made (0: everything was read back)."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any

from socialzoo.reproduce.backend import run_tasks
from socialzoo.reproduce.paper import EXPERIMENT_MAPS, PAPER_POLICIES
from socialzoo.reproduce.plan import REFERENCE_PART
from socialzoo.reproduce.runs import (
    REFERENCE_FILE,
    REFERENCE_FOLDER,
    SEEDS_FOLDER,
    Context,
    demos_path,
    finished,
    lfd_eval_dir,
    lfd_items,
    quirk_set,
    reference_folder,
    reference_rl_items,
    rl_items,
)
from socialzoo.reproduce.seeds import write_seed_results

logger = logging.getLogger(__name__)

# ---------------------------------------------------------------------------- trainings


def train_task(item: tuple[str, Any]) -> str:
    """Train one policy (name, trainer arguments) unless finished; returns its file. A task of
    socialzoo.reproduce.backend.run_tasks (a local process or a Ray task)."""
    name, args = item
    from socialzoo.train import trainer_function

    return str(trainer_function(name)(args))


def _train(ctx: Context, items: list[tuple[str, Any]]) -> tuple[list[Path], int]:
    """Train the items side by side (`workers` local processes or Ray tasks); returns (the policy
    each run keeps, how many were trained now). A run that evaluated its checkpoints on
    validation scenarios keeps its best one (socialzoo.train.validation.kept_policy)."""
    from socialzoo.train.validation import kept_policy

    pending = [(name, args) for name, args in items if not finished(name, args)]
    if pending:
        run_tasks(train_task, pending, backend=ctx.backend, workers=ctx.settings.workers)
    files = [train_task(item) for item in items]  # finished now: each returns its policy at once
    return [kept_policy(f) for f in files], len(pending)


# ---------------------------------------------------------------------------- parts


def run_demos(ctx: Context) -> int:
    """Record (or resume, or confirm) Ref's demonstrations; returns 1 if anything was recorded."""
    from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations

    s = ctx.settings
    path = demos_path(ctx)
    if path.is_file():
        return 0
    path.parent.mkdir(parents=True, exist_ok=True)
    config = DemoConfig(
        episodes=s.demo_episodes,
        chunk_episodes=min(25, s.demo_episodes),
        batch_size=s.batch_size if s.name == "quick" else 64,
        env_overrides=dict(s.demo_env_overrides),
    )
    record_demonstrations(path, config, progress=ctx.progress)
    return 1


def _store_size(path: Path) -> int:
    from socialzoo.bench.store import ResultsStore

    if not path.is_file():
        return 0
    with ResultsStore(path) as store:
        return len(store)


def run_rl_curves(ctx: Context) -> int:
    """Train PPO and DQN (every seed), evaluate every checkpoint; returns the trainings and trials
    made. Curve labels are the run folders' names ("ppo", "ppo-s1", ...): every seed is a curve."""
    from socialzoo.studies.rl_curves import STORE_NAME, rl_curves

    s = ctx.settings
    items = rl_items(ctx)
    _, trained = _train(ctx, items)
    out = ctx.ledger.path("rl", "curves")
    before = _store_size(out / STORE_NAME)
    rl_curves(
        {Path(args.out).name: Path(args.out) for _, args in items},
        out,
        trials=s.curve_trials,
        workers=s.workers,
        batch_size=s.batch_size,
        progress=ctx.progress,
        figure=False,
        env_overrides=dict(s.eval_env_overrides),
        backend=ctx.backend,
    )
    write_seed_results(ctx)
    return trained + _store_size(out / STORE_NAME) - before


def run_lfd(ctx: Context) -> int:
    """Demonstrations, BC and GAIL at every size, PIPS (every seed), then the LfD table of each
    seed (lfd/eval/lfd.csv is the first seed's); returns items made."""
    from socialzoo.studies.lfd import run_lfd_evaluation

    s = ctx.settings
    made = run_demos(ctx)
    items = lfd_items(ctx)
    files, trained = _train(ctx, items)
    for seed in s.seed_list:
        policies = {
            (name, int(args.steps)): path
            for (name, args), path in zip(items, files, strict=True)
            if args.seed == seed
        }
        result = run_lfd_evaluation(
            policies,
            lfd_eval_dir(ctx, seed),
            trials=s.lfd_trials,
            workers=s.workers,
            batch_size=s.batch_size,
            env_overrides=dict(s.eval_env_overrides),
            progress=ctx.progress,
            backend=ctx.backend,
        )
        made += result.computed
    write_seed_results(ctx)
    return made + trained


def final_policies(ctx: Context) -> tuple[dict[int, dict[str, Path]], int]:
    """The learned policies of the performance experiments (PPO, DQN, BC and GAIL on the largest
    demonstration set, PIPS) of every seed, training what is missing; each run's kept policy
    (its best validation checkpoint where it has one). Returns ({seed: {name: file}}, trainings
    made)."""
    s = ctx.settings
    made = run_demos(ctx)
    items = rl_items(ctx) + lfd_items(ctx, (s.lfd_largest,))
    files, trained = _train(ctx, items)
    out: dict[int, dict[str, Path]] = {seed: {} for seed in s.seed_list}
    for (name, args), path in zip(items, files, strict=True):
        out[int(args.seed)][name] = path
    return out, made + trained


def _evaluate(ctx: Context, experiment: str, first_seed: bool, folder: Path, **config: Any) -> Any:
    """run_benchmark of a BenchmarkConfig (`config`) on the map of `experiment` ("performance" or
    "transfer"), with the run's backend, workers, batch size and env overrides (unless `config`
    gives them), on its first settings.<experiment>_trials scenarios: for the first seed's
    policies all of them, for later seeds' at most settings.seed_trials."""
    from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark

    s = ctx.settings
    trials = getattr(s, f"{experiment}_trials")
    trials = trials if first_seed else min(trials, s.seed_trials or trials)
    common = {"backend": ctx.backend, "workers": s.workers, "batch_size": s.batch_size}
    fields = {**common, "env_overrides": dict(s.eval_env_overrides), **config}
    benchmark = BenchmarkConfig(maps=(EXPERIMENT_MAPS[experiment][0],), trials=trials, **fields)
    return run_benchmark(benchmark, folder, progress=ctx.progress, figures=False)


def _benchmark(ctx: Context, experiment: str) -> int:
    """The seven policies (the learned ones of the first seed) on the first `<experiment>_trials`
    scenarios of the experiment's map's test set into <experiment>/, and, with several seeds, the
    other seeds' learned policies on the first settings.seed_trials (or as many) into
    <experiment>/seeds/."""
    s = ctx.settings
    files, made = final_policies(ctx)
    kwargs = {name: {"path": str(path)} for name, path in files[s.seed].items()}
    folder = ctx.ledger.path(experiment)
    made += _evaluate(ctx, experiment, True, folder, policies=PAPER_POLICIES, policy_kwargs=kwargs).computed
    others = [f"{name}:{path}" for seed in s.seed_list[1:] for name, path in files[seed].items()]
    if others:
        made += _evaluate(ctx, experiment, False, folder / SEEDS_FOLDER, policies=tuple(others)).computed
    write_seed_results(ctx)
    return made


def run_performance(ctx: Context) -> int:
    """The seven policies on the first `performance_trials` gdc1-test scenarios (and the other
    seeds' learned policies)."""
    return _benchmark(ctx, "performance")


def run_transfer(ctx: Context) -> int:
    """The seven policies on the first `transfer_trials` ghc3-test scenarios (and the other seeds'
    learned policies)."""
    return _benchmark(ctx, "transfer")


def run_reference(ctx: Context) -> int:
    """`--reference`: for each quirk set of ctx.reference (socialzoo.env.quirks.ReferenceQuirks.named:
    every quirk together, or one alone), PPO and DQN of every seed trained with it
    (socialzoo.reproduce.runs.reference_rl_items) and evaluated on gdc1-test and ghc3-test with it on
    (PPO from its file without its normalisation when the set has that quirk); then
    reference/reference.csv, one row per quirk set, experiment, policy and seed, the rows of sets not
    run this time kept. BC, GAIL and PIPS are not retrained: their training reads Ref's actions,
    never the reward, and the quirks change no success. Returns the trainings and trials made."""
    from socialzoo.bench.tables import write_csv
    from socialzoo.reproduce.results import read_csv

    table = ctx.ledger.path(REFERENCE_FOLDER, REFERENCE_FILE)
    kept = [
        {**r, "quirks": quirk_set(r), "seed": int(r["seed"]), "trials": int(r["trials"])}
        for r in (read_csv(table) if table.is_file() else [])
        if quirk_set(r) not in ctx.reference
    ]
    made, rows = 0, []
    for quirks in ctx.reference:
        done, mine = _reference_set(ctx, quirks)
        made += done
        rows += mine
    write_csv([*kept, *rows], table, REFERENCE_COLUMNS)
    return made


# The columns of reference.csv.
REFERENCE_COLUMNS = (
    "quirks",
    "experiment",
    "policy",
    "seed",
    "trials",
    "success_rate",
    "success_ci_low",
    "success_ci_high",
    "average_step_reward_mean",
)


def _reference_set(ctx: Context, quirks: str) -> tuple[int, list[dict[str, Any]]]:
    """One quirk set of `run_reference`: its trainings, evaluations and rows."""
    from socialzoo.agents.mlp import evaluation_file
    from socialzoo.env.quirks import ReferenceQuirks
    from socialzoo.reproduce.results import read_csv

    s = ctx.settings
    chosen = ReferenceQuirks.named(quirks)
    items = reference_rl_items(ctx, quirks=quirks)
    if not items:
        logger.info("reproduce: reference quirk set %s reaches no trainer; nothing to run", quirks)
        return 0, []
    files, made = _train(ctx, items)
    specs: dict[int, dict[str, str]] = {seed: {} for seed in s.seed_list}
    for (name, args), path in zip(items, files, strict=True):
        folder = reference_folder(ctx, quirks, "evaluated", Path(args.out).name)
        specs[int(args.seed)][name] = f"{name}:{evaluation_file(name, path, chosen, folder)}"
    env = {**dict(s.eval_env_overrides), "quirks": dataclasses.asdict(chosen)}
    rows = []
    for experiment in EXPERIMENT_MAPS:
        for seed in s.seed_list:
            folder = reference_folder(ctx, quirks, experiment, *([] if seed == s.seed else [f"s{seed}"]))
            policies = tuple(specs[seed].values())
            made += _evaluate(
                ctx, experiment, seed == s.seed, folder, policies=policies, env_overrides=env
            ).computed
            by_spec = {str(r["policy"]): r for r in read_csv(folder / "summary.csv")}
            for name, spec in specs[seed].items():
                r = by_spec[spec]
                rows.append(
                    {
                        "quirks": quirks,
                        "experiment": experiment,
                        "policy": name,
                        "seed": seed,
                        "trials": int(r["trials"]),
                        **{column: r[column] for column in REFERENCE_COLUMNS[5:]},  # success, reward
                    }
                )
    return made, rows


PART_RUNNERS: dict[str, Callable[[Context], int]] = {
    "demos": run_demos,
    "rl-curves": run_rl_curves,
    "lfd": run_lfd,
    "performance": run_performance,
    "transfer": run_transfer,
    REFERENCE_PART: run_reference,
}
