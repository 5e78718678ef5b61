"""The benchmark of any registered task id on its fixed cases: episodes in the results store, a
summary with intervals, its tables (the benchmark's one writer) and the success figure."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.core.metrics import METRICS

STORE_FILE = "results.sqlite"
logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class TaskId:
    """A registered id's task and config.

    Attributes:
        env_id: the Gymnasium id.
        task: the task's registry name or "module:Class" path.
        kwargs: the id's config fields (plain values).
        module: the module named before the id ("module:ns/Name-vN"), imported to register it; "" if none.
    """

    env_id: str
    task: str
    kwargs: dict[str, Any]
    module: str = ""

    @property
    def name(self) -> str:
        """The id as the command line takes it again: "module:ns/Name-vN" when a module registered it."""
        return f"{self.module}:{self.env_id}" if self.module else self.env_id

    @classmethod
    def of(cls, env_id: str) -> TaskId:
        """The task of a registered id; "module:ns/Name-vN" imports the module first (Gymnasium's
        form for an id its own code registers, so the command line reaches a task of one's own).

        Raises:
            ValueError: an id that is not registered, or not a task's; a module that cannot be imported.
        """
        import importlib

        import gymnasium as gym

        import socialzoo  # noqa: F401  (registers the ids)

        module, sep, env_id = env_id.rpartition(":")
        if sep:
            try:
                importlib.import_module(module)
            except ImportError as err:
                raise ValueError(f"env id {module}:{env_id}: cannot import {module!r} ({err})") from None

        if env_id not in gym.registry:
            known = sorted(i for i in gym.registry if i.startswith("socialzoo"))
            raise ValueError(f"unknown env id {env_id!r}; registered: {', '.join(known)}")
        kwargs = dict(gym.spec(env_id).kwargs)
        task = kwargs.pop("task", None)
        if not isinstance(task, str):
            raise ValueError(f"{env_id} is not a task's id (its kwargs name no task)")
        return cls(env_id, task, kwargs, module)

    def given_fields(self, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The config fields this task (and `overrides`) sets otherwise than its registered id: what
        `--task-config` must give to play the same episodes from the id (a replay hint)."""
        import gymnasium as gym

        registered = gym.spec(self.env_id).kwargs
        fields = {**self.kwargs, **(overrides or {})}
        return {k: v for k, v in fields.items() if k not in registered or registered[k] != v}

    def make(self, batch_size: int = 1, /, **overrides: Any) -> Any:
        """The task of B = batch_size rows, with config overrides."""
        from socialzoo.env.tasks import make_task

        return make_task(self.task, batch_size, None, **{**self.kwargs, **overrides})


def config_hash(config: Any, split: str, spec: str, policy: Any) -> str:
    """16 hex digits naming everything that decides an episode of `policy` besides its case.

    Covered: the task's config, the split, the simulation's source code and the policy's module, the
    policy's parameters and its file's digest. A retrained file under the same path therefore gets
    new episodes, never the old file's.
    """
    from socialzoo.agents import policy_file
    from socialzoo.agents.base import policy_config
    from socialzoo.bench.experiment import file_digest, payload_hash

    path = policy_file(spec)
    payload = {
        "task": config.to_dict(),
        "split": split,
        "policy": {
            "spec": spec,
            "config": policy_config(policy),
            "file_sha256": file_digest(path) if path is not None else None,
        },
    }
    return payload_hash(payload, policy)


def evaluate_stored(
    store_path: Path,
    task: TaskId,
    spec: str,
    policy: Any,
    split: str = "test",
    cases: int | None = None,
    batch_size: int = 100,
    overrides: Mapping[str, Any] | None = None,
) -> tuple[list[dict[str, Any]], int]:
    """The episodes of `policy` (named `spec`) on the first `cases` cases of a split, playing only
    those the store at store_path lacks and storing each as it ends. `overrides`: the task's config
    fields, a mapping (not keywords: CrowdNav's config has a field `cases` of its own).

    Cases are played by socialzoo.bench.episodes.play_cases, so an interrupted run resumes where it
    stopped and a repeated one reads instead of playing. An episode is keyed like a benchmark trial:
    (policy spec, the task's split, case index, config hash: `config_hash`).

    Returns:
        (every case's episode, stored and new, in case order; how many were played now).

    Raises:
        socialzoo.bench.store.StoreError: store_path is not a usable results store.
        ValueError: a split the task lacks, or more cases than it holds.
    """
    from socialzoo.bench.episodes import play_cases
    from socialzoo.bench.store import TRIAL_COLUMNS, ResultsStore

    overrides = dict(overrides or {})
    probe = task.make(1, **overrides)
    splits = probe.case_splits()
    if split not in splits:
        raise ValueError(f"{task.env_id}: split must be one of {sorted(splits)}, got {split!r}")
    if splits[split] == 0:
        family = getattr(probe.config, "family", None)
        raise ValueError(
            f"{task.env_id}: the {split} split"
            + (f" of family {family}" if family else "")
            + " holds no cases"
        )
    total = splits[split] if cases is None else cases
    if not 1 <= total <= splits[split]:
        raise ValueError(
            f"{task.env_id}: {total} cases asked of the {split} split, which holds {splits[split]}"
        )
    config = probe.config
    digest = config_hash(config, split, spec, policy)
    test_set = f"{probe.name}-{split}"
    where = str(getattr(config, "map", None) or probe.name)
    with ResultsStore(store_path) as store:
        store.register_config(
            digest,
            {
                "task": config.to_dict(),
                "split": split,
                "policy": spec,
                "env_id": task.name,
                "task_config": task.given_fields(overrides),
            },
        )
        have = store.stored_indices(spec, test_set, digest)
        todo = [k for k in range(total) if k not in have]

        def store_episodes(episodes: list[dict[str, Any]]) -> None:
            store.add(
                {
                    "policy": spec,
                    "map": where,
                    "test_set": test_set,
                    "scenario_index": e["case"],
                    "seed": e["seed"],
                    "config_hash": digest,
                    "metrics": {k: float(v) for k, v in e.items() if k not in ("case", "seed")},
                }
                for e in episodes
            )

        if todo:
            play_cases(
                task.task,
                policy.act,
                split,
                todo,
                batch_size,
                config=config,
                on_episodes=store_episodes,
                guideline_metrics=True,
            )
        rows = store.rows(policy=spec, test_set=test_set, config_hash=digest, indices=range(total))
    # The store has a column for every metric of any episode it holds: another task's bool and int
    # metrics read back as None in this task's rows (its floats as NaN, as a NaN of this task's).
    episodes = [
        {
            "case": int(r["scenario_index"]),
            **{k: float(v) for k, v in r.items() if k not in TRIAL_COLUMNS and v is not None},
        }
        for r in rows
    ]
    return episodes, len(todo)


def summarize(
    episodes: Sequence[dict[str, Any]], confidence: float = 0.95, cell: Sequence[str] = ()
) -> dict[str, Any]:
    """Every registered metric of the episodes: a flag's rate ("<name>_rate") with a Wilson
    interval ("<name>_ci"), a count's mean (the registry's counts, e.g. gl_collisions) with a
    bootstrap (BCa) interval as the maps' tables give it (socialzoo.bench.tables.summarize: never
    below 0, [0, -ln((1 - confidence) / 2) / n] with no count at all), any other number's mean
    ("<name>") with a Student-t interval, NaN values left out; "episodes" counts them. With
    CrowdNav's discomfort steps, "discomfort_frequency" is pooled over every step of every episode
    (its "frequency of being in danger"). The metrics are those of the registry
    (socialzoo.core.metrics); a NaN value is e.g. the time of a failed episode. An infinite value is
    a value: the time to collision (gl_min_time_to_collision) of an episode never on a collision
    course makes its mean infinite (no interval), rather than being left out.

    Args:
        episodes: the episodes' metrics.
        confidence: the two-sided level of every interval.
        cell: the names of the table cell (policy, scenario): with the metric's name they seed the
            bootstrap's resamples (socialzoo.bench.aggregates.cell_generator), so an interval is
            reproducible and does not move when other cells are added.
    """
    from socialzoo.bench.aggregates import cell_generator
    from socialzoo.bench.stats import count_interval, mean_interval, rate_interval
    from socialzoo.bench.tables import BOOTSTRAP_SEED

    n = len(episodes)
    out: dict[str, Any] = {"episodes": n}
    keys = [k for k in METRICS if episodes and all(k in e for e in episodes)]
    for key in keys:
        if METRICS[key].kind == "bool":
            rate = rate_interval(int(sum(bool(e[key]) for e in episodes)), n, confidence)
            out[f"{key}_rate"], out[f"{key}_ci"] = rate.value, [rate.low, rate.high]
        else:
            values = [float(e[key]) for e in episodes]
            if METRICS[key].count:
                rng = cell_generator(BOOTSTRAP_SEED, *cell, key)
                mean = count_interval(values, confidence, rng=rng)
            else:
                mean = mean_interval(values, confidence, infinite=True)
            out[key], out[f"{key}_ci"] = mean.value, [mean.low, mean.high]
    if "discomfort_steps" in keys and "steps" in keys:
        steps = sum(e["steps"] for e in episodes)
        out["discomfort_frequency"] = (
            sum(e["discomfort_steps"] for e in episodes) / steps if steps else math.nan
        )
        out.pop("discomfort_frequency_ci", None)
    return out


def table_entry(policy: str, map_name: str, test_set: str, summary: dict[str, Any]) -> dict[str, Any]:
    """A policy's `summarize` as an entry of the benchmark tables (socialzoo.bench.tables): its
    names, "trials", and each metric's value ("success_rate", "<name>_mean") and interval
    ("<name>_ci_low", "<name>_ci_high"; NaN where it has none)."""
    from socialzoo.bench.tables import value_key

    entry: dict[str, Any] = {
        "policy": policy,
        "map": map_name,
        "test_set": test_set,
        "trials": summary["episodes"],
    }
    for name in METRICS:
        if name in summary or f"{name}_rate" in summary:
            entry[value_key(name)] = summary.get(f"{name}_rate", summary.get(name))
            entry[f"{name}_ci_low"], entry[f"{name}_ci_high"] = summary.get(
                f"{name}_ci", (math.nan, math.nan)
            )
    return entry


def task_policies(
    task: TaskId, policies: Sequence[str], config: Mapping[str, Any] | None = None
) -> tuple[Any, list[tuple[str, Any]]]:
    """(a one-row task of the id with `config`, each spec with its policy for that task): every
    policy is built, and refused, before any of them plays (socialzoo.agents.make_policy).

    Raises:
        ValueError, PolicyTaskError: an unknown policy, or one of another task or observation size.
    """
    from socialzoo.agents import make_policy

    probe = task.make(1, **dict(config or {}))
    return probe, [(spec, make_policy(spec, task=probe)) for spec in policies]


def acting_overrides(policy: Any, overrides: dict[str, Any]) -> dict[str, Any]:
    """The config fields of the task a policy acts in: `overrides` and those the policy needs
    (its task_overrides, such as a CrowdNav learner's robot kinematics)."""
    return {**overrides, **(getattr(policy, "task_overrides", {}) or {})}


def run_task_benchmark(
    env_id: str,
    policies: Sequence[str],
    out: str | Path,
    *,
    split: str = "test",
    cases: int | None = None,
    batch_size: int = 100,
    figures: bool = True,
    say: Callable[[str], None] | None = None,
    config: Mapping[str, Any] | None = None,
) -> tuple[list[dict[str, Any]], list[Path]]:
    """Every policy on the first `cases` cases of a split of a registered task id, into out/: the
    store (results.sqlite), NAME.csv and NAME.md (NAME: the task's name; the benchmark's one table
    writer, socialzoo.bench.tables.write_tables, in a task's layout), success.png/pdf.

    A policy acts in the task the id names (socialzoo.agents.make_policy refuses another task's,
    or a learned one of another observation size); a learned policy that declares task overrides
    (CrowdNav's learned policy: its discrete or continuous actions) acts with them. Every policy
    is built first: one that the task refuses stops the run before any plays. `say` gets one line
    per policy (success, episodes played and read from the store), as the CLI prints; without
    `say` the line is logged.
    `config` overrides the id's task config for every policy (e.g. CrowdNav's observed_people);
    the store keeps episodes of each config apart (its digest).

    Returns:
        (one table entry per policy, `table_entry`; the files written).

    Raises:
        ValueError, PolicyTaskError, StoreError: an unknown id, policy, split or count; a policy
            of another task; an unusable store.
    """
    from socialzoo.bench.tables import remove_outputs, task_layout, write_tables

    task = TaskId.of(env_id)
    config = dict(config or {})
    probe, built = task_policies(task, policies, config)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for spec, policy in built:
        overrides = acting_overrides(policy, config)
        episodes, played = evaluate_stored(
            out / STORE_FILE, task, spec, policy, split, cases, batch_size, overrides
        )
        summary = summarize(episodes, cell=(spec, env_id))
        rows.append(table_entry(spec, env_id.split("/")[-1], f"{probe.name}-{split}", summary))
        read = summary["episodes"] - played
        line = (
            f"{spec}: success {summary.get('success_rate', math.nan):.3f} "
            f"({played} episodes played, {read} read from the store)"  # as the maps' and the suite's runs say
        )
        (say or logger.info)(line)  # the CLI prints it; a library caller gets it logged (not both)
    title = f"{env_id}{''.join(f', {k}={v}' for k, v in config.items())}, {split} cases ({probe.name} task)"
    files = write_tables(rows, out, name=probe.name, title=title, layout=task_layout(rows))
    from socialzoo.bench.figures import FIGURE_FORMATS, plot_success

    if figures and all("success_rate" in r for r in rows):
        files += plot_success(rows, out, interval="95% CI")
    else:  # an older run's figure would not match these tables
        remove_outputs(out, ["success"], FIGURE_FORMATS)
    return rows, files
