"""The CrowdNav task's episodes in the benchmark's results store (socialzoo.bench.store).

`evaluate_crowd_stored` plays only the cases a store does not hold yet for a policy and writes each
episode as it ends, so an interrupted evaluation resumes where it stopped and a repeated one reads
instead of playing. An episode is keyed like a benchmark trial: (policy spec, split, case index,
config hash), where the hash covers everything that decides the episode besides its case: the
task's config, the simulation's source code and the policy's module, and the policy's parameters
(a learned policy's tensors, an engineered one's settings). A retrained file under the same path
therefore gets new episodes, never the old file's.
"""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import json
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.crowd_eval import CrowdEvaluation, evaluate_crowd, summarize_crowd
from socialzoo.env.crowd_config import CrowdNavConfig
from socialzoo.nav.crowd_cases import ARENA_MAP, SPLIT_SIZE, Split

STORE_FILE = "results.sqlite"


def _feed(digest: Any, value: Any) -> None:
    """Add a policy's state to a running sha256: arrays by dtype, shape and bytes; containers and
    dataclasses item by item; anything else by its repr."""
    if isinstance(value, np.ndarray):
        digest.update(f"array{value.dtype.str}{value.shape}".encode())
        digest.update(np.ascontiguousarray(value).tobytes())
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        _feed(digest, {f.name: getattr(value, f.name) for f in dataclasses.fields(value)})
    elif isinstance(value, dict):
        digest.update(b"{")
        for key in sorted(value, key=str):
            digest.update(repr(key).encode())
            _feed(digest, value[key])
        digest.update(b"}")
    elif isinstance(value, list | tuple):
        digest.update(b"[")
        for item in value:
            _feed(digest, item)
        digest.update(b"]")
    else:
        digest.update(repr(value).encode())


def policy_digest(policy: Any) -> str:
    """sha256 of a CrowdNav policy's state (its attributes, arrays included)."""
    digest = hashlib.sha256(type(policy).__qualname__.encode())
    _feed(digest, {k: v for k, v in vars(policy).items() if not k.startswith("_")})
    return digest.hexdigest()


def crowd_config_hash(config: CrowdNavConfig, split: Split, spec: str, policy: Any) -> str:
    """16 hex digits naming everything that decides an episode of `policy` besides its case."""
    from socialzoo.bench.experiment import source_digest

    module_file = inspect.getsourcefile(type(policy))
    payload = {
        "task": config.to_dict(),
        "split": split,
        "code_sha256": source_digest((module_file,) if module_file else ()),
        "policy": {"spec": spec, "state_sha256": policy_digest(policy)},
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
