"""`socialzoo humans compare|select|report`: one command for the people, its subcommands listed and
run with small options, and the former top-level names refused with the command to call instead."""

import json

import pytest

from socialzoo.cli import MOVED, main


def test_humans_help_lists_its_subcommands(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["humans", "--help"])
    assert exit_info.value.code == 0
    listing = capsys.readouterr().out
    for name in ("compare", "select", "report"):
        assert f"\n    {name} " in listing


@pytest.mark.parametrize("old", sorted(MOVED))
def test_former_names_fail_naming_the_new_command(old, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([old, "--help"])
    assert exit_info.value.code == 2
    assert f"'{old}' is now 'socialzoo {MOVED[old]}'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--help"])
    assert old not in capsys.readouterr().out


def test_humans_compare_runs(rooms_map_path, walker_policy_path, tmp_path, capsys):
    out = tmp_path / "cmp"
    small = ["--trials", "2", "--max-steps", "60", "--workers", "1", "--batch-size", "2"]
    argv = ["humans", "compare", "--humans", f"learned:{walker_policy_path}", "--maps", str(rooms_map_path)]
    assert main([*argv, *small, "--no-figures", "--no-progress", "--out", str(out)]) == 0
    assert "rooms: reach-rate target" in capsys.readouterr().out
    assert {p.name for p in out.iterdir()} >= {"comparison.md", "comparison.csv"}


def test_humans_select_runs(write_walker, tmp_path, capsys):
    run = tmp_path / "run"
    (run / "checkpoints").mkdir(parents=True)
    (run / "run.json").write_text(json.dumps({"args": {"map": "open_room"}}))
    write_walker(run / "checkpoints" / "step_000001000.humans.safetensors", speed=3.0)
    small = ["--trials", "2", "--max-steps", "60", "--workers", "1", "--batch-size", "2"]
    assert main(["humans", "select", "--run", str(run), *small, "--no-progress"]) == 0
    assert "chose " in capsys.readouterr().out
    assert (run / "selection" / "humans.safetensors").is_file()


def test_humans_select_refuses_more_trials_than_the_validation_set_in_one_line(
    write_walker, tmp_path, capsys
):
    # Found with `socialzoo humans select --trials 1001`: a ValueError traceback (exit status 1), where
    # `socialzoo humans compare` gives the same refusal in one line (exit status 2).
    run = tmp_path / "run"
    (run / "checkpoints").mkdir(parents=True)
    (run / "run.json").write_text(json.dumps({"args": {"map": "open_room"}}))
    write_walker(run / "checkpoints" / "step_000001000.humans.safetensors", speed=3.0)
    assert (
        main(["humans", "select", "--run", str(run), "--trials", "1001", "--workers", "1", "--no-progress"])
        == 2
    )
    err = capsys.readouterr().err
    assert err.startswith("socialzoo humans select: error: ") and "'open_room-val' holds only 1000" in err


def test_humans_compare_takes_the_shipped_humans_as_learned(tmp_path, capsys):
    """It took only learned:PATH, so the docs named socialzoo/agents/shipped/humans.safetensors,
    a path that exists only in a source checkout."""
    out = tmp_path / "cmp"
    small = ["--trials", "1", "--max-steps", "20", "--workers", "1", "--batch-size", "1"]
    argv = ["humans", "compare", "--humans", "learned", "--maps", "open_room", *small, "--no-figures"]
    assert main([*argv, "--no-progress", "--out", str(out)]) == 0, capsys.readouterr().err
    assert "open_room: reach-rate target" in capsys.readouterr().out
