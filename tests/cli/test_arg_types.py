"""The CLI's shared argument types (socialzoo.cli.arg_types)."""

import argparse

import pytest

from socialzoo.cli import main
from socialzoo.cli.arg_types import out_dir, out_file, out_path


def test_out_path_takes_a_path_whose_folders_can_be_made(tmp_path):
    assert out_path(str(tmp_path / "new" / "deeper" / "x.gif")) == tmp_path / "new" / "deeper" / "x.gif"
    assert out_path("episode.gif").name == "episode.gif"


def test_out_path_names_the_file_in_its_way(tmp_path):
    blocker = tmp_path / "results"
    blocker.write_text("a file, not a folder")
    with pytest.raises(
        argparse.ArgumentTypeError, match=r"cannot write .*results/run.*'.*results' is not a folder"
    ):
        out_path(str(blocker / "run" / "x.csv"))


def _refused_out(capsys, words, out):
    """The usage error (exit 2) of `socialzoo WORDS --out OUT`, whose --out cannot be written."""
    with pytest.raises(SystemExit) as exit_info:
        main([*words, "--out", str(out)])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "argument --out: cannot write" in err
    return err


@pytest.mark.parametrize(
    "words",
    [
        ("benchmark", "--trials", "1"),
        ("demos", "--episodes", "1"),
        ("demo",),
        ("replay",),
        ("suite",),
        ("crowdnav", "eval"),
        ("metrics", "log.json"),
        ("humans", "report"),
        ("reproduce",),
        ("train", "ppo"),
    ],
    ids=" ".join,
)
def test_every_out_is_checked_before_the_command_runs(tmp_path, capsys, words):
    # An --out under a file was a NotADirectoryError traceback, for demo and replay only after
    # the episode had run.
    blocker = tmp_path / "afile"
    blocker.write_text("")
    err = _refused_out(capsys, words, blocker / "out")
    assert "is not a folder" in err and "Traceback" not in err


@pytest.mark.parametrize(
    "words",
    [
        ("benchmark", "--trials", "1"),
        ("suite",),
        ("humans", "realism"),
        ("humans", "calibrate", "--model", "sf"),
        ("humans", "report"),
        ("reproduce",),
        ("train", "ppo"),
        ("train", "people-bc"),
    ],
    ids=" ".join,
)
def test_an_out_folder_that_is_a_file_is_a_usage_error(tmp_path, capsys, words):
    # A file named as the output folder passed out_path (its parent is a folder) and the command
    # ended in a FileExistsError traceback when it made the folder, for train after its setup.
    afile = tmp_path / "results"
    afile.write_text("")
    assert "it is a file, not a folder" in _refused_out(capsys, words, afile)
    assert out_path(str(afile)) == afile  # a file output may replace a file
    assert out_dir(str(tmp_path / "new")) == tmp_path / "new"


@pytest.mark.parametrize(
    "words",
    [
        ("demos", "--episodes", "1"),
        ("demo",),
        ("replay",),
        ("metrics", "log.json"),
        ("map", "import", "--walls", "walls.txt", "--name", "box"),
    ],
    ids=" ".join,
)
def test_an_out_file_that_is_a_folder_is_a_usage_error(tmp_path, capsys, words):
    # A folder named as the output file passed out_path and the command ended in an
    # IsADirectoryError traceback when it wrote the file, after the episode or the import had run.
    folder = tmp_path / "episode.html"
    folder.mkdir()
    assert "it is a folder, not a file" in _refused_out(capsys, words, folder)
    assert out_path(str(folder)) == folder  # an output folder may be one that is there
    assert out_file(str(tmp_path / "new.csv")) == tmp_path / "new.csv"


@pytest.mark.parametrize(
    "words",
    [
        ("demo", "--seed", "-1"),
        ("demo", "--stride", "0"),
        ("demo", "--max-frames", "0"),
        ("replay", "--seed", "-1"),
        ("map", "check", "gdc1", "--seed", "-1"),
        ("map", "check", "gdc1", "--drive", "-1"),
        ("map", "check", "gdc1", "--max-route", "-5"),
        ("map", "check", "gdc1", "--max-route", "nan"),
        ("humans", "realism", "--seed", "-1"),
        ("humans", "calibrate", "--seed", "-1"),
    ],
    ids=" ".join,
)
def test_a_bad_number_is_a_usage_error_naming_its_option(capsys, words):
    # These were numpy tracebacks (a negative seed, --drive -1), a ZeroDivisionError (--stride 0),
    # or taken as they came (--max-route -5 judged every route infeasible).
    with pytest.raises(SystemExit) as exit_info:
        main(list(words))
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert f"argument {words[-2]}: expected" in err and repr(words[-1]) in err
