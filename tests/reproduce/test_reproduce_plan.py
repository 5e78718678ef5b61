"""Settings, their hash and the part names."""

import pytest

from socialzoo.reproduce.plan import (
    PARTS,
    Settings,
    full_settings,
    parse_parts,
    quick_settings,
    settings_hash,
)


def test_hash_changes_with_what_is_stored_not_with_how():
    base = quick_settings()
    assert settings_hash(base) == settings_hash(quick_settings())
    assert settings_hash(base) != settings_hash(quick_settings(curve_trials=3))
    assert settings_hash(base) != settings_hash(quick_settings(lfd_overrides={"bc": {"epochs": 2}}))
    assert settings_hash(base) == settings_hash(quick_settings(workers=2, batch_size=4))
    assert settings_hash(base) != settings_hash(full_settings())


def test_full_settings_are_the_papers_protocol():
    s = full_settings()
    assert (s.rl_total_steps, s.rl_checkpoint_every, s.curve_trials) == (84_000, 2_000, 100)
    assert s.lfd_sizes == (155_400, 116_600, 77_700, 38_800, 3_500) and s.pips_steps == 3_500
    assert (s.performance_trials, s.transfer_trials, s.lfd_trials) == (2_000, 2_000, 100)
    assert s.lfd_largest == 155_400


def test_settings_round_trip_and_validation():
    s = quick_settings()
    assert Settings.from_json(s.to_json()) == s
    with pytest.raises(ValueError, match="curve_trials"):
        quick_settings(curve_trials=0)
    with pytest.raises(ValueError, match=r"rl_overrides.*'sac'"):
        quick_settings(rl_overrides={"sac": {}})
    with pytest.raises(ValueError, match="name"):
        Settings(name="medium")
    with pytest.raises(ValueError, match="unknown field"):
        Settings.from_json({"name": "full", "nope": 1})


def test_parse_parts():
    assert parse_parts(None) == PARTS
    assert parse_parts("lfd,demos") == ("demos", "lfd")
    assert parse_parts(["transfer"]) == ("transfer",)
    with pytest.raises(ValueError, match=r"'rl'.*demos, rl-curves, lfd, performance, transfer"):
        parse_parts("rl,lfd")


def test_seeds_and_checkpoint_choice_settings():
    s = full_settings(seeds=3, seed=4)
    assert s.seed_list == (4, 5, 6) and full_settings().seed_list == (0,)
    assert (s.select_trials, s.select_every, s.batch_size) == (100, 12_000, 256)
    assert settings_hash(full_settings(seeds=3)) != settings_hash(full_settings())
    # How many test scenarios the later seeds play extends a run, it does not start another.
    assert settings_hash(full_settings(seeds=3, seed_trials=1000)) == settings_hash(full_settings(seeds=3))
    assert Settings.from_json(s.to_json()) == s
    with pytest.raises(ValueError, match="select_every"):
        full_settings(select_every=3_000)  # not a multiple of 2,000
    with pytest.raises(ValueError, match="seeds"):
        full_settings(seeds=0)
    with pytest.raises(ValueError, match="seed_trials"):
        full_settings(seed_trials=0)


def test_seeds_on_the_command_line(tmp_path, capsys):
    from socialzoo.cli import main

    with pytest.raises(SystemExit) as stop:  # refused by argparse's type, as --workers 0 elsewhere
        main(["reproduce", "--out", str(tmp_path), "--seeds", "0"])
    assert stop.value.code == 2
    assert "--seeds" in capsys.readouterr().err and not any(tmp_path.iterdir())
    assert main(["reproduce", "--out", str(tmp_path), "--seed-trials", "0"]) == 2
    assert "seed_trials" in capsys.readouterr().err and not any(tmp_path.iterdir())
    assert main(["reproduce", "--out", str(tmp_path), "--workers", "0"]) == 2
    assert "workers" in capsys.readouterr().err and not any(tmp_path.iterdir())


def test_more_seed_trials_reuse_the_work_folder_and_record_the_new_count(tmp_path):
    import json

    from socialzoo.reproduce.ledger import Ledger

    first = Ledger(tmp_path, full_settings(seeds=5, seed_trials=1000))
    second = Ledger(tmp_path, full_settings(seeds=5))  # no SettingsMismatch: the same items
    assert second.work == first.work
    record = json.loads((second.work / "settings.json").read_text())
    assert record["settings"]["seed_trials"] is None and record["settings"]["seeds"] == 5
