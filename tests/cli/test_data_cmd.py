"""`socialzoo data fetch eth-ucy` and `socialzoo data list` on small synthetic scenes copied from a
folder (--from): the credit printed, the table, and bad input a named error (exit 2) with nothing
left in the cache."""

import hashlib
import os

import pytest

from socialzoo.cli import main
from socialzoo.data import fetch
from socialzoo.data.fetch import SceneFile

FILES = {
    "one.txt": "0\t1\t0.0\t0.0\n10\t1\t1.0\t0.0\n10\t2\t5.0\t5.0\n20\t2\t5.0\t6.0\n",
    "two_a.txt": "0\t1\t0.0\t0.0\n10\t1\t0.5\t0.0\n",
    "two_b.txt": "0\t1\t3.0\t3.0\n10\t1\t3.5\t3.0\n",
}


@pytest.fixture
def source(tmp_path, monkeypatch):
    """A folder holding the synthetic scenes' files, and SCENES replaced by them."""

    def entry(name):
        return SceneFile(f"x/test/{name}", hashlib.sha256(FILES[name].encode()).hexdigest())

    monkeypatch.setattr(
        fetch, "SCENES", {"one": (entry("one.txt"),), "two": (entry("two_a.txt"), entry("two_b.txt"))}
    )
    folder = tmp_path / "from" / "sub"
    folder.mkdir(parents=True)
    for name, text in FILES.items():
        (folder / name).write_text(text)
    return folder.parent


def test_fetch_then_list(source, tmp_path, capsys):
    cache = tmp_path / "cache"
    assert main(["data", "list", "--cache", str(cache)]) == 0
    out = capsys.readouterr().out
    assert f"cache: {cache}" in out and "one     no" in out and "two     no" in out
    assert f"`socialzoo data fetch eth-ucy --cache {cache}`" in out

    assert (
        main(["data", "fetch", "eth-ucy", "--scenes", "one", "--from", str(source), "--cache", str(cache)])
        == 0
    )
    out = capsys.readouterr().out
    assert "Pellegrini" in out and "Crowds by example" in out and "Trajectron++" in out
    assert "one    one.txt" in out
    assert sorted(p.name for p in cache.iterdir()) == ["one.txt"]

    assert main(["data", "list", "--cache", str(cache)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].split() == ["scene", "fetched", "tracks", "frames", "duration", "at", "once"]
    # one: 2 tracks, 3 frames = 0.8 s, both people on frame 1
    assert lines[2].split() == ["one", "yes", "2", "3", "0.8", "s", "2"]
    assert lines[3].split() == ["two", "no"]

    assert main(["data", "fetch", "eth-ucy", "--from", str(source), "--cache", str(cache)]) == 0
    capsys.readouterr()
    assert main(["data", "list", "--cache", str(cache)]) == 0
    # two: 2 + 10 + 2 frames joined, one person at a time
    assert capsys.readouterr().out.splitlines()[3].split() == ["two", "yes", "2", "14", "5.2", "s", "1"]


def test_a_wrong_file_is_refused_and_nothing_cached(source, tmp_path, capsys):
    (source / "sub" / "two_b.txt").write_text("0\t1\t0\t0\n")
    cache = tmp_path / "cache"
    assert main(["data", "fetch", "eth-ucy", "--from", str(source), "--cache", str(cache)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo data fetch: error: ") and "Traceback" not in err
    assert "no two_b.txt below" in err and "pinned SHA-256" in err
    assert not cache.exists()


def test_an_unknown_scene_is_a_usage_error(source, tmp_path, capsys):
    cache = tmp_path / "cache"
    with pytest.raises(SystemExit) as info:
        main(["data", "fetch", "eth-ucy", "--scenes", "one,three", "--cache", str(cache)])
    assert info.value.code == 2
    assert "unknown scene(s) 'three'; known: one, two" in capsys.readouterr().err
    assert not cache.exists()
    with pytest.raises(SystemExit):
        main(["data", "fetch", "other-data", "--cache", str(cache)])
    assert "invalid choice: 'other-data'" in capsys.readouterr().err


def test_a_changed_cached_file_is_reported(source, tmp_path, capsys):
    cache = tmp_path / "cache"
    assert main(["data", "fetch", "eth-ucy", "--from", str(source), "--cache", str(cache)]) == 0
    (cache / "one.txt").write_text("0\t1\t0\t0\n")
    capsys.readouterr()
    assert main(["data", "list", "--cache", str(cache)]) == 2
    out = capsys.readouterr().out
    assert "one     broken" in out and "fetch it again" in out


def test_a_reader_that_leaves_early_ends_the_command_quietly(tmp_path):
    # `socialzoo data list | head -1` ended in a BrokenPipeError traceback (any command's output).
    import subprocess
    import sys

    command = [sys.executable, "-m", "socialzoo", "data", "list"]
    env = {**os.environ, "SOCIALZOO_DATA_DIR": str(tmp_path)}
    listing = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    listing.stdout.close()  # the reader leaves before the first line
    _, err = listing.communicate(timeout=120)
    assert b"Traceback" not in err and listing.returncode in (0, 141)
