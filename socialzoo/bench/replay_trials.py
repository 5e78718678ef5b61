"""Stored benchmark trials, replayed: find a trial in a results store (`socialzoo benchmark --out DIR`), rebuild
its env config, scenario and policy, run it again and check that the replayed metrics are the stored ones."""

from __future__ import annotations

import json
import math
import shlex
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.agents import Policy, make_policy
from socialzoo.agents.base import policy_config
from socialzoo.bench.experiment import STORE_NAME, config_hash
from socialzoo.bench.replay import record_episode
from socialzoo.bench.store import ResultsStore
from socialzoo.bench.test_sets import TEST_SET_DIR
from socialzoo.env.config import EnvConfig
from socialzoo.env.metrics import SUMMARY_KEYS
from socialzoo.maps.map_file import Map, load_map, map_sha256
from socialzoo.render.replay_data import EpisodeTrace
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.scenario_sets import TestSet

# Relative tolerance of the metric check. Replays are bit-identical in practice (the runner's
# results do not depend on the batch); the tolerance only keeps the check from failing on a
# platform whose libm rounds a last bit differently.
METRIC_RTOL = 1e-9


@dataclass(frozen=True, kw_only=True)
class StoredTrial:
    """One trial of a results store, with what it takes to run it again.

    Attributes:
        policy, test_set, index, seed, map: as the TrialResult that stored it
            (socialzoo.bench.runner.TrialResult and its Trial).
        config_hash: the trial's config hash in the store.
        env_config: the env config the trial ran with.
        policy_kwargs: make_policy keyword arguments of the run that stored it (e.g. a path).
        policy_config: the policy's parameters as stored.
        test_set_info: the test set as the run recorded it (map, base_seed, size, scenario),
            or None when the store does not say.
        metrics: the stored metrics (socialzoo.env.metrics.SUMMARY_KEYS).
    """

    policy: str
    test_set: str
    index: int
    seed: int
    map: str
    config_hash: str
    env_config: EnvConfig
    policy_kwargs: Mapping[str, Any]
    policy_config: Mapping[str, Any]
    test_set_info: Mapping[str, Any] | None
    metrics: Mapping[str, Any]

    def scenario(self, world_map: Map | None = None) -> Scenario:
        """The trial's scenario, generated as the runner generates it: from the seed and the test
        set's scenario settings (the env config's when the store does not record the test set)."""
        m = world_map if world_map is not None else load_map(self.env_config.map_name)
        cfg = self.env_config.scenario
        if self.test_set_info is not None and "scenario" in self.test_set_info:
            cfg = ScenarioConfig(**self.test_set_info["scenario"])
        return generate_scenario(m, self.seed, cfg)

    def build_policy(self) -> Policy:
        """The policy with the stored parameters.

        Raises:
            ValueError: the policy cannot be rebuilt with the stored parameters (the message says
                what differs).
        """
        wanted = _canonical(self.policy_config)
        policy = make_policy(self.policy, **dict(self.policy_kwargs))
        if _canonical(policy_config(policy)) == wanted:
            return policy
        if not self.policy_kwargs and self.policy_config:
            # The run built it with other arguments than its config; its config is its parameters.
            try:
                policy = make_policy(self.policy, **dict(self.policy_config))
            except TypeError:
                pass
            else:
                if _canonical(policy_config(policy)) == wanted:
                    return policy
        raise ValueError(
            f"policy {self.policy!r} of trial {self.test_set} #{self.index}: cannot rebuild it with the "
            f"stored parameters {wanted} (make_policy gives {_canonical(policy_config(policy))})"
        )

    def code_changed(self, policy: Policy) -> bool | None:
        """Whether the config hash computed now differs from the stored one (the simulation code,
        the policy's module or file, the map changed since the trial ran); None when the store
        lacks the test set's description."""
        if self.test_set_info is None:
            return None
        info = self.test_set_info
        test_set = TestSet(
            str(info["map"]),
            int(info["base_seed"]),
            int(info["size"]),
            ScenarioConfig(**info["scenario"]),
            name=self.test_set,
        )
        now = config_hash(self.env_config, self.policy, policy, test_set, dict(self.policy_kwargs))
        return now != self.config_hash


def _canonical(config: Mapping[str, Any]) -> str:
    """A config as sorted JSON (tuples and lists alike), for comparison."""
    return json.dumps(config, sort_keys=True, default=str)


def store_path(results: str | Path) -> Path:
    """The results store of `results`: a `socialzoo benchmark --out` directory or its results.sqlite.

    Raises:
        FileNotFoundError: no store there.
    """
    path = Path(results)
    # A crowd matrix (socialzoo benchmark --humans A,B) keeps a store in each model's folder.
    inner = sorted(str(p.parent) for p in path.glob(f"*/{STORE_NAME}")) if path.is_dir() else []
    if path.is_dir():
        path = path / STORE_NAME
    if not path.is_file():
        where = f"; its folders hold one each: {', '.join(inner)}" if inner else ""
        raise FileNotFoundError(
            f"{path}: no results store (write one with socialzoo benchmark --out DIR){where}"
        )
    return path


def find_trials(
    results: str | Path,
    index: int,
    *,
    policies: Sequence[str] | None = None,
    test_set: str | None = None,
) -> list[StoredTrial]:
    """The stored trials of scenario `index`, one per policy (in the order of `policies`, else by name).

    Args:
        results: a `socialzoo benchmark --out` directory, or its results.sqlite.
        index: the scenario index in the test set (the trial number of `socialzoo replay --trial`).
        policies: only these policies (those not stored are left out; the caller may run them).
        test_set: the test set, by name ("gdc1-quick") or map ("gdc1"); needed when the store
            holds the scenario index for several test sets.

    Returns:
        The trials; when a policy was stored under several config hashes (runs of older code),
        the one of the store's latest run, else the most recently finished.

    Raises:
        FileNotFoundError: no store at `results`.
        socialzoo.bench.store.StoreError: not a results store.
        ValueError: no trial matches (the message lists what the store holds), several test
            sets do and `test_set` was not given, or the trial is a task id's fixed case (the
            message names the `socialzoo replay --env` command that plays it).
    """
    path = store_path(results)
    with ResultsStore(path) as store:
        run = json.loads(store.meta("config") or "{}")
        rows = store.rows(indices=[index])
        wanted = [p.lower() for p in policies] if policies else None
        if test_set is not None:
            rows = [r for r in rows if test_set in (r["test_set"], r["map"])]
        if wanted is not None:
            rows = [r for r in rows if r["policy"] in wanted]
        if not rows:
            everything = store.rows()
            held = sorted({(r["policy"], r["test_set"]) for r in everything})
            indices = sorted({r["scenario_index"] for r in everything})
            span = f"scenario indices {indices[0]}..{indices[-1]}" if indices else "no trials"
            raise ValueError(
                f"{path}: no stored trial of scenario {index}"
                + (f" on {test_set!r}" if test_set else "")
                + (f" for {', '.join(wanted)}" if wanted else "")
                + f"; the store holds {span} of (policy, test set) {held}"
            )
        sets = sorted({r["test_set"] for r in rows})
        if len(sets) > 1:
            raise ValueError(
                f"{path}: scenario {index} is stored for several test sets {sets}; choose one (--test-set)"
            )
        latest = dict(run.get("config_hashes", {}))
        chosen: dict[str, dict[str, Any]] = {}
        for row in rows:
            current = latest.get(f"{row['policy']}/{row['test_set']}") == row["config_hash"]
            rank = (current, row["finished_at"])
            have = chosen.get(row["policy"])
            if have is None or rank > have["_rank"]:
                chosen[row["policy"]] = {**row, "_rank": rank}
        order = [p for p in wanted if p in chosen] if wanted else sorted(chosen)
        trials = []
        for name in order:
            row = chosen[name]
            stored = store.config(row["config_hash"])
            if stored is None:
                raise ValueError(
                    f"{path}: config {row['config_hash']} of trial {row['test_set']} #{index} is missing"
                )
            if "env" not in stored and "task" in stored:
                # socialzoo.bench.task_benchmark's trials: a task id's fixed case, not a map's scenario.
                given = "".join(
                    " --task-config " + shlex.quote(f"{k}={v if isinstance(v, str) else json.dumps(v)}")
                    for k, v in stored.get("task_config", {}).items()
                )
                raise ValueError(
                    f"{path}: trial {row['test_set']} #{index} is a task id's case (socialzoo benchmark "
                    f"--maps ID, or socialzoo suite); play it with socialzoo replay --env "
                    f"{stored.get('env_id', 'ID')}{given} --split {stored.get('split', 'test')} "
                    f"--case {index} --policy {name}"
                )
            kwargs = run.get("policies", {}).get(name, {}).get("kwargs", {}) if row["_rank"][0] else {}
            trials.append(
                StoredTrial(
                    policy=name,
                    test_set=row["test_set"],
                    index=int(row["scenario_index"]),
                    seed=int(row["seed"]),
                    map=row["map"],
                    config_hash=row["config_hash"],
                    env_config=EnvConfig.from_dict(stored["env"]),
                    policy_kwargs=dict(kwargs),
                    policy_config=dict(stored.get("policy_config", {})),
                    test_set_info=run.get("test_sets", {}).get(row["test_set"]),
                    metrics={k: row[k] for k in SUMMARY_KEYS if k in row},
                )
            )
        return trials


def _same(a: Any, b: Any) -> bool:
    """Metric values equal: NaN (or a missing value) equals NaN; floats to METRIC_RTOL."""
    if a is None or b is None or isinstance(a, float) or isinstance(b, float):
        fa, fb = (math.nan if v is None else float(v) for v in (a, b))
        if math.isnan(fa) or math.isnan(fb):
            return math.isnan(fa) and math.isnan(fb)
        return math.isclose(fa, fb, rel_tol=METRIC_RTOL, abs_tol=1e-12)
    return bool(a == b)


def compare_metrics(stored: Mapping[str, Any], replayed: Mapping[str, Any]) -> list[str]:
    """The metrics whose replayed value differs from the stored one, as "name: stored -> replayed"."""
    return [
        f"{key}: stored {stored[key]!r}, replayed {replayed.get(key)!r}"
        for key in stored
        if not _same(stored[key], replayed.get(key))
    ]


@dataclass(frozen=True)
class TrialReplay:
    """A stored trial run again.

    Attributes:
        trial: the stored trial.
        trace: the recorded episode.
        mismatches: metrics that differ from the stored ones (empty when the replay reproduces
            the trial).
        code_changed: whether the code or configuration behind the trial's config hash changed
            since it was stored (None: unknown).
    """

    trial: StoredTrial
    trace: EpisodeTrace
    mismatches: list[str]
    code_changed: bool | None


def map_change(results: str | Path, trial: StoredTrial, world_map: Map) -> str:
    """'' or why `trial` cannot reproduce: its map file is no longer the one the run stored (the
    run's generated test set, DIR/test_sets/NAME.json, records the map's sha256; shipped maps have
    none there)."""
    path = store_path(results).parent / TEST_SET_DIR / f"{trial.test_set}.json"
    try:
        then = json.loads(path.read_text(encoding="utf-8")).get("map_sha256")
    except (OSError, ValueError, AttributeError):
        return ""
    now = map_sha256(world_map)
    if not isinstance(then, str) or then == now:
        return ""
    return (
        f"the map {trial.env_config.map} changed since the run stored it (sha256 {then[:12]}... then, "
        f"{now[:12]}... now)"
    )


def replay_trial(
    trial: StoredTrial,
    *,
    laser_rays: int | None = None,
    laser_stride: int = 1,
    world_map: Map | None = None,
) -> TrialReplay:
    """Run a stored trial again, record it and compare its metrics with the stored ones.

    A trial's outcome depends only on (policy, test set, scenario index, env config) and the code
    (socialzoo.bench.runner), so a replay reproduces it exactly while the code is unchanged; the
    store's config hash covers the code, and `StoredTrial.code_changed` says when it no longer matches.

    Args:
        trial: from `find_trials`.
        laser_rays: rays of the recorded scan (socialzoo.bench.replay.record_episode).
        laser_stride: steps between recorded scans (likewise).
        world_map: the loaded map of the trial's env config, if at hand.

    Raises:
        ValueError: the policy cannot be rebuilt with the stored parameters.
    """
    policy = trial.build_policy()
    m = world_map if world_map is not None else load_map(trial.env_config.map_name)
    trace = record_episode(
        trial.env_config,
        trial.scenario(m),
        policy,
        label=f"{trial.policy} (stored #{trial.index})",
        laser_rays=laser_rays,
        laser_stride=laser_stride,
        world_map=m,
    )
    return TrialReplay(
        trial, trace, compare_metrics(trial.metrics, trace.metrics), trial.code_changed(policy)
    )
