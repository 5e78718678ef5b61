"""The CrowdNav task's episodes in the benchmark's results store (socialzoo.bench.store).

`evaluate_crowd_stored` plays only the cases a store does not hold yet for a policy and writes each
episode as it ends, so an interrupted evaluation resumes where it stopped and a repeated one reads
instead of playing. An episode is keyed like a benchmark trial: (policy spec, split, case index,
config hash), where the hash covers everything that decides the episode besides its case: the
task's config, the simulation's source code and the policy's module, the policy's parameters and
its file's digest. A retrained file under the same path therefore gets new episodes, never the old
file's.
"""

from __future__ import annotations

import hashlib
import inspect
import json
from pathlib import Path
from typing import Any

from socialzoo.bench.crowd_eval import CrowdEvaluation, evaluate_crowd, summarize_crowd
from socialzoo.env.crowd_config import CrowdNavConfig
from socialzoo.nav.crowd_cases import ARENA_MAP, SPLIT_SIZE, Split

STORE_FILE = "results.sqlite"


def crowd_config_hash(config: CrowdNavConfig, split: Split, spec: str, policy: Any) -> str:
    """16 hex digits naming everything that decides an episode of `policy` besides its case, as
    socialzoo.bench.experiment.config_hash does for a benchmark trial: the task, the simulation's
    code and the policy's module, the policy's parameters (its config()) and its file's digest."""
    from socialzoo.agents import policy_file as file_of
    from socialzoo.agents.base import policy_config
    from socialzoo.bench.experiment import file_digest, source_digest

    module_file = inspect.getsourcefile(type(policy))
    policy_file = file_of(spec)
    payload = {
        "task": config.to_dict(),
        "split": split,
        "code_sha256": source_digest((module_file,) if module_file else ()),
        "policy": {
            "spec": spec,
            "config": policy_config(policy),
            "file_sha256": file_digest(policy_file) if policy_file is not None else None,
        },
    }
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def evaluate_crowd_stored(
    store_path: Path,
    spec: str,
    policy: Any,
    config: CrowdNavConfig,
    split: Split = "test",
    cases: int | None = None,
    batch_size: int = 100,
) -> tuple[CrowdEvaluation, int]:
    """`evaluate_crowd` of `policy` (named `spec`) on the first `cases` cases, playing only those the
    store at store_path lacks and storing each episode as it ends.

    Returns:
        (the evaluation of all the cases, stored and new, in case order; how many were played now).

    Raises:
        socialzoo.bench.store.StoreError: store_path is not a usable results store.
        ValueError: as evaluate_crowd.
    """
    from socialzoo import __version__
    from socialzoo.bench.store import TRIAL_COLUMNS, ResultsStore
    from socialzoo.env.crowd_source import CrowdCaseSource

    if split not in SPLIT_SIZE:
        raise ValueError(f"evaluate_crowd_stored: split must be 'val' or 'test', got {split!r}")
    total = SPLIT_SIZE[split] if cases is None else cases
    config_hash = crowd_config_hash(config, split, spec, policy)
    test_set = f"crowdnav-{split}"
    where = config.map or ARENA_MAP
    with ResultsStore(store_path) as store:
        store.register_config(config_hash, {"task": config.to_dict(), "split": split, "policy": spec})
        have = store.stored_indices(spec, test_set, config_hash)
        todo = [k for k in range(total) if k not in have]
        seeds = {}
        if todo:
            scenarios = CrowdCaseSource(config, 1).fixed(split, todo)
            seeds = {k: int(s.seed) for k, s in zip(todo, scenarios, strict=True)}

        def store_episodes(episodes: list[dict[str, Any]]) -> None:
            store.add(
                {
                    "policy": spec,
                    "map": where,
                    "test_set": test_set,
                    "scenario_index": e["case"],
                    "seed": seeds[e["case"]],
                    "config_hash": config_hash,
                    "package_version": __version__,
                    "metrics": {k: float(v) for k, v in e.items() if k != "case"},
                }
                for e in episodes
            )

        if todo:
            evaluate_crowd(policy.act, config, split, total, batch_size, indices=todo, on_episodes=store_episodes)
        rows = store.rows(policy=spec, test_set=test_set, config_hash=config_hash, indices=range(total))
    episodes = [
        {"case": int(r["scenario_index"]), **{k: float(v) for k, v in r.items() if k not in TRIAL_COLUMNS}}
        for r in rows
    ]
    return CrowdEvaluation(split, episodes, summarize_crowd(episodes, config.time_step)), len(todo)
