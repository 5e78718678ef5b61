"""The demonstration file format: reading a file, or the finished parts of one in progress."""

import json

import numpy as np
import pytest

from socialzoo.agents.demonstrations import (
    EPISODE_KEYS,
    TRANSITION_KEYS,
    DemonstrationError,
    load_demonstrations,
    parts_dir,
    read_metadata,
)


def _chunk(episode_ids, steps_each):
    n = len(episode_ids) * steps_each
    return {
        "obs": np.zeros((n, 3), np.float32),
        "action": np.arange(n, dtype=np.int64),
        "next_obs": np.ones((n, 3), np.float32),
        "reward": np.zeros(n, np.float32),
        "terminated": np.zeros(n, bool),
        "truncated": np.zeros(n, bool),
        "episode": np.repeat(np.array(episode_ids, np.int64), steps_each),
        "episode_ids": np.array(episode_ids, np.int64),
        "episode_seeds": np.array(episode_ids, np.uint64) + 7,
        "episode_lengths": np.full(len(episode_ids), steps_each, np.int64),
    }


def test_finished_parts_are_read_in_chunk_order(tmp_path):
    path = tmp_path / "demos.npz"
    parts = parts_dir(path)
    parts.mkdir()
    np.savez_compressed(parts / "chunk_00001.npz", **_chunk([2], 4))
    np.savez_compressed(parts / "chunk_00000.npz", **_chunk([0, 1], 3))
    meta = {"format": "socialzoo-demos/1", "config_hash": "abc"}
    chunks = {"chunk_00000.npz": {}, "chunk_00001.npz": {}}
    (parts / "index.json").write_text(json.dumps({"metadata": meta, "chunks": chunks}))
    arrays, read_meta = load_demonstrations(path)
    assert set(arrays) == {*TRANSITION_KEYS, *EPISODE_KEYS}
    assert arrays["episode_ids"].tolist() == [0, 1, 2]
    assert arrays["episode"].tolist() == [0, 0, 0, 1, 1, 1, 2, 2, 2, 2]
    assert read_meta == meta


def test_a_missing_or_foreign_file_names_itself(tmp_path):
    with pytest.raises(DemonstrationError, match="no such demonstration file"):
        load_demonstrations(tmp_path / "nothing.npz")
    foreign = tmp_path / "foreign.npz"
    np.savez_compressed(foreign, x=np.zeros(2))
    with pytest.raises(DemonstrationError, match=r"foreign\.npz: not a socialzoo demonstration file"):
        read_metadata(foreign)
    parts_dir(tmp_path / "empty.npz").mkdir()
    with pytest.raises(DemonstrationError, match=r"no index\.json"):
        load_demonstrations(tmp_path / "empty.npz")
