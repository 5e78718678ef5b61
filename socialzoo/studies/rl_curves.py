"""Experiment 1, RL data efficiency (SPEC section 10): every checkpoint of PPO and DQN runs on the same scenarios,
with 90% confidence bands, as rl_curves.csv and rl_curves.{png,pdf} (the paper's learning-curve figure)."""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.bench.runner import Backend, RunSpec, Trial, TrialResult, env_config_for, evaluate
from socialzoo.bench.store import ResultsStore, trial_row
from socialzoo.bench.tables import policy_label, summarize, value_key, write_csv
from socialzoo.core.metrics import axis_label, metric, registered
from socialzoo.scenarios.scenario_sets import TestSet, get_test_set, validation_set

logger = logging.getLogger(__name__)

STORE_NAME = "curves.sqlite"
CSV_NAME = "rl_curves.csv"
FIGURE_STEM = "rl_curves"
CURVE_TEST_SET = "gdc1-test"
CURVE_TRIALS = 100
# Our own validation scenarios on gdc1 (base seed apart from every test set's): for choices.
VALIDATION_SET = validation_set("gdc1")
# The label of a run of another seed than the first: "<learner>-s<seed>" (socialzoo.reproduce).
_SEED_SUFFIX = re.compile(r"-s\d+$")
# Curves: (metric, axis label, scale), the labels from the metric registry; flags as percentages.
CURVE_PANELS: tuple[tuple[str, str, float], ...] = tuple(
    (name, axis_label(name), 100.0 if metric(name).kind == "bool" else 1.0)
    for name in registered("success", "time_to_goal", "average_step_reward")
)
CSV_COLUMNS = (
    "label",
    "step",
    "policy",
    "test_set",
    "trials",
    "success_rate",
    "success_ci_low",
    "success_ci_high",
    "time_to_goal_mean",
    "time_to_goal_ci_low",
    "time_to_goal_ci_high",
    "time_to_goal_n",
    "average_step_reward_mean",
    "average_step_reward_ci_low",
    "average_step_reward_ci_high",
)


def step_files(run_dir: str | Path, suffix: str, what: str) -> list[tuple[int, Path]]:
    """(step, file) of every run_dir/checkpoints/step_<N><suffix> (N digits only), by step: the
    checkpoints of a training run.

    Raises:
        FileNotFoundError: there is none (the error names the folder, `what` and the file pattern).
    """
    folder = Path(run_dir) / "checkpoints"
    name = re.compile(rf"step_(\d+){re.escape(suffix)}")
    found = sorted((int(m[1]), p) for p in folder.glob(f"step_*{suffix}") if (m := name.fullmatch(p.name)))
    if not found:
        raise FileNotFoundError(f"{folder}: no {what} (step_*{suffix})")
    return found


def run_checkpoints(run_dir: str | Path) -> list[tuple[int, Path]]:
    """(step, policy file) of every checkpoint a training run wrote, by step.

    Training runs are folders written by `socialzoo train ppo|dqn` (checkpoints/step_*.safetensors).

    Raises:
        FileNotFoundError: the folder has no checkpoints.
    """
    return step_files(run_dir, ".safetensors", "checkpoints of a training run")


def _policy_key(path: Path) -> str:
    """The registry name a policy file was saved under (its header's "policy")."""
    from socialzoo.env.policy_file import read_policy_file

    return str(read_policy_file(path)[1]["policy"])


def checkpoint_specs(runs: Mapping[str, str | Path]) -> dict[str, tuple[str, int]]:
    """Label "<run label>@<step>" -> (policy spec "ppo:PATH", step) for every checkpoint of the runs."""
    specs = {}
    for label, folder in runs.items():
        for step, path in run_checkpoints(folder):
            specs[f"{label}@{step}"] = (f"{_policy_key(path)}:{path.resolve()}", step)
    return specs


def evaluate_policies(
    policies: Mapping[str, str],
    test_set: TestSet,
    trials: int,
    store: ResultsStore,
    *,
    workers: int = 2,
    batch_size: int = 100,
    progress: bool = True,
    env_overrides: Mapping[str, Any] | None = None,
    backend: Backend = "local",
) -> list[dict[str, Any]]:
    """Run (or read back) `trials` scenarios of a test set for each policy, storing trials as they
    finish under the policy's label; returns every stored trial row of these labels.

    Args:
        policies: label -> policy spec ("ref", "ppo:PATH").
        test_set: the scenarios (its first `trials`).
        trials: scenarios per policy.
        store: the results store.
        workers: local processes.
        batch_size: env rows per worker.
        progress: show a progress bar.
        env_overrides: EnvConfig.replace keywords for the evaluation env (e.g. {"max_steps": 400}).
        backend: "local" (`workers` processes) or "ray" (Ray tasks; a running Ray is used).
    """
    from socialzoo.agents import make_policy, split_policy_spec
    from socialzoo.bench.experiment import config_hash

    if trials > len(test_set):
        raise ValueError(f"{trials} trials asked of test set {test_set.name!r}, which holds {len(test_set)}")
    name = test_set.name or test_set.map_name
    env_config = env_config_for(test_set, **dict(env_overrides or {}))
    hashes, pending, label_of = {}, [], {}
    for label, spec in policies.items():
        key, path = split_policy_spec(spec)
        h = config_hash(env_config, key, make_policy(spec), test_set, {"path": path} if path else None)
        store.register_config(
            h, {"label": label, "policy": spec, "env": env_config.to_dict(), "test_set": name}
        )
        hashes[label] = h
        label_of[spec] = label
        done = store.stored_indices(label, name, h)
        pending += [Trial(spec, name, k) for k in range(trials) if k not in done]
    logger.info(
        "%d policies x %d scenarios of %s: %d trials to run", len(policies), trials, name, len(pending)
    )

    def deliver(batch: list[TrialResult]) -> None:
        store.add(
            trial_row(r, hashes[label_of[r.trial.policy]], policy=label_of[r.trial.policy], test_set=name)
            for r in batch
        )

    run_spec = RunSpec(
        test_sets={name: test_set},
        env_configs={name: env_config},
        policies={s: {} for s in policies.values()},
        batch_size=batch_size,
    )
    evaluate(
        pending,
        run_spec,
        backend=backend,
        workers=workers,
        on_results=deliver,
        progress=progress,
        desc="checkpoints",
    )
    rows = []
    for label in policies:
        rows += store.rows(policy=label, test_set=name, config_hash=hashes[label], indices=range(trials))
    return rows


def curve_rows(rows: Sequence[Mapping[str, Any]], steps: Mapping[str, int]) -> list[dict[str, Any]]:
    """One CSV row per label of stored trials: success rate and means with 90% intervals."""
    out = []
    for entry in summarize(rows):
        label = entry["policy"]
        row = {
            "label": label.rsplit("@", 1)[0],
            "step": steps.get(label, ""),
            "policy": label,
            **{k: entry[k] for k in CSV_COLUMNS[3:] if k in entry},
        }
        out.append(row)
    return sorted(out, key=lambda r: (r["label"], r["step"] if r["step"] != "" else -1))


def write_curves_csv(rows: Sequence[Mapping[str, Any]], path: str | Path) -> Path:
    """Write curve rows (curve_rows) as CSV."""
    return write_csv(rows, path, CSV_COLUMNS, blank_nan=False)


def plot_curves(
    rows: Sequence[Mapping[str, Any]],
    out_dir: str | Path,
    references: Sequence[Mapping[str, Any]] = (),
    formats: Sequence[str] = ("png", "pdf"),
    stem: str = FIGURE_STEM,
) -> list[Path]:
    """<stem>.{png,pdf} (default rl_curves): success, time to goal and average step reward against
    training steps, one line per run with its 90% band; `references` (curve rows without steps,
    e.g. Ref) as horizontal lines."""
    from socialzoo.bench.figures import pyplot, save_figure, series_color

    plt = pyplot()
    fig, axes = plt.subplots(1, len(CURVE_PANELS), figsize=(4.2 * len(CURVE_PANELS), 3.4))
    labels = list(dict.fromkeys(r["label"] for r in rows))
    bases = list(dict.fromkeys(_SEED_SUFFIX.sub("", label) for label in labels))
    for ax, (key, ylabel, scale) in zip(axes, CURVE_PANELS, strict=True):
        mean_key, low_key, high_key = value_key(key), f"{key}_ci_low", f"{key}_ci_high"
        for label in labels:
            points = [r for r in rows if r["label"] == label]
            x = [r["step"] / 1000 for r in points]
            y = [scale * r[mean_key] for r in points]
            low = [scale * r[low_key] if math.isfinite(r[low_key]) else math.nan for r in points]
            high = [scale * r[high_key] if math.isfinite(r[high_key]) else math.nan for r in points]
            # Runs of one learner with several seeds ("ppo", "ppo-s1", ...) share its colour.
            base = _SEED_SUFFIX.sub("", label)
            color = series_color(bases.index(base))
            seeds = sum(_SEED_SUFFIX.sub("", other) == base for other in labels)
            first = label == next(o for o in labels if _SEED_SUFFIX.sub("", o) == base)
            name = policy_label(base) + (f" ({seeds} seeds)" if seeds > 1 else "")
            ax.plot(x, y, color=color, label=name if first else None, linewidth=1.5 if seeds == 1 else 1.0)
            ax.fill_between(x, low, high, color=color, alpha=0.25 / seeds, linewidth=0)
        for j, ref in enumerate(references):
            if math.isfinite(ref[mean_key]):
                ax.axhline(
                    scale * ref[mean_key],
                    color="0.3",
                    linestyle=("--", ":", "-.")[j % 3],
                    linewidth=1,
                    label=policy_label(ref["label"]),
                )
        ax.set_xlabel("training steps (thousands)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, out_dir, stem, formats)


def _checkpoint_rows(
    runs: Mapping[str, str | Path],
    references: Sequence[str],
    test_set: TestSet,
    trials: int,
    out: Path,
    **evaluation: Any,
) -> list[dict[str, Any]]:
    """The curve rows of every checkpoint of `runs` and of each reference policy (step ""), their
    trials stored in out/curves.sqlite (evaluate_policies' keywords in `evaluation`)."""
    out.mkdir(parents=True, exist_ok=True)
    specs = checkpoint_specs(runs)
    policies = {label: spec for label, (spec, _) in specs.items()} | {r: r for r in references}
    with ResultsStore(out / STORE_NAME) as store:
        trial_rows = evaluate_policies(policies, test_set, trials, store, **evaluation)
    return curve_rows(trial_rows, {label: step for label, (_, step) in specs.items()})


@dataclass(frozen=True)
class CurvesResult:
    """What `rl_curves` produced.

    Attributes:
        rows: one row per checkpoint (CSV_COLUMNS).
        references: one row per reference policy.
        files: the store, CSV and figures.
    """

    rows: list[dict[str, Any]]
    references: list[dict[str, Any]]
    files: list[Path]


def rl_curves(
    runs: Mapping[str, str | Path],
    out_dir: str | Path,
    *,
    test_set: str | TestSet = CURVE_TEST_SET,
    trials: int = CURVE_TRIALS,
    references: Sequence[str] = ("ref",),
    workers: int = 2,
    batch_size: int = 100,
    progress: bool = True,
    figure: bool = True,
    env_overrides: Mapping[str, Any] | None = None,
    backend: Backend = "local",
) -> CurvesResult:
    """Experiment 1: evaluate every checkpoint of each run on the same scenarios, write the curves.

    Success, time to goal and average step reward per checkpoint. The paper evaluates each checkpoint on the
    same 100 test scenarios: the first 100 of gdc1-test, for evaluation only (never to choose anything);
    choosing something, such as how long to train, uses VALIDATION_SET instead (`steps_to_match`). Trials are
    stored as they finish (curves.sqlite, one row per checkpoint and scenario, keyed by the checkpoint file's
    digest and the code), so an interrupted evaluation resumes and a repeated one reads.

    Args:
        runs: label ("ppo", "dqn") -> training run folder.
        out_dir: where curves.sqlite, rl_curves.csv and rl_curves.{png,pdf} go.
        test_set: the scenarios (default: the first 100 of gdc1-test, as the paper).
        trials: scenarios per checkpoint.
        references: policy specs drawn as horizontal lines (evaluated on the same scenarios).
        workers: local processes.
        batch_size: env rows per worker.
        progress: show a progress bar.
        figure: draw the figure (needs matplotlib).
        env_overrides: EnvConfig.replace keywords for the evaluation env (default: the benchmark's).
        backend: "local" or "ray" (see `evaluate_policies`).
    """
    ts = get_test_set(test_set) if isinstance(test_set, str) else test_set
    out = Path(out_dir)
    all_rows = _checkpoint_rows(
        runs, references, ts, trials, out,
        workers=workers, batch_size=batch_size, progress=progress, env_overrides=env_overrides, backend=backend,
    )  # fmt: skip
    rows = [r for r in all_rows if r["step"] != ""]
    refs = [r for r in all_rows if r["step"] == ""]
    files = [out / STORE_NAME, write_curves_csv(all_rows, out / CSV_NAME)]
    if figure:
        files += plot_curves(rows, out, refs)
    return CurvesResult(rows, refs, files)


def steps_to_match(
    run: str | Path,
    out_dir: str | Path,
    *,
    reference: str = "ref",
    validation: TestSet = VALIDATION_SET,
    trials: int = 200,
    label: str = "ppo",
    workers: int = 2,
    batch_size: int = 100,
    progress: bool = True,
    env_overrides: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Beyond the paper: the fewest training steps after which a run's checkpoint succeeds at least
    as often as `reference` does, both measured on the same validation scenarios (never a test set).
    Trials are stored in out_dir/curves.sqlite, the curve rows written to out_dir/steps_to_ref.csv.

    The validation scenarios are VALIDATION_SET: scenarios of our own seeds, apart from every test set.

    Returns:
        {"reference": its curve row, "checkpoints": curve rows by step, "steps": the first step
        whose success rate >= the reference's (None if none does), "steps_ci": the first step whose
        90% interval reaches the reference's rate (None if none)}.
    """
    if validation.name.endswith(("-test", "-quick")):
        raise ValueError(
            f"steps_to_match chooses a training length: use validation scenarios, not {validation.name!r}"
        )
    out = Path(out_dir)
    all_rows = _checkpoint_rows(
        {label: run}, [reference], validation, trials, out,
        workers=workers, batch_size=batch_size, progress=progress, env_overrides=env_overrides,
    )  # fmt: skip
    ref = next(r for r in all_rows if r["step"] == "")
    points = [r for r in all_rows if r["step"] != ""]
    write_curves_csv(all_rows, out / "steps_to_ref.csv")
    first = next((r["step"] for r in points if r["success_rate"] >= ref["success_rate"]), None)
    first_ci = next((r["step"] for r in points if r["success_ci_high"] >= ref["success_rate"]), None)
    return {"reference": ref, "checkpoints": points, "steps": first, "steps_ci": first_ci}
