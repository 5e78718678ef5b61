"""The scenario suite's evaluation (socialzoo.scenarios.suite: Fig. 7 of Francis et al. 2025): policies x scenarios
x seeds into one results store, a policy x scenario table and heatmap per metric, replays."""

from __future__ import annotations

import json
import logging
import re
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal, get_args

from socialzoo.bench.runner import BACKENDS, Backend
from socialzoo.bench.task_benchmark import STORE_FILE, TaskId
from socialzoo.core.files import json_text
from socialzoo.core.validation import check_int
from socialzoo.scenarios.suite import SUITE, SUITE_NAMES

logger = logging.getLogger(__name__)

SuiteTask = Literal["action_selection", "crowdnav"]
TASKS: tuple[str, ...] = get_args(SuiteTask)
# The policies each task's suite runs when none are named (engineered: no file needed).
DEFAULT_POLICIES: dict[str, tuple[str, ...]] = {
    "action_selection": ("goalone", "ref"),
    "crowdnav": ("orca", "social_force"),
}
DEFAULT_SEEDS = 30
# The action-selection task's time limit in the suite, steps (60 s, as the family ids have).
SUITE_MAX_STEPS = 2400
# Two-sided level of every interval of the tables and the page (as a task id's benchmark).
CONFIDENCE = 0.95
REPLAYS_DIR = "replays"
# The name of a replay page write_replays writes (POLICY-caseK-HASH.html): the only files of
# REPLAYS_DIR a rerun removes.
REPLAY_PAGE = re.compile(r".+-case\d+-[0-9a-f]{8}\.html")
# Replay pages: REPLAY_LASER_RAYS laser rays drawn (and a state every 50 ms of the task's steps:
# socialzoo.render.replay_data.default_stride).
REPLAY_LASER_RAYS = 60


class SuiteError(ValueError):
    """A suite run that cannot start: an unknown scenario, a family not registered, a task that
    cannot play families, too many seeds; raised before anything is written."""


@dataclass(frozen=True)
class SuiteScenario:
    """A scenario of a suite run: a suite entry, or any registered family named on its own.

    Attributes:
        name: the family's registry name (socialzoo.scenarios.catalogue.FAMILIES).
        letter: its letter in Fig. 7 ("" for a family outside the suite).
        title: its title (the suite's, else the family's name).
        map_name: the map the family is designed for.
        description: the family's one line.
    """

    name: str
    letter: str
    title: str
    map_name: str
    description: str

    @property
    def label(self) -> str:
        """The label of tables and figures: "a. Frontal approach", or the family's name outside the suite."""
        return f"{self.letter}. {self.title}" if self.letter else self.title


@dataclass(frozen=True, kw_only=True)
class SuiteConfig:
    """What a suite run evaluates, and how.

    Attributes:
        policies: policy specs (socialzoo.agents: registry names, "NAME:PATH"); empty: the
            task's DEFAULT_POLICIES.
        scenarios: suite scenarios by family name or Fig. 7 letter, or any registered family's
            name (default the 25 of the suite).
        task: the task that plays them: "action_selection" (sub-policy actions) or "crowdnav"
            (velocity control).
        seeds: cases per scenario and policy: cases 0..seeds-1 of the split.
        backend: "local" (processes on this machine) or "ray".
        address: Ray cluster address (Ray backend); None starts a local Ray.
        workers: local processes, or Ray chunks (None: one per cluster CPU).
        batch_size: env rows stepped together per worker.
        replays: replay pages per scenario and policy: its first failed episodes, then its first
            successful ones, `replays` in all (0: none).
        metrics: the tables' and heatmaps' metrics (registered names); empty: those of
            HEADLINE_METRICS the episodes hold.
    """

    policies: tuple[str, ...] = ()
    scenarios: tuple[str, ...] = SUITE_NAMES
    task: SuiteTask = "action_selection"
    seeds: int = DEFAULT_SEEDS
    backend: Backend = "local"
    address: str | None = None
    workers: int | None = 2
    batch_size: int = 64
    replays: int = 1
    metrics: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        from socialzoo.agents import check_policy_spec
        from socialzoo.core.metrics import UnknownMetricError, metric

        for name in ("policies", "scenarios", "metrics"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
            values = getattr(self, name)
            if len(set(values)) != len(values):
                raise SuiteError(f"SuiteConfig.{name} has duplicates: {list(values)!r}")
        if self.task not in TASKS:
            raise SuiteError(f"SuiteConfig.task must be one of {TASKS}, got {self.task!r}")
        if not self.scenarios:
            raise SuiteError("SuiteConfig.scenarios is empty")
        for spec in self.policies:
            try:
                check_policy_spec(spec)
            except ValueError as err:
                raise SuiteError(f"SuiteConfig.policies: {err}") from None
        for name in self.metrics:
            try:
                metric(name)
            except UnknownMetricError as err:
                raise SuiteError(f"SuiteConfig.metrics: {err}") from None
        for name, low in (("seeds", 1), ("batch_size", 1), ("replays", 0)):
            check_int("SuiteConfig", name, getattr(self, name), low=low, error=SuiteError)
        check_int("SuiteConfig", "workers", self.workers, low=1, allow_none=True, error=SuiteError)
        if self.backend not in BACKENDS:
            raise SuiteError(f"SuiteConfig.backend must be one of {BACKENDS}, got {self.backend!r}")
        if self.address is not None and self.backend != "ray":
            raise SuiteError(f"SuiteConfig.address is for the Ray backend, got backend {self.backend!r}")

    @property
    def policy_specs(self) -> tuple[str, ...]:
        """The policies run: those named, else the task's defaults."""
        return self.policies or DEFAULT_POLICIES[self.task]

    def to_json(self) -> dict[str, Any]:
        """The config as plain JSON values (the policies run, not only those named)."""
        return asdict(self) | {
            "policies": list(self.policy_specs),
            "scenarios": list(self.scenarios),
            "metrics": list(self.metrics),
        }


def resolve_scenarios(names: Sequence[str]) -> list[SuiteScenario]:
    """The scenarios a run names, in order (a name given twice, once): Fig. 7 letters, suite
    family names, or other registered families' names (case-insensitive; MODULE:NAME imports
    MODULE first, for a family it registers).

    Raises:
        SuiteError: names that are none of these (every one listed, with the suite's letters and
            names and the registered families), or suite scenarios whose family is not registered
            yet (listed, with the registered families).
    """
    from socialzoo.scenarios.catalogue import FAMILIES, family_name, get_family

    by_key = {e.letter: e for e in SUITE} | {e.family: e for e in SUITE}
    chosen: dict[str, SuiteScenario] = {}
    unknown, unregistered = [], []
    for raw in names:
        try:
            key = family_name(raw.strip()).lower()
        except ValueError as err:
            raise SuiteError(str(err)) from None
        entry = by_key.get(key)
        name = entry.family if entry is not None else key
        if entry is None and key not in FAMILIES:
            unknown.append(raw)
            continue
        if name not in FAMILIES:
            unregistered.append(f"{entry.letter}. {name}" if entry is not None else name)
            continue
        family = get_family(name)
        chosen.setdefault(
            name,
            SuiteScenario(
                name=name,
                letter=entry.letter if entry is not None else "",
                title=entry.title if entry is not None else name,
                map_name=family.map_name,
                description=family.description,
            ),
        )
    registered = ", ".join(sorted(FAMILIES))
    if unknown:
        suite = ", ".join(f"{e.letter} {e.family}" for e in SUITE)
        raise SuiteError(
            f"unknown scenario(s) {', '.join(map(repr, unknown))}: a scenario is a Fig. 7 letter or a suite "
            f"name ({suite}), or a registered scenario family ({registered})"
        )
    if unregistered:
        raise SuiteError(
            f"suite scenario(s) {', '.join(unregistered)} not registered as scenario families yet "
            f"(socialzoo.scenarios.catalogue.FAMILIES); registered: {registered}"
        )
    return list(chosen.values())


def suite_env_id(task: str) -> str:
    """The suite's env id of a task: socialzoo/Suite-vN (action selection), socialzoo/CrowdNavSuite-vN.

    Raises:
        SuiteError: an unknown task.
    """
    from socialzoo.env.registration import CROWD_SUITE_ID, SUITE_ID

    if task == "action_selection":
        return SUITE_ID
    if task == "crowdnav":
        return CROWD_SUITE_ID
    raise SuiteError(f"unknown suite task {task!r}; known: {', '.join(TASKS)}")


def suite_task(task: str, scenario: SuiteScenario) -> TaskId:
    """The task that plays a scenario's family: the suite's registered id of the task
    (`suite_env_id`) with the family in its kwargs; where that id is not registered, the
    action-selection task on the family's map with the suite's time limit, or the CrowdNav task
    of the family.

    Raises:
        SuiteError: an unknown task.
    """
    env_id = suite_env_id(task)
    try:
        registered = TaskId.of(env_id)
    except ValueError:  # not registered (yet): the task built directly
        kwargs: dict[str, Any] = {"family": scenario.name}
        if task == "action_selection":
            kwargs = {"map": scenario.map_name, **kwargs, "max_steps": SUITE_MAX_STEPS}
        return TaskId(env_id, task, kwargs)
    return TaskId(env_id, registered.task, {**registered.kwargs, "family": scenario.name})


@dataclass(frozen=True)
class SuiteUnit:
    """One policy on one scenario: what the store keys its episodes by, and how to play them.

    Attributes:
        scenario: the scenario.
        spec: the policy spec.
        policy: the policy object (built in this process; the backend's workers build their own).
        task: the task id that plays the scenario.
        overrides: the task config the policy acts in (a learned policy's task_overrides).
        config: the task's resolved config.
        split: the case split played ("test", else the task's first split).
        split_size: how many cases the split holds.
        cases: how many are played (cases 0..cases-1).
        digest: the episodes' config hash (socialzoo.bench.task_benchmark.config_hash).
        test_set: the store's test set name ("<task>-<split>").
        where: the store's map column (the task's map, else its name).
        runner_set: the runner's test set of the unit's scenario and config.
    """

    scenario: SuiteScenario
    spec: str
    policy: Any
    task: TaskId
    overrides: Mapping[str, Any]
    config: Any
    split: str
    split_size: int
    cases: int
    digest: str
    test_set: str
    where: str
    runner_set: str


def plan_suite(config: SuiteConfig) -> tuple[list[SuiteUnit], list[str]]:
    """Every (scenario, policy) unit of a run, checked before anything runs: the scenarios
    resolved and registered, the task built for each family, the policies built for the task,
    enough cases in the split.

    Returns:
        (the units, scenario-major; notes for the output, e.g. a family played on its val split).

    Raises:
        SuiteError: see `resolve_scenarios`; a metric the task does not compute; a task whose
            config refuses the family; a policy that does not act in the task; more seeds than the
            split holds.
    """
    from socialzoo.bench.task_benchmark import acting_overrides, config_hash
    from socialzoo.core.metrics import metric
    from socialzoo.env.people import COST_KEYS

    # Every suite episode holds its task's metrics and Table I's (play_cases(guideline_metrics=True)); the
    # action-selection task's also what the robot costs the people (people_time_lost, ...; the scenario
    # cards recommend them) when those are asked for: each scenario is then played beside a twin
    # without the robot (PeopleConfig.counterfactual), which doubles the rows stepped.
    computed = {config.task, "guidelines"}
    twins = config.task == "action_selection" and any(name in COST_KEYS for name in config.metrics)
    others = [
        name
        for name in config.metrics
        if not computed & set(metric(name).sources) and not (twins and name in COST_KEYS)
    ]
    if others:
        raise SuiteError(f"the {config.task} task's episodes hold no metric {', '.join(others)}")
    counterfactual = {"people": {"counterfactual": True}} if twins else {}
    scenarios = resolve_scenarios(config.scenarios)
    units: list[SuiteUnit] = []
    notes: list[str] = []
    policies: dict[str, Any] = {}
    blind: dict[str, bool] = {}
    for scenario in scenarios:
        task = suite_task(config.task, scenario)
        probe = _probe(task, scenario, {})
        splits = probe.case_splits()
        split = "test" if "test" in splits else next(iter(splits))
        if split != "test":
            notes.append(
                f"{scenario.name}: the {config.task} task has no test split for it yet; "
                f"played on its {split} cases 0-{config.seeds - 1}"
            )
        if config.seeds > splits[split]:
            raise SuiteError(
                f"{scenario.name}: {config.seeds} seeds asked of the {split} split, which holds {splits[split]}"
            )
        for spec in config.policy_specs:
            if spec not in policies:
                policies[spec], blind[spec] = _suite_policy(spec, config.task, task, scenario, probe)
                if blind[spec]:
                    notes.append(
                        f"{spec}: its observations have no signal block (it was trained without the "
                        "suite's signals), so it plays with signals off: it does not see gestures or doors"
                    )
            policy = policies[spec]
            overrides = acting_overrides(policy, {"signals": False} if blind[spec] else {}) | counterfactual
            acting = _probe(task, scenario, overrides) if overrides else probe
            runner_set = scenario.name + (f" {json.dumps(overrides, sort_keys=True)}" if overrides else "")
            units.append(
                SuiteUnit(
                    scenario=scenario,
                    spec=spec,
                    policy=policy,
                    task=task,
                    overrides=overrides,
                    config=acting.config,
                    split=split,
                    split_size=splits[split],
                    cases=config.seeds,
                    digest=config_hash(acting.config, split, spec, policy),
                    test_set=f"{acting.name}-{split}",
                    where=str(getattr(acting.config, "map", None) or acting.name),
                    runner_set=runner_set,
                )
            )
    return units, notes


def _suite_policy(
    spec: str, task_name: str, task: TaskId, scenario: SuiteScenario, probe: Any
) -> tuple[Any, bool]:
    """(the policy of `spec` for the task, whether it plays with signals off): a learned policy whose
    observations lack the suite ids' signal block (trained on a task without it) acts in the task
    with signals off, where its observations are the ones it learned on.

    Raises:
        SuiteError: the policy acts in neither (named by make_policy's message).
    """
    from socialzoo.agents import make_policy

    try:
        return make_policy(spec, task=probe), False
    except ValueError as err:  # PolicyTaskError included
        if not getattr(probe.config, "signals", False):
            raise SuiteError(f"--task {task_name}: {err}") from None
        plain = _probe(task, scenario, {"signals": False})
        try:
            return make_policy(spec, task=plain), True
        except ValueError:
            raise SuiteError(f"--task {task_name}: {err}") from None


def _probe(task: TaskId, scenario: SuiteScenario, overrides: Mapping[str, Any]) -> Any:
    """A task of one row for the scenario.

    Raises:
        SuiteError: the task's config refuses the family, or another config error (named).
    """
    try:
        return task.make(1, **overrides)
    except (ValueError, KeyError) as err:
        if "family" in str(err) and ("unexpected keyword" in str(err) or "known fields" in str(err)):
            raise SuiteError(
                f"--task {task.task}: the {task.task} task's config has no `family` field yet, so it cannot "
                f"play the suite's scenario families (run --task action_selection until it lands): {err}"
            ) from None
        raise SuiteError(f"{scenario.name}: the {task.task} task cannot be built ({err})") from None


@dataclass(frozen=True)
class Replay:
    """A replay page of one stored episode.

    Attributes:
        scenario: the scenario's family name.
        policy: the policy spec.
        case: the case index.
        seed: the case's scenario seed.
        success: whether the stored episode succeeded.
        path: the page, relative to the run's folder.
        reproduced: the recorded episode ended as the stored one (success and steps); None when the
            page was kept from an earlier run.
    """

    scenario: str
    policy: str
    case: int
    seed: int
    success: bool
    path: str
    reproduced: bool | None


@dataclass
class SuiteResult:
    """What a run produced.

    Attributes:
        config: the run's config.
        scenarios: the scenarios, in order.
        policies: the policy specs, in order.
        units: the (scenario, policy) units.
        entries: one table entry per unit (socialzoo.bench.task_benchmark.table_entry, map = the
            scenario's name), policy-major.
        metrics: the tables' and heatmaps' metrics, in registry order.
        played: episodes played now.
        reused: episodes read from the store.
        replays: the replay pages.
        notes: remarks for the output (a split other than test, a replay that differs).
        files: every file written.
        seconds: the run's wall time.
        confidence: the two-sided level of every interval.
    """

    config: SuiteConfig
    scenarios: list[SuiteScenario]
    policies: list[str]
    units: list[SuiteUnit]
    entries: list[dict[str, Any]]
    metrics: list[str]
    played: int = 0
    reused: int = 0
    replays: list[Replay] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)
    seconds: float = 0.0
    confidence: float = CONFIDENCE

    def entry(self, policy: str, scenario: str) -> dict[str, Any] | None:
        """The table entry of a policy on a scenario, or None."""
        return next((e for e in self.entries if e["policy"] == policy and e["map"] == scenario), None)


def run_suite(
    config: SuiteConfig,
    out: str | Path,
    *,
    progress: bool = False,
    say: Callable[[str], None] | None = None,
) -> SuiteResult:
    """Run the suite into `out`: the store (results.sqlite), config.json, per metric
    tables/METRIC.csv and .md and heatmaps/METRIC.png, suite.csv and suite.md (every metric),
    replays/SCENARIO/*.html and results.html.

    Args:
        config: what to run.
        out: the output folder (made if missing; a rerun reads what its store holds).
        progress: show the episodes' progress (socialzoo.bench.progress).
        say: called with each note and each replay written, as the CLI prints them.

    Raises:
        SuiteError: see `plan_suite`; nothing is written then.
        socialzoo.bench.store.StoreError: out/results.sqlite is not a usable store.
    """
    from socialzoo import __version__
    from socialzoo.bench.suite_page import (
        CONFIG_FILE,
        HEATMAPS_DIR,
        PAGE_FILE,
        TABLES_DIR,
        plot_heatmap,
        write_suite_page,
        write_suite_tables,
    )
    from socialzoo.bench.tables import remove_outputs
    from socialzoo.bench.task_benchmark import evaluate_stored, summarize, table_entry
    from socialzoo.core.files import write_text_atomic
    from socialzoo.core.metrics import names as metric_names

    start = time.perf_counter()
    units, notes = plan_suite(config)
    for note in notes:
        _tell(say, note)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    store_path = out / STORE_FILE
    played = _play_missing(units, store_path, config, progress)
    entries, episodes_of = [], {}
    for unit in units:
        episodes, late = evaluate_stored(
            store_path,
            unit.task,
            unit.spec,
            unit.policy,
            unit.split,
            unit.cases,
            config.batch_size,
            unit.overrides,
        )
        if late:  # the backend stored them all, unless its rows were keyed otherwise than evaluate_stored's
            logger.warning(
                "%s on %s: %d episodes played again by evaluate_stored", unit.spec, unit.scenario.name, late
            )
        played += late
        episodes_of[(unit.spec, unit.scenario.name)] = episodes
        entries.append(
            table_entry(
                unit.spec,
                unit.scenario.name,
                unit.test_set,
                summarize(episodes, CONFIDENCE, cell=(unit.spec, unit.scenario.name)),
            )
        )
    reused = len(units) * config.seeds - played
    scenarios = list(dict.fromkeys(u.scenario for u in units))
    policies = list(config.policy_specs)
    order = {(p, s.name): i for i, (p, s) in enumerate((p, s) for p in policies for s in scenarios)}
    entries.sort(key=lambda e: order[(e["policy"], e["map"])])
    result = SuiteResult(
        config=config,
        scenarios=scenarios,
        policies=policies,
        units=units,
        entries=entries,
        metrics=suite_metrics(entries, config.metrics),
        played=played,
        reused=reused,
        notes=notes,
    )
    files = [store_path]
    files += write_suite_tables(result, out)
    files += [plot_heatmap(result, name, out / HEATMAPS_DIR) for name in result.metrics]
    # An older run's tables and heatmaps of metrics this one left out (another --metrics).
    stale = [name for name in metric_names() if name not in result.metrics]
    remove_outputs(out / TABLES_DIR, stale, ("csv", "md"))
    remove_outputs(out / HEATMAPS_DIR, stale, ("png",))
    result.replays = write_replays(units, episodes_of, out, config.replays, say)
    result.notes += [
        f"the replay {r.path} did not end as its stored episode (the code changed since it was stored?)"
        for r in result.replays
        if r.reproduced is False
    ]
    files += [out / r.path for r in result.replays]
    record = {
        "suite": config.to_json(),
        "package_version": __version__,
        "confidence": CONFIDENCE,
        "units": [
            {
                "scenario": u.scenario.name,
                "policy": u.spec,
                "env_id": u.task.env_id,
                "task": u.task.task,
                "task_kwargs": {**u.task.kwargs, **u.overrides},
                "split": u.split,
                "cases": u.cases,
                "config_hash": u.digest,
            }
            for u in units
        ],
        "notes": result.notes,
    }
    files.append(write_text_atomic(out / CONFIG_FILE, json_text(record, indent=2, default=str) + "\n"))
    result.seconds = time.perf_counter() - start
    files.append(write_suite_page(result, out / PAGE_FILE))
    result.files = files
    return result


def _tell(say: Callable[[str], None] | None, line: str) -> None:
    """A line for the output: to `say` where given (the CLI prints it), else to the log."""
    if say is not None:
        say(line)
    else:
        logger.info(line)


def _play_missing(units: Sequence[SuiteUnit], store_path: Path, config: SuiteConfig, progress: bool) -> int:
    """Play every unit's cases the store lacks on the run's backend, storing each episode as it ends
    under the key `evaluate_stored` reads it by; returns how many were played."""
    from socialzoo.bench.runner import CaseSet, RunSpec, Trial, TrialResult, evaluate
    from socialzoo.bench.store import ResultsStore, trial_row

    with ResultsStore(store_path) as store:
        trials: list[Trial] = []
        by_key: dict[tuple[str, str], SuiteUnit] = {}
        for unit in units:
            store.register_config(
                unit.digest,
                {
                    "task": unit.config.to_dict(),
                    "split": unit.split,
                    "policy": unit.spec,
                    "env_id": unit.task.name,
                    "task_config": unit.task.given_fields(unit.overrides),
                },
            )
            have = store.stored_indices(unit.spec, unit.test_set, unit.digest)
            trials += [Trial(unit.spec, unit.runner_set, k) for k in range(unit.cases) if k not in have]
            by_key[(unit.spec, unit.runner_set)] = unit
        if not trials:
            return 0
        sets = {u.runner_set: u for u in units}
        spec = RunSpec(
            test_sets={
                name: CaseSet(u.task.task, u.split, u.split_size, name, u.where) for name, u in sets.items()
            },
            env_configs={name: u.config for name, u in sets.items()},
            policies={u.spec: {} for u in units},
            batch_size=config.batch_size,
            guideline_metrics=True,  # every suite episode gets the guidelines' Table I metrics
        )

        def store_results(results: list[TrialResult]) -> None:
            rows = []
            for r in results:
                unit = by_key[(r.trial.policy, r.trial.test_set)]
                metrics = {k: float(v) for k, v in r.metrics.items()}
                names = {
                    "policy": unit.spec,
                    "map": unit.where,
                    "test_set": unit.test_set,
                    "metrics": metrics,
                }
                rows.append(trial_row(r, unit.digest, **names))
            store.add(rows)

        evaluate(
            trials,
            spec,
            backend=config.backend,
            workers=config.workers,
            address=config.address,
            on_results=store_results,
            progress=progress,
            desc="suite episodes",
        )
    return len(trials)


# The tables' and heatmaps' metrics unless chosen: the task's success and the guidelines' Table I
# core (collisions, time, path, SPL, personal space, closest approach, time to collision, clearance).
HEADLINE_METRICS = (
    "success",
    "collision",
    "timeout",
    "gl_success",
    "gl_collisions",
    "gl_timeout",
    "gl_time_to_goal",
    "gl_path_length",
    "gl_spl",
    "gl_stalled_time",
    "gl_personal_space_compliance",
    "gl_min_distance_to_human",
    "gl_min_time_to_collision",
    "gl_clearing_distance_min",
    "gl_jerk_avg",
)


def suite_metrics(entries: Sequence[Mapping[str, Any]], chosen: Sequence[str] = ()) -> list[str]:
    """The metrics of the tables and heatmaps: `chosen` (in registry order), else every registered
    metric that every entry holds.

    Raises:
        SuiteError: a chosen metric that the episodes do not hold (the message lists theirs).
    """
    from socialzoo.bench.tables import task_layout

    held = list(task_layout(entries, guidelines=True).metrics)
    if not chosen:
        headline = [m for m in held if m in HEADLINE_METRICS]
        return headline or held
    missing = [m for m in chosen if m not in held]
    if missing:
        raise SuiteError(f"the episodes hold no metric {', '.join(missing)}; they hold {', '.join(held)}")
    return [m for m in held if m in chosen]


def replay_choices(episodes: Sequence[Mapping[str, Any]], count: int) -> list[Mapping[str, Any]]:
    """The `count` episodes to replay: the failed ones first (the policy's mistakes are what a reader
    looks for), then successful ones to make up the count; in case order."""
    failed = [e for e in episodes if not bool(e["success"])]
    succeeded = [e for e in episodes if bool(e["success"])]
    return sorted((failed + succeeded)[:count], key=lambda e: int(e["case"]))


def _slug(text: str) -> str:
    """A file-name-safe form of a policy spec ("ppo:runs/a.safetensors" -> "ppo-runs-a.safetensors")."""
    return re.sub(r"[^A-Za-z0-9_.]+", "-", text).strip("-") or "policy"


def write_replays(
    units: Sequence[SuiteUnit],
    episodes_of: Mapping[tuple[str, str], Sequence[Mapping[str, Any]]],
    out: Path,
    count: int,
    say: Callable[[str], None] | None = None,
) -> list[Replay]:
    """Replay pages (socialzoo.render.replay_html) of each unit's chosen episodes
    (`replay_choices`), as replays/SCENARIO/POLICY-caseK-HASH.html; a page already there (same
    episode key) is kept, and an older run's pages this run does not show (another policy, scenario,
    episode or --replays) are removed. Each new recording is checked against the stored episode."""
    import numpy as np

    from socialzoo.bench.episode_play import step_seconds
    from socialzoo.bench.replay import record_task_episode
    from socialzoo.render.replay_data import Encoding, default_stride
    from socialzoo.render.replay_html import write_replay_html

    replays = []
    for unit in units:
        if count == 0:
            break
        name = unit.scenario.name
        for episode in replay_choices(episodes_of[(unit.spec, name)], count):
            case, success = int(episode["case"]), bool(episode["success"])
            rel = f"{REPLAYS_DIR}/{name}/{_slug(unit.spec)}-case{case}-{unit.digest[:8]}.html"
            path = out / rel
            task = unit.task.make(1, **unit.overrides)
            seed = int(task.reset(np.array([0]), {"split": unit.split, "cases": [case]})[0])
            if path.is_file():
                replays.append(Replay(name, unit.spec, case, seed, success, rel, None))
                continue
            stride = default_stride(step_seconds(task))
            trace = record_task_episode(
                task, unit.policy, label=unit.spec, laser_rays=REPLAY_LASER_RAYS, laser_stride=stride
            )
            same = bool(trace.metrics.get("success")) == success and int(
                trace.metrics.get("steps", -1)
            ) == int(episode.get("steps", -2))
            title = f"{unit.spec} on {unit.scenario.label}, {unit.split} case {case}"
            subtitle = f"family {name} on {unit.scenario.map_name}; the {unit.task.task} task"
            scene = task.viewer_scene(title, subtitle, [trace])
            write_replay_html(
                path,
                scene,
                [trace],
                encoding=Encoding(stride=stride, laser_rays=REPLAY_LASER_RAYS),
            )
            _tell(say, f"replay {rel}: {trace.outcome}")
            replays.append(Replay(name, unit.spec, case, seed, success, rel, same))
    shown = {r.path for r in replays}
    for page in sorted((out / REPLAYS_DIR).glob("*/*.html")):
        rel = page.relative_to(out).as_posix()
        if rel not in shown and REPLAY_PAGE.fullmatch(page.name):
            page.unlink()
            if not any(page.parent.iterdir()):
                page.parent.rmdir()
    return replays
