"""The demonstration file format: (obs, action, next_obs, reward, terminated, truncated, episode) transitions of a
demonstrating policy in a compressed .npz file, with a JSON metadata entry."""

from __future__ import annotations

import json
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.core.files import read_json

DEMO_FORMAT = "socialzoo-demos/1"
# Per-transition arrays of a recording, in order.
TRANSITION_KEYS = ("obs", "action", "next_obs", "reward", "terminated", "truncated", "episode")
# Per-episode arrays.
EPISODE_KEYS = ("episode_ids", "episode_seeds", "episode_lengths")


# What numpy and zipfile raise for a file that is not a whole, pickle-free .npz: EOFError (an empty
# or cut .npy), BadZipFile (a cut or foreign zip), zlib.error (damaged compressed data), ValueError
# (pickled objects refused, a bad .npy header), OSError (unreadable), KeyError (a missing array).
_NPZ_ERRORS = (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error)


class DemonstrationError(ValueError):
    """A recording that cannot be resumed or read: another config, or damaged files (random
    bytes, a truncated file, a file of another kind); or one a trainer cannot use as asked (fewer
    steps than asked, another demonstrator or observation layout). The message names the file."""


def parts_dir(path: str | Path) -> Path:
    """Where the chunks of the recording `path` live while it is being written.

    A recording is written in chunks of episodes as it goes (FILE.parts/chunk_NNNNN.npz plus index.json); when
    every chunk is there they are merged into FILE and the parts are removed.
    """
    path = Path(path)
    return path.with_name(path.name + ".parts")


def read_parts(parts: Path) -> dict[str, np.ndarray]:
    """The finished chunks of a recording in progress, concatenated in chunk order.

    Args:
        parts: the recording's parts folder (parts_dir(path)).

    Returns:
        Arrays keyed by TRANSITION_KEYS and EPISODE_KEYS, as in load_demonstrations.

    Raises:
        DemonstrationError: no index.json, an unreadable index.json, no finished chunk, or an
            unreadable chunk (naming the file).
    """
    index = read_index(parts)
    chunks = [_read_arrays(parts / name, "demonstration chunk") for name in sorted(index["chunks"])]
    if not chunks:
        raise DemonstrationError(f"{parts}: no finished chunk yet")
    return _concatenated(chunks, parts)


def read_index(parts: Path) -> dict[str, Any]:
    """The index.json of a recording in progress: {"metadata": {...}, "chunks": {name: {...}}}.

    Raises:
        DemonstrationError: no index.json, or one that is not such an object (naming the file).
    """
    index_path = parts / "index.json"
    if not index_path.exists():
        raise DemonstrationError(f"{parts}: no index.json; not a demonstration recording")
    index = read_json(index_path, "recording index", DemonstrationError, kind=dict)
    if not isinstance(index.get("metadata"), dict) or not isinstance(index.get("chunks"), dict):
        raise DemonstrationError(
            f"{index_path}: not a recording index (an object with 'metadata' and 'chunks' objects)"
        )
    return index


def _open_npz(path: Path, what: str) -> np.lib.npyio.NpzFile:
    """`path` opened as a pickle-free .npz archive."""
    try:
        data = np.load(path, allow_pickle=False)
    except _NPZ_ERRORS as err:
        raise DemonstrationError(f"{path}: not a readable {what} ({type(err).__name__}: {err})") from None
    if not isinstance(data, np.lib.npyio.NpzFile):
        raise DemonstrationError(f"{path}: a single .npy array, not a {what} (a .npz archive)")
    return data


def _read_arrays(path: Path, what: str) -> dict[str, np.ndarray]:
    """The TRANSITION_KEYS and EPISODE_KEYS arrays of one .npz file, checked to agree in length."""
    with _open_npz(path, what) as f:
        try:
            arrays = {k: f[k] for k in (*TRANSITION_KEYS, *EPISODE_KEYS)}
        except _NPZ_ERRORS as err:
            raise DemonstrationError(f"{path}: unreadable {what} ({type(err).__name__}: {err})") from None
    steps = {len(arrays[k]) if arrays[k].ndim else -1 for k in TRANSITION_KEYS}
    episodes = {len(arrays[k]) if arrays[k].ndim else -1 for k in EPISODE_KEYS}
    if len(steps) != 1 or len(episodes) != 1 or -1 in steps | episodes:
        raise DemonstrationError(f"{path}: {what} arrays of different lengths; a damaged file")
    return arrays


def _concatenated(chunks: list[dict[str, np.ndarray]], where: Path) -> dict[str, np.ndarray]:
    try:
        return {k: np.concatenate([c[k] for c in chunks]) for k in (*TRANSITION_KEYS, *EPISODE_KEYS)}
    except ValueError as err:  # chunks of another observation width
        raise DemonstrationError(f"{where}: chunks that do not fit together ({err})") from None


def read_metadata(path: str | Path) -> dict[str, Any]:
    """The metadata dict of a demonstration file.

    Raises:
        DemonstrationError: no such file, or not a socialzoo demonstration file (random bytes, a
            truncated file, a file of another kind); the message names the file.
    """
    path = Path(path)
    if not path.exists():
        raise DemonstrationError(f"{path}: no such demonstration file")
    with _open_npz(path, "socialzoo demonstration file") as f:
        try:
            meta = json.loads(str(f["metadata"]))
        except (*_NPZ_ERRORS, RecursionError) as err:  # RecursionError: JSON nested past Python's limit
            raise DemonstrationError(
                f"{path}: not a socialzoo demonstration file ({type(err).__name__}: {err})"
            ) from None
    if not isinstance(meta, dict):
        raise DemonstrationError(f"{path}: not a socialzoo demonstration file (metadata is not an object)")
    return meta


def load_demonstrations(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Read a demonstration file, or the finished chunks of one still being recorded.

    Returns:
        (arrays, metadata): arrays keyed by TRANSITION_KEYS (obs (N, D) float32, action (N,)
        int64, next_obs (N, D), reward (N,) float32, terminated (N,) bool, truncated (N,) bool,
        episode (N,) int64 scenario index) and EPISODE_KEYS (episode_ids, episode_seeds,
        episode_lengths, one entry per episode); metadata as written (config, env config, policy
        config, seeds, package version, observation and action names).

    Raises:
        DemonstrationError: neither the file nor its parts exist, or they are not readable (random
            bytes, a truncated file, a file of another kind); the message names the file.
    """
    path = Path(path)
    if path.exists():
        meta = read_metadata(path)
        return _read_arrays(path, "demonstration file"), meta
    parts = parts_dir(path)
    if not parts.exists():
        raise DemonstrationError(f"{path}: no such demonstration file (nor {parts})")
    arrays = read_parts(parts)
    return arrays, read_index(parts)["metadata"]
