"""The ETH/UCY fetcher (socialzoo.data.fetch) on small synthetic scenes: downloads from a local HTTP
server, copies from a folder, checksums (a wrong one leaves nothing in the cache), the cache folder,
and load_scene. Never touches the internet."""

import functools
import hashlib
import http.server
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from socialzoo.data import fetch
from socialzoo.data.fetch import (
    SCENES,
    ChecksumError,
    DownloadError,
    SceneFile,
    UnknownSceneError,
    check_recordings,
    data_dir,
    fetch_scenes,
    load_recording,
    load_scene,
)

# Synthetic stand-ins for the real files: one scene of one file, one of two (joined, as univ).
FILES = {
    "one/test/one.txt": "0\t1\t0.0\t0.0\n10\t1\t1.0\t0.0\n10\t2\t5.0\t5.0\n",
    "two/test/two_a.txt": "0\t1\t0.0\t0.0\n10\t1\t0.5\t0.0\n",
    "two/test/two_b.txt": "0\t1\t3.0\t3.0\n10\t1\t3.5\t3.0\n20\t1\t4.0\t3.0\n",
}


def _scenes(files=FILES):
    def entry(path):
        return SceneFile(path, hashlib.sha256(files[path].encode()).hexdigest())

    return {
        "one": (entry("one/test/one.txt"),),
        "two": (entry("two/test/two_a.txt"), entry("two/test/two_b.txt")),
    }


@pytest.fixture
def scenes(monkeypatch):
    """SCENES replaced by the synthetic scenes."""
    table = _scenes()
    monkeypatch.setattr(fetch, "SCENES", table)
    return table


def _write_tree(root, files=FILES):
    for path, text in files.items():
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_text(text)
    return root


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@pytest.fixture
def server(tmp_path, monkeypatch):
    """Base URL of a local HTTP server serving tmp_path/served (the synthetic files), stopped after."""
    for name in ("http_proxy", "https_proxy", "HTTP_PROXY", "HTTPS_PROXY", "ALL_PROXY", "all_proxy"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("NO_PROXY", "127.0.0.1,localhost")
    served = _write_tree(tmp_path / "served")
    handler = functools.partial(_QuietHandler, directory=str(served))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}/"
    httpd.shutdown()
    httpd.server_close()


def test_the_pinned_scenes():
    assert list(SCENES) == ["eth", "hotel", "univ", "zara1", "zara2"]
    assert [f.name for f in SCENES["univ"]] == ["students001.txt", "students003.txt"]
    for files in SCENES.values():
        for file in files:
            assert len(file.sha256) == 64 and int(file.sha256, 16) >= 0
            assert file.path.endswith(f"/test/{file.name}")
    assert fetch.COMMIT in fetch.BASE_URL and fetch.BASE_URL.startswith("https://")
    assert "Pellegrini" in fetch.CREDIT and "Lerner" in fetch.CREDIT and "Trajectron++" in fetch.CREDIT


def test_download_from_a_server(scenes, server, tmp_path):
    cache = tmp_path / "cache"
    got = fetch_scenes(base_url=server, cache=cache, progress=False)
    assert got == {"one": [cache / "one.txt"], "two": [cache / "two_a.txt", cache / "two_b.txt"]}
    assert sorted(p.name for p in cache.iterdir()) == ["one.txt", "two_a.txt", "two_b.txt"]
    assert (cache / "two_b.txt").read_text() == FILES["two/test/two_b.txt"]
    # Fetched files with the right checksum are kept: no server needed the second time.
    assert fetch_scenes(["two"], base_url="http://127.0.0.1:9/", cache=cache, progress=False) == {
        "two": got["two"]
    }


def test_a_wrong_checksum_leaves_the_cache_empty(scenes, server, tmp_path, monkeypatch):
    wrong = dict(scenes)
    wrong["two"] = (scenes["two"][0], SceneFile("two/test/two_b.txt", "0" * 64))
    monkeypatch.setattr(fetch, "SCENES", wrong)
    cache = tmp_path / "cache"
    cache.mkdir()
    with pytest.raises(ChecksumError, match=r"two_b.txt \(scene two\): SHA-256 [0-9a-f]{64}, expected 0{64}"):
        fetch_scenes(base_url=server, cache=cache, progress=False)
    assert list(cache.iterdir()) == []  # not even the right files fetched before it, nor a partial one
    made = tmp_path / "made" / "cache"
    with pytest.raises(ChecksumError):
        fetch_scenes(["two"], base_url=server, cache=made, progress=False)
    assert not made.exists()  # the folder this call made is gone too


def test_a_missing_file_on_the_server(scenes, server, tmp_path, monkeypatch):
    monkeypatch.setattr(fetch, "SCENES", {"gone": (SceneFile("gone/test/gone.txt", "0" * 64),)})
    cache = tmp_path / "cache"
    with pytest.raises(
        DownloadError, match=r"could not download http://127\.0\.0\.1:\d+/gone/test/gone\.txt"
    ):
        fetch_scenes(base_url=server, cache=cache, progress=False)
    assert not cache.exists()


def test_a_complete_cache_is_only_read(scenes, server, tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    got = fetch_scenes(base_url=server, cache=cache, progress=False)

    def read_only(*args, **kwargs):
        raise OSError(30, "Read-only file system", str(cache))

    # A shared cache mounted read-only: fetching what it holds already writes nothing, so succeeds.
    monkeypatch.setattr(fetch.tempfile, "TemporaryDirectory", read_only)
    assert fetch_scenes(base_url="http://127.0.0.1:9/", cache=cache, progress=False) == got
    (cache / "two_b.txt").unlink()
    with pytest.raises(OSError, match="Read-only"):
        fetch_scenes(["two"], base_url=server, cache=cache, progress=False)


def test_fetched_files_get_the_mode_of_a_new_file(scenes, server, tmp_path):
    umask = os.umask(0o022)
    try:
        fetch_scenes(["one"], base_url=server, cache=tmp_path / "cache", progress=False)
        fetch_scenes(
            ["two"], source_dir=_write_tree(tmp_path / "src"), cache=tmp_path / "cache", progress=False
        )
    finally:
        os.umask(umask)
    # Not pooch's 0o600 for a download: a cache shared by a group is readable by all of it.
    modes = {p.name: p.stat().st_mode & 0o777 for p in (tmp_path / "cache").iterdir()}
    assert modes == {"one.txt": 0o644, "two_a.txt": 0o644, "two_b.txt": 0o644}


def test_a_failed_fetch_keeps_what_another_fetch_put_in_its_new_folder(scenes, tmp_path, monkeypatch):
    cache = tmp_path / "cache"

    def download(scene, file, base_url, staged, progress):
        # Another fetch into the same new folder finished meanwhile; this one then fails.
        (cache / "two_a.txt").write_text(FILES["two/test/two_a.txt"])
        raise DownloadError(f"could not download {file.name}")

    monkeypatch.setattr(fetch, "_download", download)
    with pytest.raises(DownloadError):
        fetch_scenes(["one"], base_url="http://127.0.0.1:9/", cache=cache, progress=False)
    assert [p.name for p in cache.iterdir()] == ["two_a.txt"]


class _StallingHandler(http.server.BaseHTTPRequestHandler):
    """Sends the first bytes of a file, then nothing for a while: a fetch in the middle of a download."""

    def do_GET(self):
        self.send_response(200)
        self.send_header("Content-Length", "1000")
        self.end_headers()
        self.wfile.write(b"0" * 10)
        self.wfile.flush()
        time.sleep(5)

    def log_message(self, *args):
        pass


def test_a_killed_fetch_leaves_its_staging_folder_to_the_next_fetch(scenes, tmp_path, monkeypatch):
    monkeypatch.setenv("NO_PROXY", "127.0.0.1,localhost")
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _StallingHandler)
    threading.Thread(target=httpd.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True).start()
    cache = tmp_path / "cache"
    code = (
        "from socialzoo.data.fetch import fetch_scenes; "
        f"fetch_scenes(['hotel'], base_url='http://127.0.0.1:{httpd.server_address[1]}/', cache={str(cache)!r})"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    child = subprocess.Popen([sys.executable, "-c", code], env=env)
    try:
        deadline = time.monotonic() + 60
        while not list(cache.glob(".fetching-*/*")) and time.monotonic() < deadline:
            time.sleep(0.05)  # until the download has begun in the staging folder
    finally:
        child.kill()  # SIGKILL: no cleanup runs
        child.wait()
        httpd.shutdown()
        httpd.server_close()
    assert [p.name.startswith(".fetching-") for p in cache.iterdir()] == [True]
    _write_tree(tmp_path / "source")
    fetch_scenes(["one"], source_dir=tmp_path / "source", cache=cache, progress=False)
    assert [p.name for p in cache.iterdir()] == ["one.txt"]


def test_only_staging_folders_whose_fetch_is_gone_are_removed(tmp_path):
    ended = subprocess.Popen([sys.executable, "-c", ""])
    ended.wait()
    running = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    host, old = fetch._host(), time.time() - fetch.STALE_STAGING_SECONDS - 60
    names = {
        f".fetching-{os.getpid()}-{host}-abc123": False,  # this process: a fetch in another thread
        f".fetching-{running.pid}-{host}-def456": False,  # a concurrent fetch
        f".fetching-{ended.pid}-{host}-ghi789": True,  # killed: its process is gone
        ".fetching-12-another.host-jkl012": False,  # another machine's fetch, recently active
        ".fetching-13-another.host-mno345": True,  # another machine's, untouched for long
        ".fetching-pqr678": False,  # named before pid and host: recent
        ".fetching-stu901": True,  # and old
    }
    try:
        for name, stale in names.items():
            (tmp_path / name).mkdir()
            (tmp_path / name / "part.txt").write_text("0")
            if stale and f"-{host}-" not in name:  # left untouched for longer than the limit
                for path in (tmp_path / name / "part.txt", tmp_path / name):
                    os.utime(path, (old, old))
        (tmp_path / "one.txt").write_text("kept")
        removed = fetch.remove_stale_staging(tmp_path)
    finally:
        running.kill()
        running.wait()
    assert sorted(p.name for p in removed) == sorted(name for name, stale in names.items() if stale)
    kept = {name for name, stale in names.items() if not stale} | {"one.txt"}
    assert {p.name for p in tmp_path.iterdir()} == kept
    assert fetch.remove_stale_staging(tmp_path / "missing") == []


def test_an_unknown_scene_fetches_nothing(scenes, tmp_path):
    cache = tmp_path / "cache"
    with pytest.raises(UnknownSceneError, match=r"unknown scene\(s\) 'three'; known: one, two"):
        fetch_scenes(["one", "three"], base_url="http://127.0.0.1:9/", cache=cache)
    assert not cache.exists()
    with pytest.raises(ValueError, match="known: one, two"):
        load_scene("three", cache=cache)


def test_copy_from_a_folder(scenes, tmp_path):
    source = tmp_path / "elsewhere"
    # Found by name anywhere below the folder; a same-named file with other bytes is passed over.
    (source / "deep" / "er").mkdir(parents=True)
    (source / "a").mkdir()
    (source / "a" / "one.txt").write_text("not it\n")
    (source / "deep" / "er" / "one.txt").write_text(FILES["one/test/one.txt"])
    cache = tmp_path / "cache"
    assert fetch_scenes(["one"], source_dir=source, cache=cache, progress=False) == {
        "one": [cache / "one.txt"]
    }
    assert (cache / "one.txt").read_text() == FILES["one/test/one.txt"]


def test_copy_checks_checksums_and_presence(scenes, tmp_path):
    source = tmp_path / "elsewhere"
    source.mkdir()
    (source / "one.txt").write_text("0\t1\t0.0\t0.0\n")
    cache = tmp_path / "cache"
    with pytest.raises(ChecksumError, match=f"no one.txt below {source} has the pinned SHA-256"):
        fetch_scenes(["one"], source_dir=source, cache=cache)
    with pytest.raises(FileNotFoundError, match=f"two_a.txt \\(scene two\\) is nowhere below {source}"):
        fetch_scenes(["two"], source_dir=source, cache=cache)
    with pytest.raises(FileNotFoundError, match="not a folder"):
        fetch_scenes(source_dir=source / "absent", cache=cache)
    assert not cache.exists()


def test_load_scene_reads_and_joins(scenes, tmp_path):
    cache = tmp_path / "cache"
    with pytest.raises(FileNotFoundError, match=r"scene 'one' is not fetched .*socialzoo data fetch eth-ucy"):
        load_scene("one", cache=cache)
    fetch_scenes(source_dir=_write_tree(tmp_path / "src"), cache=cache, progress=False)
    one = load_scene("one", cache=cache)
    assert (one.name, one.dt, one.num_frames, len(one.tracks)) == ("one", 0.4, 2, 2)
    two = load_scene("two", cache=cache)
    # two_a: frames 0..1; 10 empty frames; two_b: frames 12..14, its person 1 renumbered 2
    assert (two.name, two.num_frames) == ("two", 15)
    assert [(t.person, t.first_frame, t.last_frame) for t in two.tracks] == [(1, 0, 1), (2, 12, 14)]
    np.testing.assert_array_equal(two.grid([1], first=12, last=12), [[[3.0, 3.0]]])
    (cache / "two_b.txt").write_text("0\t1\t0\t0\n")
    with pytest.raises(ChecksumError, match="fetch it again"):
        load_scene("two", cache=cache)


def test_recordings_are_scenes_or_track_files(scenes, tmp_path):
    cache = tmp_path / "cache"
    fetch_scenes(source_dir=_write_tree(tmp_path / "src"), cache=cache, progress=False)
    mine = tmp_path / "mine.txt"
    mine.write_text(FILES["two/test/two_b.txt"])
    # Scenes first, in SCENES order, then the files as given.
    assert check_recordings([str(mine), "two", "one"]) == ["one", "two", str(mine)]
    assert check_recordings(["two", f"other={mine}"]) == ["two", f"other={mine}"]
    np.testing.assert_array_equal(
        load_recording("one", cache=cache).grid(), load_scene("one", cache=cache).grid()
    )
    own = load_recording(str(mine))
    assert (own.name, own.num_frames, own.source) == ("mine", 3, str(mine))
    assert load_recording(f"other={mine}").name == "other"
    with pytest.raises(UnknownSceneError, match=r"'nowhere.txt' is neither a scene nor a track file"):
        check_recordings(["one", "nowhere.txt"])
    with pytest.raises(UnknownSceneError, match=r"'x=nowhere.txt' is neither"):
        load_recording("x=nowhere.txt")
    with pytest.raises(ValueError, match=r"two recordings named 'one': name them NAME=PATH"):
        check_recordings(["one", f"one={mine}"])
    with pytest.raises(ValueError, match="at least one"):
        check_recordings([])


def test_data_dir(monkeypatch, tmp_path):
    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path / "mine"))
    assert data_dir() == tmp_path / "mine"
    monkeypatch.delenv("SOCIALZOO_DATA_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert data_dir().parts[-2:] == ("socialzoo", "eth-ucy")


def test_a_cache_folder_given_with_a_tilde_is_below_home(scenes, server, tmp_path, monkeypatch):
    # `SOCIALZOO_DATA_DIR="~/data"` and `--cache=~/data` reach us unexpanded; pooch would expand
    # the ~ while we did not, so its download landed in one folder and our check looked in another.
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SOCIALZOO_DATA_DIR", "~/mine")
    assert data_dir() == tmp_path / "home" / "mine"
    assert data_dir("~/other") == tmp_path / "home" / "other"
    got = fetch_scenes(["one"], base_url=server, progress=False)
    assert got == {"one": [tmp_path / "home" / "mine" / "one.txt"]}
    assert load_scene("one").num_frames == 2
    _write_tree(tmp_path / "home" / "src")
    fetch_scenes(["two"], source_dir="~/src", cache="~/other", progress=False)
    assert load_scene("two", cache="~/other").name == "two"
    assert not (tmp_path / "~").exists()
