"""`socialzoo train`: inputs the trainer finds bad are usage errors (exit status 2) naming them."""

import pytest

from socialzoo.cli import main
from socialzoo.train.ppo import PPOArgs
from socialzoo.train.run_dir import RunDir


def test_an_unknown_map_is_a_usage_error(tmp_path, capsys):
    argv = ["train", "ppo", "--out", str(tmp_path / "run"), "--map", "nomap", "--no-progress"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo train ppo: error: ") and "unknown map 'nomap'" in err


def test_a_missing_demonstration_file_is_a_usage_error(tmp_path, capsys):
    demos = tmp_path / "none.npz"
    assert main(["train", "bc", "--out", str(tmp_path / "run"), "--demos", str(demos), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo train bc: error: ") and str(demos) in err


def test_a_folder_holding_a_run_of_other_arguments_is_a_usage_error(tmp_path, capsys):
    # Found rerunning `socialzoo train ppo` into a finished run's folder with another --total-steps:
    # a RunDirError traceback, exit status 1.
    out = tmp_path / "run"
    RunDir(out, "ppo", PPOArgs(out=out, total_steps=4000))
    before = (out / "run.json").read_text()
    assert main(["train", "ppo", "--out", str(out), "--total-steps", "2000", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo train ppo: error: ") and "total_steps differ" in err
    assert (out / "run.json").read_text() == before


@pytest.mark.parametrize("steps", ["0", "x"])
def test_bad_numbers_are_usage_errors(tmp_path, steps):
    with pytest.raises(SystemExit) as exit_:
        code = main(["train", "ppo", "--out", str(tmp_path), "--total-steps", steps])
        raise SystemExit(code)
    assert exit_.value.code == 2
