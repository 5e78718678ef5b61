"""Recording demonstrations of an engineered policy (Ref by default) for the imitation baselines, chunk by chunk,
so that a long recording survives an interruption and resumes."""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import json
import logging
import os
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo import __version__
from socialzoo.agents import POLICIES, make_policy
from socialzoo.agents.base import policy_config as policy_config_of
from socialzoo.agents.demonstrations import (
    DEMO_FORMAT,
    TRANSITION_KEYS,
    DemonstrationError,
    parts_dir,
    read_index,
    read_metadata,
    read_parts,
)
from socialzoo.bench.experiment import source_digest
from socialzoo.bench.progress import progress_bar
from socialzoo.bench.runner import BatchedRunner, RunSpec, Trial, env_config_for
from socialzoo.core.files import write_json
from socialzoo.core.validation import check_int
from socialzoo.env.observation import describe_observation
from socialzoo.nav.subpolicies import ACTION_NAMES
from socialzoo.scenarios.scenario_sets import TestSet, evaluation_seeds

logger = logging.getLogger(__name__)

# Base seed of the demonstration scenarios; the test sets use 20220001 to 20220004.
DEMO_BASE_SEED = 20220100
# On a map without a registered test set 20220100 is its generated test set's
# (scenario_sets.CUSTOM_TEST_SEED): its demonstrations come from this base seed.
OTHER_MAP_DEMO_SEED = 20220200


@dataclass(frozen=True, kw_only=True)
class DemoConfig:
    """What to record.

    Demonstration scenarios come from their own seeds, disjoint from the benchmark's test sets.

    Attributes:
        policy: registry name of the demonstrating policy.
        policy_kwargs: its make_policy keyword arguments.
        map: map name; scenarios are drawn with the benchmark generator from their own seeds.
        episodes: number of episodes (scenarios 0 .. episodes - 1 of the demonstration set).
        base_seed: seed of the demonstration scenario set; None: DEMO_BASE_SEED, or on a map without
            a registered test set OTHER_MAP_DEMO_SEED (DEMO_BASE_SEED is that map's test set's). A
            base seed of one of the map's validation or test sets is refused (evaluation_seeds).
        chunk_episodes: episodes per chunk file.
        batch_size: env rows stepped together.
        env_overrides: EnvConfig.replace keywords (plain JSON), e.g. {"max_steps": 1600}.
    """

    policy: str = "ref"
    policy_kwargs: Mapping[str, Any] = field(default_factory=dict)
    map: str = "gdc1"
    episodes: int = 100
    base_seed: int | None = None
    chunk_episodes: int = 25
    batch_size: int = 64
    env_overrides: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.policy not in POLICIES:
            raise ValueError(
                f"DemoConfig.policy: unknown policy {self.policy!r}; known: {', '.join(sorted(POLICIES))}"
            )
        if not isinstance(self.map, str) or not self.map:
            raise ValueError(f"DemoConfig.map must be a map name, got {self.map!r}")
        reserved = evaluation_seeds(self.map)
        if self.base_seed is None:
            seed = DEMO_BASE_SEED if DEMO_BASE_SEED not in reserved else OTHER_MAP_DEMO_SEED
            object.__setattr__(self, "base_seed", seed)
        for name, low in (("episodes", 1), ("chunk_episodes", 1), ("batch_size", 1), ("base_seed", 0)):
            check_int("DemoConfig", name, getattr(self, name), low=low)
        if self.base_seed in reserved:
            raise ValueError(
                f"DemoConfig.base_seed {self.base_seed} is the base seed of a validation or test set of map "
                f"{self.map!r}: demonstrations are training data"
            )

    def to_json(self) -> dict[str, Any]:
        """The config as plain JSON values (written into the recording's metadata)."""
        return dataclasses.asdict(self) | {
            "policy_kwargs": dict(self.policy_kwargs),
            "env_overrides": dict(self.env_overrides),
        }

    def test_set(self) -> TestSet:
        """The demonstration scenarios as a TestSet (name "<map>-demos")."""
        assert self.base_seed is not None  # resolved in __post_init__
        return TestSet(self.map, self.base_seed, self.episodes, name=f"{Path(self.map).stem}-demos")


def _metadata(config: DemoConfig) -> dict[str, Any]:
    test_set = config.test_set()
    env = env_config_for(test_set, **dict(config.env_overrides))
    policy = make_policy(config.policy, **dict(config.policy_kwargs))
    policy_config = policy_config_of(policy)
    module_file = inspect.getsourcefile(type(policy))
    identity = {
        "code_sha256": source_digest((module_file,) if module_file else ()),
        "config": config.to_json(),
        "policy_config": policy_config,
        "env_config": env.to_dict(),
        "scenario_config": dataclasses.asdict(test_set.cfg),
    }
    digest = hashlib.sha256(json.dumps(identity, sort_keys=True, default=str).encode()).hexdigest()[:16]
    return {
        "format": DEMO_FORMAT,
        "package_version": __version__,
        "config_hash": digest,
        **identity,
        "test_set": {"name": test_set.name, "map": test_set.map_name, "base_seed": test_set.base_seed},
        "scenario_seeds": [test_set.seed(k) for k in range(config.episodes)],
        "observation_names": describe_observation(env.observation),
        "action_names": list(ACTION_NAMES),
    }


def _write_npz(path: Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Write a compressed .npz atomically (a killed write leaves no half file under `path`)."""
    tmp = path.with_name(path.name + ".tmp")
    with tmp.open("wb") as f:
        np.savez_compressed(f, **arrays)  # type: ignore[arg-type]  # numpy's stub reads **kwds as allow_pickle
    os.replace(tmp, path)


# The dtypes of a step's values, in the order _Recorder keeps them.
_DTYPES = dict(
    obs=np.float32, action=np.int64, next_obs=np.float32, reward=np.float32, terminated=bool, truncated=bool
)


class _Recorder:
    """Collects each row's transitions and closes an episode when its row finishes."""

    def __init__(self) -> None:
        self.rows: dict[int, list[tuple[Any, ...]]] = {}
        self.episodes: dict[int, dict[str, np.ndarray]] = {}

    def __call__(
        self, task: Any, row_trial: list[Any], obs: np.ndarray, actions: np.ndarray, result: Any
    ) -> None:
        for row, trial in enumerate(row_trial):
            if trial is None:
                continue
            self.rows.setdefault(row, []).append(
                (
                    obs[row, 0],
                    int(actions[row, 0]),
                    result.obs[row, 0].copy(),
                    float(result.reward[row, 0]),
                    bool(result.terminated[row, 0]),
                    bool(result.truncated[row, 0]),
                )
            )
            if task.core.done[row].all():
                columns = zip(*self.rows.pop(row), strict=True)
                self.episodes[trial.index] = {
                    key: np.array(column, dtype=dtype)
                    for (key, dtype), column in zip(_DTYPES.items(), columns, strict=True)
                }


def _chunk_arrays(
    episodes: Mapping[int, Mapping[str, np.ndarray]], seeds: list[int]
) -> dict[str, np.ndarray]:
    ids = sorted(episodes)
    out = {
        key: np.concatenate([episodes[i][key] for i in ids]) for key in TRANSITION_KEYS if key != "episode"
    }
    lengths = np.array([len(episodes[i]["action"]) for i in ids], dtype=np.int64)
    out["episode"] = np.repeat(np.array(ids, dtype=np.int64), lengths)
    out["episode_ids"] = np.array(ids, dtype=np.int64)
    out["episode_seeds"] = np.array([seeds[i] for i in ids], dtype=np.uint64)
    out["episode_lengths"] = lengths
    return out


def record_demonstrations(path: str | Path, config: DemoConfig, *, progress: bool = False) -> Path:
    """Record (or resume, or confirm) a demonstration file.

    Episodes run in chunks of config.chunk_episodes, batched; each finished chunk is written to
    FILE.parts/ and listed in its index.json at once. A rerun with the same config skips the
    chunks already written; once all are there they are merged into `path` and the parts are
    removed. Calling again when `path` is complete does nothing.

    The file format (and its reader) is socialzoo.agents.demonstrations.

    Args:
        path: the .npz file to produce.
        config: what to record.
        progress: show the recorded episodes (a bar on a terminal, lines in a log: bench.progress).

    Returns:
        `path`.

    Raises:
        DemonstrationError: `path` or its parts hold a recording of another config.
    """
    path = Path(path)
    meta = _metadata(config)
    if path.exists():
        existing = read_metadata(path)
        if existing.get("config_hash") != meta["config_hash"]:
            raise DemonstrationError(
                f"{path} holds a recording of another config (hash {existing.get('config_hash')!r}, "
                f"this one {meta['config_hash']!r}); choose another file or remove it"
            )
        logger.info("%s is complete; nothing to record", path)
        return path
    parts = parts_dir(path)
    parts.mkdir(parents=True, exist_ok=True)
    index_path = parts / "index.json"
    index = read_index(parts) if index_path.exists() else {"metadata": meta, "chunks": {}}
    if index["metadata"].get("config_hash") != meta["config_hash"]:
        raise DemonstrationError(
            f"{parts} holds a partial recording of another config; remove it or choose another file"
        )
    test_set = config.test_set()
    spec = RunSpec(
        test_sets={test_set.name: test_set},
        env_configs={test_set.name: env_config_for(test_set, **dict(config.env_overrides))},
        policies={config.policy: dict(config.policy_kwargs)},
        batch_size=config.batch_size,
    )
    seeds = meta["scenario_seeds"]
    num_chunks = -(-config.episodes // config.chunk_episodes)
    bar = progress_bar(config.episodes, "demonstrations", enabled=progress, unit="episode")
    try:
        for c in range(num_chunks):
            lo, hi = c * config.chunk_episodes, min((c + 1) * config.chunk_episodes, config.episodes)
            name = f"chunk_{c:05d}.npz"
            if name in index["chunks"] and (parts / name).exists():
                bar.update(hi - lo)
                continue
            recorder = _Recorder()
            BatchedRunner(spec).run(
                [Trial(config.policy, test_set.name, k) for k in range(lo, hi)],
                on_results=lambda batch: bar.update(len(batch)),
                on_step=recorder,
            )
            arrays = _chunk_arrays(recorder.episodes, seeds)
            arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
            _write_npz(parts / name, arrays)
            index["chunks"][name] = {"episodes": [lo, hi], "steps": len(arrays["action"])}
            write_json(index_path, index)
            logger.info("demonstrations: wrote %s (episodes %d-%d)", parts / name, lo, hi - 1)
    finally:
        bar.close()
    data = read_parts(parts)
    data["metadata"] = np.array(json.dumps(meta, sort_keys=True))
    _write_npz(path, data)
    shutil.rmtree(parts)
    logger.info("demonstrations: %s, %d episodes, %d steps", path, config.episodes, len(data["action"]))
    return path
