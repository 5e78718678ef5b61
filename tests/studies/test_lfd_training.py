"""The LfD experiment's training: one run per (algorithm, size) in its own folder, all from one
recording, each skipped once finished."""

import pytest

from socialzoo.studies.lfd import find_lfd_policies, lfd_policy_file
from socialzoo.studies.lfd_training import LfdTrainConfig, train_lfd

SMALL_BC = {"hidden": [16], "epochs": 1, "min_updates": 20, "batch_size": 64, "checkpoint_every": 20}


def test_each_size_gets_its_own_run_and_a_rerun_repeats_nothing(small_demos, tmp_path):
    config = LfdTrainConfig(
        demos=small_demos, root=tmp_path, algos=("bc",), sizes=(1_500, 500), overrides={"bc": SMALL_BC},
        progress=False,
    )  # fmt: skip
    files = train_lfd(config)
    assert files == {("bc", s): lfd_policy_file(tmp_path, "bc", s) for s in (1_500, 500)}
    assert find_lfd_policies(tmp_path) == files
    stamps = {k: p.stat().st_mtime_ns for k, p in files.items()}
    assert train_lfd(config) == files
    assert {k: p.stat().st_mtime_ns for k, p in files.items()} == stamps
    assert config.args("bc", 500).steps == 500 and config.args("bc", 500).hidden == (16,)


def test_bad_configs_fail_before_training(small_demos, tmp_path):
    with pytest.raises(ValueError, match="unknown trainer 'nope'"):
        LfdTrainConfig(demos=small_demos, root=tmp_path, algos=("nope",))
    with pytest.raises(ValueError, match=r"unknown argument\(s\) \['lr_typo'\]"):
        LfdTrainConfig(demos=small_demos, root=tmp_path, overrides={"bc": {"lr_typo": 1.0}})
    with pytest.raises(ValueError, match="trainers not run"):
        LfdTrainConfig(demos=small_demos, root=tmp_path, algos=("bc",), overrides={"gail": {}})
    # A bool is no episode count (True passed as 1 before).
    with pytest.raises(ValueError, match=r"LfdTrainConfig\.demo_episodes must be an int >= 1, got True"):
        LfdTrainConfig(demos=small_demos, root=tmp_path, demo_episodes=True)
