"""The `benchmark` experiment (SPEC section 10, performance and transfer): policies x maps x trials
-> results store -> summary.csv, summary.md and figures, with config.json beside them."""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import inspect
import json
import logging
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from socialzoo.bench.runner import Backend, RunSpec, Trial, TrialResult, env_config_for, evaluate
from socialzoo.bench.store import ResultsStore, trial_row
from socialzoo.bench.tables import (
    PAPER_LAYOUT,
    TableLayout,
    policy_label,
    remove_outputs,
    summarize,
    write_tables,
)
from socialzoo.core.files import json_text, no_file, write_text_atomic
from socialzoo.core.metrics import names as metric_names
from socialzoo.core.validation import check_int
from socialzoo.data.fetch import sha256
from socialzoo.env.config import EnvConfig
from socialzoo.scenarios.scenario_sets import TEST_SETS, TestSet

logger = logging.getLogger(__name__)

STORE_NAME = "results.sqlite"
CONFIG_NAME = "config.json"
GIF_NAME = "ref_episode.gif"
# The full benchmark's default policies; the quick one (`make run`) adds the shipped learned policies.
DEFAULT_POLICIES = ("goalone", "ref")
QUICK_POLICIES = ("goalone", "ref", "ppo", "dqn", "bc", "gail", "pips")
QUICK_MAPS = ("gdc1", "ghc3")


@dataclass(frozen=True, kw_only=True)
class BenchmarkConfig:
    """What a benchmark run evaluates, and how.

    Attributes:
        policies: policy specs: registry names (socialzoo.agents.POLICIES; a learned policy's
            name alone is its shipped file) or "NAME:PATH" for a learned policy's file.
        maps: maps to evaluate on; each uses its test set "<map>-test" (2000 scenarios), or
            "<map>-quick" (100) with quick=True.
        trials: scenarios per policy and map: the first `trials` of each test set; None: all.
        quick: use the quick test sets.
        backend: "local" (processes on this machine) or "ray".
        address: Ray cluster address (Ray backend); None starts a local Ray.
        workers: local processes, or Ray chunks (None: one per cluster CPU).
        batch_size: env rows stepped together per worker.
        env_overrides: EnvConfig.replace keywords applied to every map's env config, e.g.
            {"max_steps": 400}; plain JSON values.
        policy_kwargs: make_policy keyword arguments per policy name, e.g. {"ppo": {"path": ...}}.
        gif: also write one animated Ref episode (ref_episode.gif) on the first map.
        humans: the people of every scenario, a people spec (socialzoo.humans.models):
            "social_force" (or "sf", the default), "orca", "groups", "learned:PATH" (a learned
            human policy file, `socialzoo train humans`), or a mix such as "sf@0.5+orca@0.5" or
            "learned:PATH@0.4+sf@0.6". It is set as EnvConfig.people.models: the env drives
            every person itself, learned ones included. Not EnvConfig.num_learned_humans: those
            are human agents that a learner drives from outside (multi-agent training), which a
            benchmark has none of.
        human_metrics: also record the humans' episode metrics (socialzoo.bench.human_metrics)
            with every trial, and write humans.csv and humans.md.
        counterfactual: also run every scenario without the robot and record what the robot
            costs the people (EnvConfig.people.counterfactual: people_time_lost,
            people_extra_distance).
    """

    policies: tuple[str, ...] = DEFAULT_POLICIES
    maps: tuple[str, ...] = QUICK_MAPS
    trials: int | None = None
    quick: bool = False
    backend: Backend = "local"
    address: str | None = None
    workers: int | None = 2
    batch_size: int = 64
    env_overrides: Mapping[str, Any] = field(default_factory=dict)
    policy_kwargs: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    gif: bool = False
    humans: str = "social_force"
    human_metrics: bool = False
    counterfactual: bool = False

    def __post_init__(self) -> None:
        from socialzoo.agents import check_policy_spec
        from socialzoo.bench.runner import check_backend

        try:
            check_humans(self.humans)
        except ValueError as err:
            raise ValueError(f"BenchmarkConfig.humans: {err}") from None
        for name in ("counterfactual", "human_metrics"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"BenchmarkConfig.{name} must be a bool, got {getattr(self, name)!r}")

        object.__setattr__(self, "policies", tuple(self.policies))
        object.__setattr__(self, "maps", tuple(self.maps))
        if not self.policies:
            raise ValueError("BenchmarkConfig.policies is empty")
        for p in self.policies:
            try:
                check_policy_spec(p)
            except ValueError as err:
                raise ValueError(f"BenchmarkConfig.policies: {err}") from None
        if not self.maps:
            raise ValueError("BenchmarkConfig.maps is empty")
        for name in ("policies", "maps"):
            values = getattr(self, name)
            if len(set(values)) != len(values):
                raise ValueError(f"BenchmarkConfig.{name} has duplicates: {list(values)!r}")
        unknown = sorted(set(self.policy_kwargs) - set(self.policies))
        if unknown:
            raise ValueError(f"BenchmarkConfig.policy_kwargs names policies not evaluated: {unknown}")
        check_int("BenchmarkConfig", "trials", self.trials, low=1, allow_none=True)
        check_backend(self.backend, "BenchmarkConfig.backend")
        if self.address is not None and self.backend != "ray":
            raise ValueError(f"BenchmarkConfig.address is for the Ray backend, got backend {self.backend!r}")
        check_int("BenchmarkConfig", "workers", self.workers, low=1, allow_none=True)
        check_int("BenchmarkConfig", "batch_size", self.batch_size, low=1)
        env = EnvConfig().replace(**dict(self.env_overrides))  # fail early, naming a bad override
        if env.num_learned_humans:
            raise ValueError(
                f"BenchmarkConfig.env_overrides: num_learned_humans = {env.num_learned_humans} asks for human "
                "agents that a learner drives (multi-agent training), and a benchmark has no learner; name "
                "learned people in BenchmarkConfig.humans instead (a people spec: 'learned:PATH', or a mix "
                "such as 'learned:PATH@0.4+sf@0.6')"
            )

    def test_set_name(self, map_name: str) -> str:
        """The registry test set evaluated on a map."""
        return f"{map_name}-{'quick' if self.quick else 'test'}"

    def to_json(self) -> dict[str, Any]:
        """Plain JSON form."""
        return dataclasses.asdict(self) | {
            "policies": list(self.policies),
            "maps": list(self.maps),
            "env_overrides": dict(self.env_overrides),
            "policy_kwargs": {k: dict(v) for k, v in self.policy_kwargs.items()},
        }


def quick_config(**changes: Any) -> BenchmarkConfig:
    """The quick benchmark (`make run`): GoAlone, Ref and the shipped learned policies, 100 trials on
    each quick test set, a GIF."""
    return BenchmarkConfig(
        **{"policies": QUICK_POLICIES, "maps": QUICK_MAPS, "quick": True, "gif": True, **changes}
    )


@dataclass(frozen=True)
class BenchmarkResult:
    """What a benchmark run produced.

    Attributes:
        out_dir: the output directory.
        summary: one dict per policy and map (socialzoo.bench.tables.summarize).
        files: every file written (store, config, tables, figures, GIF).
        computed: trials run by this call.
        reused: trials read from the store.
        seconds: wall time of the evaluation itself.
    """

    out_dir: Path
    summary: list[dict[str, Any]]
    files: list[Path]
    computed: int
    reused: int
    seconds: float


def env_id_for(map_name: str) -> str | None:
    """The registered benchmark env id of a map ("gdc1" -> "socialzoo/ActionSelection-v2"), or None.

    Its version suffix changes whenever a seeded rollout changes, so it is part of the config hash.
    """
    from socialzoo.env.registration import BENCHMARK_IDS

    return next((env_id for env_id, kw in BENCHMARK_IDS.items() if kw.get("map") == map_name), None)


def file_digest(path: str | Path) -> str | None:
    """sha256 of a file's bytes, or None when there is no such file."""
    return sha256(path) if Path(path).is_file() else None


# Subpackages whose code decides a rollout (with the policy's own module): the world, its people, maps,
# navigation, scenario families and scripts, and the tasks.
_ROLLOUT_PACKAGES = ("core", "humans", "maps", "nav", "scenarios", "env")


@functools.cache
def source_digest(files: tuple[str, ...] = ()) -> str:
    """sha256 of the source code that decides a rollout (socialzoo.core, humans, maps, nav, scenarios,
    env) plus `files`, e.g. a policy's module (paths and contents)."""
    import socialzoo

    root = Path(socialzoo.__file__).resolve().parent
    paths = sorted(
        {f for pkg in _ROLLOUT_PACKAGES for f in (root / pkg).rglob("*.py")} | {Path(f) for f in files}
    )
    digest = hashlib.sha256()
    for path in paths:
        name = path.relative_to(root).as_posix() if path.is_relative_to(root) else path.name
        digest.update(name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def config_hash(
    env_config: EnvConfig,
    policy: str,
    policy_object: Any,
    test_set: TestSet,
    policy_kwargs: Mapping[str, Any] | None = None,
    humans: Mapping[str, Any] | None = None,
) -> str:
    """16 hex digits naming everything that decides a trial's outcome besides its scenario index.

    Covered: the env config and the map's registered env id; the map's data; the source code of
    the simulation (socialzoo.core, humans, nav, env) and of the policy's module, so that results
    of changed code are never read back as current ones; the policy's parameters (and the digest
    of its file, for learned policies); the test set's generator (map, base seed, scenario
    config; not its length, so a longer run reuses a shorter one's trials); and, when given,
    `humans`: whether human metrics are recorded. A learned people model counts by the digest of
    its file, not its path (hashed_people).
    """
    from socialzoo.agents.base import policy_config
    from socialzoo.bench.test_sets import map_sha256
    from socialzoo.maps.map_file import load_map

    kwargs = dict(policy_kwargs or {})
    env = env_config.to_dict()
    env["people"]["models"] = hashed_people(env_config.people.models)
    payload = {
        "env_id": env_id_for(test_set.map_name),
        "env": env,
        "map_sha256": map_sha256(load_map(env_config.map_name)),
        "policy": {
            "name": policy,
            "config": policy_config(policy_object),
            "file_sha256": file_digest(kwargs["path"]) if "path" in kwargs else None,
        },
        "test_set": {
            "map": test_set.map_name,
            "base_seed": test_set.base_seed,
            "scenario": dataclasses.asdict(test_set.cfg),
        },
    }
    if humans is not None:
        payload["humans"] = dict(humans)
    return payload_hash(payload, policy_object)


def payload_hash(payload: Mapping[str, Any], policy_object: Any) -> str:
    """A config hash (both benchmarks'): 16 hex digits of the sha256 of `payload` with "code_sha256",
    the source_digest of the rollout code and of the module of the policy's class, as sorted JSON."""
    module_file = inspect.getsourcefile(type(policy_object))
    payload = {**payload, "code_sha256": source_digest((module_file,) if module_file else ())}
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()[:16]


def hashed_people(models: str) -> str:
    """A people spec as the config hash reads it: each learned model's file named by the sha256
    of its bytes instead of its path, so the same file under another name reads its trials back
    and another file runs again; specs without a learned model unchanged."""
    from socialzoo.humans.models import parse_people

    parts = parse_people(models)
    if all(part.path is None for part in parts):
        return models
    named = (
        part if part.path is None else dataclasses.replace(part, path=f"sha256:{file_digest(part.path)}")
        for part in parts
    )
    return "+".join(f"{part.name}@{part.share!r}" for part in named)


def check_humans(humans: str) -> str:
    """Validate a benchmark's humans, a people spec (the file of a learned model must exist);
    returns it.

    Raises:
        ValueError: naming the spec: an unknown model, a bad share, a missing file.
    """
    from socialzoo.humans.models import parse_people

    for part in parse_people(humans):
        if part.path is not None and not Path(part.path).is_file():
            raise ValueError(f"humans {humans!r}: {no_file(part.path, 'learned policy file')}")
    return humans


def people_overrides(config: BenchmarkConfig) -> dict[str, Any]:
    """EnvConfig overrides for the run's people: none for the benchmark's (social force, no
    counterfactual rows), else EnvConfig.people with the spec and the counterfactual rows."""
    from socialzoo.humans.models import PeopleConfig

    people = PeopleConfig(models=config.humans, counterfactual=config.counterfactual)
    if people.is_default:
        return {}
    return {"people": {"models": config.humans, "counterfactual": config.counterfactual}}


def _resolve_test_sets(
    config: BenchmarkConfig, test_sets: Mapping[str, TestSet] | None, out_dir: Path
) -> dict[str, TestSet]:
    """Test set per map: given ones first, else the registry's (a map file with a shipped map's contents
    included: scenario_sets.shipped_map), else one generated for the map and stored in out_dir
    (socialzoo.bench.test_sets: any shipped map or map file)."""
    from socialzoo.bench.test_sets import stored_set_name, stored_test_set
    from socialzoo.scenarios.scenario_sets import shipped_map

    given: dict[str, TestSet] = {}
    # Every map's test set by name first: two map files of one name are refused before the first
    # one's set is generated (the second's then clashed with the file it wrote: "the map now has
    # sha256 ...: use another --out directory").
    names: dict[str, str] = {}
    for m in config.maps:
        name = config.test_set_name(shipped_map(m) or m)
        if test_sets is not None and m in test_sets:
            given[m] = test_sets[m]
        elif name in TEST_SETS:
            given[m] = TEST_SETS[name]
        names[m] = (given[m].name or m) if m in given else stored_set_name(m, config.quick)
        same = [k for k in names if k != m and names[k] == names[m]]
        if same:
            raise ValueError(
                f"maps {same[0]!r} and {m!r} both give test set {names[m]!r} (one map, or two of "
                "one name): benchmark one of them"
            )
    return {
        m: given[m] if m in given else stored_test_set(m, out_dir, config.trials, quick=config.quick)
        for m in config.maps
    }


def run_benchmark(
    config: BenchmarkConfig,
    out_dir: str | Path,
    *,
    test_sets: Mapping[str, TestSet] | None = None,
    progress: bool = True,
    on_results: Callable[[list[TrialResult]], None] | None = None,
    figures: bool = True,
) -> BenchmarkResult:
    """Run (or resume, or read back) a benchmark and write its tables and figures.

    Writes into out_dir: results.sqlite (every trial), config.json (this config, each map's
    resolved env config and test set with its scenario seeds, policy parameters, config
    hashes, package version), summary.csv, summary.md, success.{png,pdf}, metrics.{png,pdf},
    and ref_episode.gif when config.gif (else an older run's is removed, as are its figures
    without `figures` and its humans tables without config.human_metrics).

    Trials already in the store (same policy, test set, scenario and config hash) are read, not rerun,
    so a repeated run is free and an interrupted one resumes where it stopped.

    Args:
        config: what to evaluate.
        out_dir: output directory (created).
        test_sets: test sets to use for some maps instead of the registry's (keyed by map
            name as in config.maps); for small custom runs and tests.
        progress: show a progress bar.
        on_results: also called with each group of finished trials, after they are stored.
        figures: draw the figures (needs matplotlib).

    Maps without a registered test set (any shipped map or map file) get one generated on first
    use and stored in out_dir/test_sets/ with the map's hash (socialzoo.bench.test_sets); reruns
    read it back, so their trials compare with the stored ones.

    Raises:
        ValueError: an unknown map, more trials than a test set holds, a stored test set made on
            another version of its map.
        FileNotFoundError: a map file that does not exist.
        socialzoo.bench.store.StoreError: out_dir holds a results file that is not a socialzoo
            store or is corrupted (it is left untouched).
    """
    from socialzoo.agents import check_observation_size, make_policy
    from socialzoo.agents.base import policy_config
    from socialzoo.env.observation import observation_space

    out = Path(out_dir)
    # Every policy is built (a bad policy file refused) and the store opened (an unusable one refused)
    # before any test set is made: generating a new map's 2000 scenarios takes minutes.
    policy_kwargs = {p: dict(config.policy_kwargs.get(p, {})) for p in config.policies}
    policies = {p: make_policy(p, **policy_kwargs[p]) for p in config.policies}
    if (out / STORE_NAME).exists():
        ResultsStore(out / STORE_NAME).close()
    sets = _resolve_test_sets(config, test_sets, out)
    counts = {}
    for m, ts in sets.items():
        n = len(ts) if config.trials is None else config.trials
        if n > len(ts):
            raise ValueError(
                f"{n} trials asked on map {m!r}, but test set {ts.name or m!r} holds only {len(ts)}"
            )
        counts[m] = n
    set_names = {m: ts.name or m for m, ts in sets.items()}
    env_configs = {
        set_names[m]: env_config_for(ts, **{**people_overrides(config), **dict(config.env_overrides)})
        for m, ts in sets.items()
    }
    # A learned policy reads the observations of the benchmark's env configs: one of another layout (a
    # file trained with other observation settings) is refused here, by name, not when it first acts.
    for env_config in {c.observation_size: c for c in env_configs.values()}.values():
        space = observation_space(env_config.observation, env_config.signals)
        for p in config.policies:
            check_observation_size(p, policies[p], "action_selection", space)
    policy_configs = {p: policy_config(policies[p]) for p in config.policies}
    spec = RunSpec(
        test_sets={set_names[m]: ts for m, ts in sets.items()},
        env_configs=env_configs,
        policies=policy_kwargs,
        batch_size=config.batch_size,
        human_metrics=config.human_metrics,
    )
    # What the config hash records about the humans besides the env config: whether human metrics
    # are recorded; None without them, so the hashes of such runs are as before.
    humans = {"human_metrics": True} if config.human_metrics else None
    hashes = {
        (p, set_names[m]): config_hash(
            env_configs[set_names[m]], p, policies[p], ts, policy_kwargs[p], humans
        )
        for p in config.policies
        for m, ts in sets.items()
    }
    out.mkdir(parents=True, exist_ok=True)
    store = ResultsStore(out / STORE_NAME)
    files = [store.path]
    try:
        for (p, name), h in hashes.items():
            store.register_config(
                h,
                {
                    "policy": p,
                    "policy_config": policy_configs[p],
                    "env": env_configs[name].to_dict(),
                    "test_set": name,
                },
            )
        run_json = _run_json(
            config, sets, set_names, counts, env_configs, policy_kwargs, policy_configs, hashes
        )
        store.set_meta("config", json.dumps(run_json, sort_keys=True))
        config_path = out / CONFIG_NAME
        write_text_atomic(config_path, json_text(run_json, indent=2, sort_keys=True) + "\n")
        files.append(config_path)

        pending: list[Trial] = []
        total = 0
        for p in config.policies:
            for m in config.maps:
                name = set_names[m]
                done = store.stored_indices(p, name, hashes[(p, name)])
                total += counts[m]
                pending += [Trial(p, name, k) for k in range(counts[m]) if k not in done]
        reused = total - len(pending)
        logger.info("benchmark: %d trials, %d stored, %d to run", total, reused, len(pending))

        def deliver(batch: list[TrialResult]) -> None:
            store.add(trial_row(r, hashes[(r.trial.policy, r.trial.test_set)]) for r in batch)
            if on_results is not None:
                on_results(batch)

        start = time.perf_counter()
        evaluate(
            pending,
            spec,
            backend=config.backend,
            workers=config.workers,
            address=config.address,
            on_results=deliver,
            progress=progress,
            desc="benchmark",
        )
        seconds = time.perf_counter() - start
        rows = []
        for p in config.policies:
            for m in config.maps:
                name = set_names[m]
                rows += store.rows(
                    policy=p, test_set=name, config_hash=hashes[(p, name)], indices=range(counts[m])
                )
    finally:
        store.close()
    # What the robot cost the people (--counterfactual; groups' intrusions) where every trial holds it.
    people = tuple(n for n in metric_names("people") if rows and all(r.get(n) is not None for r in rows))
    layout = TableLayout(PAPER_LAYOUT.metrics + people, paper=True)
    summary = summarize(
        rows,
        policies=config.policies,
        maps=[_display_name(sets[m]) for m in config.maps],
        metrics=layout.metrics,
    )
    files += write_tables(summary, out, title=_title(config, counts), layout=layout)
    if config.human_metrics:
        from socialzoo.bench.human_metrics import summarize_humans, write_humans_tables

        files += write_humans_tables(
            summarize_humans(rows, policies=config.policies, maps=[sets[m].map_name for m in config.maps]),
            out,
            title=f"Humans ({config.humans}) in the {_title(config, counts)}",
        )
    else:  # an older run's people tables would sit beside tables without them
        remove_outputs(out, ["humans"], ("csv", "md"))
    from socialzoo.bench.figures import FIGURE_FORMATS, SUMMARY_FIGURES, plot_summary

    if figures:
        files += plot_summary(summary, out)
    else:  # an older run's figures would not match these tables
        remove_outputs(out, SUMMARY_FIGURES, FIGURE_FORMATS)
    if config.gif:
        first = config.maps[0]
        files.append(write_episode_gif(out / GIF_NAME, env_configs[set_names[first]], sets[first], 0, "ref"))
    else:  # an older run's animation (--quick) would sit beside tables of other trials
        remove_outputs(out, [Path(GIF_NAME).stem], [Path(GIF_NAME).suffix[1:]])
    return BenchmarkResult(out, summary, files, len(pending), reused, seconds)


def _display_name(test_set: TestSet) -> str:
    """The map's own name, as trials record it (a map file names its map inside)."""
    from socialzoo.maps.map_file import load_map

    return load_map(test_set.map_name).name


def _title(config: BenchmarkConfig, counts: Mapping[str, int]) -> str:
    kind = "quick test sets" if config.quick else "test sets"
    return (
        f"Social Action Selection benchmark ({kind}: "
        + ", ".join(f"{m} {n}" for m, n in counts.items())
        + ")"
    )


def _run_json(
    config: BenchmarkConfig,
    sets: Mapping[str, TestSet],
    set_names: Mapping[str, str],
    counts: Mapping[str, int],
    env_configs: Mapping[str, EnvConfig],
    policy_kwargs: Mapping[str, Mapping[str, Any]],
    policy_configs: Mapping[str, Mapping[str, Any]],
    hashes: Mapping[tuple[str, str], str],
) -> dict[str, Any]:
    from socialzoo import __version__

    return {
        "package_version": __version__,
        "written_at": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "benchmark": config.to_json(),
        "test_sets": {
            set_names[m]: {
                "map": ts.map_name,
                "env_id": env_id_for(ts.map_name),
                "base_seed": ts.base_seed,
                "size": len(ts),
                "trials": counts[m],
                "scenario": dataclasses.asdict(ts.cfg),
                "seeds": [ts.seed(k) for k in range(counts[m])],
            }
            for m, ts in sets.items()
        },
        "env_configs": {name: cfg.to_dict() for name, cfg in env_configs.items()},
        "policies": {
            p: {"kwargs": dict(policy_kwargs[p]), "config": dict(policy_configs[p])} for p in policy_kwargs
        },
        "config_hashes": {f"{p}/{name}": h for (p, name), h in hashes.items()},
    }


def write_episode_gif(
    path: str | Path,
    env_config: EnvConfig,
    test_set: TestSet,
    index: int,
    policy: str,
) -> Path:
    """Animate one episode of `policy` on scenario `index` of a test set as a GIF
    (socialzoo.bench.episode_video.animate_episode at its defaults), among the env config's people."""
    from socialzoo.agents import make_policy
    from socialzoo.bench.episode_play import scenario_task
    from socialzoo.bench.episode_video import animate_episode
    from socialzoo.maps.map_file import load_map

    m = load_map(env_config.map_name)
    task = scenario_task(env_config, test_set.scenario(index, m), m)
    label = f"{policy_label(policy)}, {test_set.name or test_set.map_name} #{index}"
    return animate_episode(path, task, make_policy(policy), label=label).path
