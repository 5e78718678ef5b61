"""The demonstration file format: (obs, action, next_obs, reward, terminated, truncated, episode)
transitions of a demonstrating policy in a compressed .npz file, with a JSON metadata entry.

A recording is written in chunks of episodes as it goes (FILE.parts/chunk_NNNNN.npz plus
index.json); when every chunk is there they are merged into FILE and the parts are removed.
This module reads both forms, for the imitation baselines; the recorder that writes them is
socialzoo.bench.demonstrations.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

DEMO_FORMAT = "socialzoo-demos/1"
# Per-transition arrays of a recording, in order.
TRANSITION_KEYS = ("obs", "action", "next_obs", "reward", "terminated", "truncated", "episode")
# Per-episode arrays.
EPISODE_KEYS = ("episode_ids", "episode_seeds", "episode_lengths")


class DemonstrationError(Exception):
    """A recording that cannot be resumed or read: another config, or damaged files."""


def parts_dir(path: str | Path) -> Path:
    """Where the chunks of the recording `path` live while it is being written."""
    path = Path(path)
    return path.with_name(path.name + ".parts")


def read_parts(parts: Path) -> dict[str, np.ndarray]:
    """The finished chunks of a recording in progress, concatenated in chunk order.

    Args:
        parts: the recording's parts folder (parts_dir(path)).

    Returns:
        Arrays keyed by TRANSITION_KEYS and EPISODE_KEYS, as in load_demonstrations.

    Raises:
        DemonstrationError: no index.json, no finished chunk, or an unreadable chunk.
    """
    index_path = parts / "index.json"
    if not index_path.exists():
        raise DemonstrationError(f"{parts}: no index.json; not a demonstration recording")
    index = json.loads(index_path.read_text())
    chunks = []
    for name in sorted(index["chunks"]):
        try:
            with np.load(parts / name, allow_pickle=False) as f:
                chunks.append({k: f[k] for k in (*TRANSITION_KEYS, *EPISODE_KEYS)})
        except (OSError, ValueError, KeyError) as err:
            raise DemonstrationError(f"{parts / name}: unreadable demonstration chunk ({err})") from None
    if not chunks:
        raise DemonstrationError(f"{parts}: no finished chunk yet")
    return {k: np.concatenate([c[k] for c in chunks]) for k in (*TRANSITION_KEYS, *EPISODE_KEYS)}


def read_metadata(path: str | Path) -> dict[str, Any]:
    """The metadata dict of a demonstration file."""
    try:
        with np.load(path, allow_pickle=False) as f:
            return json.loads(str(f["metadata"]))
    except (OSError, ValueError, KeyError) as err:
        raise DemonstrationError(f"{path}: not a socialzoo demonstration file ({err})") from None


def load_demonstrations(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Read a demonstration file, or the finished chunks of one still being recorded.

    Returns:
        (arrays, metadata): arrays keyed by TRANSITION_KEYS (obs (N, D) float32, action (N,)
        int64, next_obs (N, D), reward (N,) float32, terminated (N,) bool, truncated (N,) bool,
        episode (N,) int64 scenario index) and EPISODE_KEYS (episode_ids, episode_seeds,
        episode_lengths, one entry per episode); metadata as written (config, env config, policy
        config, seeds, package version, observation and action names).

    Raises:
        DemonstrationError: neither the file nor its parts are readable.
    """
    path = Path(path)
    if path.exists():
        meta = read_metadata(path)
        with np.load(path, allow_pickle=False) as f:
            return {k: f[k] for k in (*TRANSITION_KEYS, *EPISODE_KEYS)}, meta
    parts = parts_dir(path)
    if not parts.exists():
        raise DemonstrationError(f"{path}: no such demonstration file (nor {parts})")
    arrays = read_parts(parts)
    return arrays, json.loads((parts / "index.json").read_text())["metadata"]
