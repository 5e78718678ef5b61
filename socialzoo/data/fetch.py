"""The ETH/UCY pedestrian recordings: fetched from a pinned public copy (or a local folder) into a
cache outside the repository, every file checked against its SHA-256, and read as Recordings."""

from __future__ import annotations

import contextlib
import hashlib
import logging
import os
import re
import shutil
import socket
import tempfile
import time
from collections.abc import Iterable
from pathlib import Path
from typing import NamedTuple

from socialzoo.data.tracks import Recording, join, read_tracks

logger = logging.getLogger(__name__)

COMMIT = "1031c7bd1a444273af378c1ec1dcca907ba59830"
BASE_URL = f"https://raw.githubusercontent.com/StanfordASL/Trajectron-plus-plus/{COMMIT}/experiments/pedestrians/raw/"
# The cache folder when SOCIALZOO_DATA_DIR is not set: platformdirs.user_cache_dir("socialzoo")/CACHE_NAME.
ENV_VAR, CACHE_NAME = "SOCIALZOO_DATA_DIR", "eth-ucy"
# A fetch stages its files in CACHE/.fetching-<pid>-<host>-<random>/; a later fetch removes one whose
# owner is gone: a process of this host that no longer runs, or, for a folder of another host or one
# named before the pid and host were in the name, a folder untouched for STALE_STAGING_SECONDS.
STAGING_PREFIX = ".fetching-"
STALE_STAGING_SECONDS = 24 * 3600
_STAGING_NAME = re.compile(r"\.fetching-(\d+)-(.*)-[a-z0-9_]+")
# Empty frames between the files of a scene made of several (univ).
JOIN_GAP_FRAMES = 10
CREDIT = (
    "ETH (BIWI): S. Pellegrini, A. Ess, K. Schindler, L. van Gool, \"You'll never walk alone: modeling "
    'social behavior for multi-target tracking", ICCV 2009.\n'
    'UCY (univ, zara): A. Lerner, Y. Chrysanthou, D. Lischinski, "Crowds by example", Computer Graphics '
    "Forum (Eurographics) 2007.\n"
    "Files as prepared by Trajectron++ (T. Salzmann, B. Ivanovic, P. Chakravarty, M. Pavone, ECCV 2020) "
    "and Social GAN (A. Gupta et al., CVPR 2018)."
)


class SceneFile(NamedTuple):
    """One file of a scene: its path below BASE_URL (its name is the last part) and its SHA-256."""

    path: str
    sha256: str

    @property
    def name(self) -> str:
        """The file name, which it keeps in the cache."""
        return self.path.rpartition("/")[2]


# (path below BASE_URL, SHA-256) of every file; its scene is the path's first part.
_FILES = (
    ("eth/test/biwi_eth.txt", "cf8d3fd342a15f409ebc2a1fc76b91a0f06390bd21f1e11410f3859331ab082b"),
    ("hotel/test/biwi_hotel.txt", "9caa771bb9153d6b809dd0916b6f86761b641e6bbb15e766c1de3133fbbb7fcf"),
    ("univ/test/students001.txt", "a6d87f278d94136fe39b8be91555487a29ac77259ae403b9dba2d5c18caf7b5b"),
    ("univ/test/students003.txt", "e25798b660634330aa89f8bb259425de720e84d0873902726c1d1f4ccff21d6c"),
    ("zara1/test/crowds_zara01.txt", "1147a1962a09abfb86f28c6cddcac862e095a0cf129b3016385b69eacdd09d85"),
    ("zara2/test/crowds_zara02.txt", "8a649d0f8c9ae75c87c4d23a85f892786b0aa30266e996c7be03e69dafff22ff"),
)
# Scene -> its files, in the order they are joined.
SCENES: dict[str, tuple[SceneFile, ...]] = {
    scene: tuple(SceneFile(*f) for f in _FILES if f[0].partition("/")[0] == scene)
    for scene in dict.fromkeys(f[0].partition("/")[0] for f in _FILES)
}


class UnknownSceneError(ValueError):
    """A scene name that is not in SCENES (the message lists the known ones)."""


class ChecksumError(ValueError):
    """A file whose SHA-256 is not the pinned one (the message names the file, both hashes)."""


class DownloadError(OSError):
    """A file that could not be downloaded (the message names the URL and the cause)."""


def data_dir(cache: str | Path | None = None) -> Path:
    """The cache folder: `cache` when given, else $SOCIALZOO_DATA_DIR, else
    platformdirs.user_cache_dir("socialzoo")/eth-ucy; a leading ~ is the home folder (as pooch reads it)."""
    if cache is not None:
        return Path(cache).expanduser()
    if os.environ.get(ENV_VAR):
        return Path(os.environ[ENV_VAR]).expanduser()
    return user_cache() / CACHE_NAME


def user_cache() -> Path:
    """The user's own socialzoo cache folder, platformdirs.user_cache_dir("socialzoo")
    (~/.cache/socialzoo on Linux): the data cache's default home, and where what cannot be written into
    a read-only data cache goes (socialzoo.scenarios.recorded.RecordedScene.open_map)."""
    import platformdirs

    return Path(platformdirs.user_cache_dir("socialzoo"))


def sha256(path: str | Path) -> str:
    """The hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def check_scenes(scenes: Iterable[str] | None) -> list[str]:
    """The scene names asked for (all of SCENES when None), in SCENES order.

    Raises:
        UnknownSceneError: a name not in SCENES.
    """
    if scenes is None:
        return list(SCENES)
    asked = list(scenes)
    unknown = [s for s in asked if s not in SCENES]
    if unknown:
        raise UnknownSceneError(
            f"unknown scene(s) {', '.join(map(repr, unknown))}; known: {', '.join(SCENES)}"
        )
    return [s for s in SCENES if s in asked]


def fetch_scenes(
    scenes: Iterable[str] | None = None,
    *,
    source_dir: str | Path | None = None,
    base_url: str | None = None,
    cache: str | Path | None = None,
    progress: bool = True,
) -> dict[str, list[Path]]:
    """Bring the files of the scenes into the cache, each checked against its pinned SHA-256.

    A file already in the cache with the right checksum is kept (when all are, nothing is written,
    so a complete cache may be read-only). All-or-nothing: the files are
    gathered in a temporary folder inside the cache and moved in only when every one is right, so
    an error leaves nothing new in the cache (a cache folder made by this call is removed again,
    unless another fetch has put files in it meanwhile). The temporary folder of a fetch that was
    killed (SIGKILL, a machine that went down) is removed by the next fetch into the cache once its
    owner is gone (remove_stale_staging); a concurrent fetch's is never touched.

    Args:
        scenes: scene names (default: all of SCENES).
        source_dir: copy the files from this local folder, each found by its name anywhere below it
            (for machines without internet), instead of downloading them.
        base_url: download from here instead of BASE_URL (files at BASE/SCENE/test/NAME).
        cache: the cache folder (default: data_dir()).
        progress: log a line per file (INFO).

    Returns:
        scene -> the paths of its files in the cache, in joining order.

    Raises:
        UnknownSceneError: an unknown scene name (before anything is fetched).
        ChecksumError: a file with another SHA-256 than the pinned one.
        FileNotFoundError: source_dir is not a folder, or holds no file of a needed name.
        DownloadError: a download failed.
    """
    chosen = check_scenes(scenes)
    source = None if source_dir is None else Path(source_dir).expanduser()
    if source is not None and not source.is_dir():
        raise FileNotFoundError(f"--from {source}: not a folder")
    folder = data_dir(cache)
    remove_stale_staging(folder)
    result = {scene: [folder / file.name for file in SCENES[scene]] for scene in chosen}
    needed: list[tuple[str, SceneFile]] = []
    for scene in chosen:
        for file in SCENES[scene]:
            target = folder / file.name
            if target.is_file() and sha256(target) == file.sha256:
                if progress:
                    logger.info("%s: %s already in %s", scene, file.name, folder)
            else:
                needed.append((scene, file))
    if not needed:  # nothing written, so a complete cache may be read-only
        return result
    made = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    try:
        with tempfile.TemporaryDirectory(prefix=_staging_prefix(), dir=folder) as staging:
            for scene, file in needed:
                staged = Path(staging) / file.name
                if source is not None:
                    _copy(scene, file, source, staged, progress)
                else:
                    _download(scene, file, base_url or BASE_URL, staged, progress)
            # pooch downloads through a temporary file of mode 0o600: give every file the mode a new
            # file gets (a copy's), so a cache shared by a group is readable by it.
            umask = os.umask(0o022)
            os.umask(umask)
            for _, file in needed:
                staged = Path(staging) / file.name
                os.chmod(staged, 0o666 & ~umask)
                os.replace(staged, folder / file.name)
    except BaseException:
        if made:  # only when empty: another fetch into the same new folder may have moved files in
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    return result


def _host() -> str:
    """This machine's name as a file name may hold it."""
    return re.sub(r"[^A-Za-z0-9.]+", "_", socket.gethostname()) or "host"


def _staging_prefix() -> str:
    """The name of this process's staging folders, less the random end: its pid and host."""
    return f"{STAGING_PREFIX}{os.getpid()}-{_host()}-"


def _running(pid: int) -> bool:
    """Whether process `pid` of this machine runs (one of another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except OSError:  # no signals to send (a platform without them): count it as running
        return True
    return True


def remove_stale_staging(folder: str | Path) -> list[Path]:
    """Remove the staging folders in cache `folder` whose fetch is gone; returns those removed.

    A folder named by a process of this host goes when that process no longer runs; one of another
    host (a cache on a shared drive), or named before the pid and host were in the name, when nothing
    in it changed for STALE_STAGING_SECONDS. A live fetch's folder is kept. A folder that cannot be
    removed (a read-only cache) is left, without an error.
    """
    folder = Path(folder)
    removed: list[Path] = []
    try:
        entries = [p for p in folder.iterdir() if p.name.startswith(STAGING_PREFIX) and p.is_dir()]
    except OSError:  # no such folder yet, or not readable
        return removed
    host, now = _host(), time.time()
    for path in entries:
        named, stale = _STAGING_NAME.fullmatch(path.name), False
        if named and named[2] == host:
            stale = not _running(int(named[1]))
        else:
            with contextlib.suppress(OSError):  # gone meanwhile: nothing to do
                newest = max([path.stat().st_mtime, *(p.stat().st_mtime for p in path.iterdir())])
                stale = now - newest > STALE_STAGING_SECONDS
        if stale:
            shutil.rmtree(path, ignore_errors=True)
            if not path.exists():
                logger.info("removed %s, left by a fetch that was stopped", path)
                removed.append(path)
    return removed


def load_scene(name: str, cache: str | Path | None = None) -> Recording:
    """The recording of a fetched scene (a scene of several files joined, JOIN_GAP_FRAMES apart).

    Args:
        name: a scene of SCENES.
        cache: the cache folder (default: data_dir()).

    Raises:
        UnknownSceneError: an unknown scene (a ValueError listing the known ones).
        FileNotFoundError: the scene is not fetched.
        ChecksumError: a cached file was changed since it was fetched.
        TrackFileError: a file cannot be read.
    """
    (scene,) = check_scenes([name])
    folder = data_dir(cache)
    recordings = []
    for file in SCENES[scene]:
        path = folder / file.name
        if not path.is_file():
            hint = "" if cache is None else f" --cache {folder}"
            raise FileNotFoundError(
                f"scene {scene!r} is not fetched ({path} is missing): run `socialzoo data fetch eth-ucy{hint}`"
            )
        _verify(path, file, f"{path} (scene {scene}; fetch it again)")
        recordings.append(read_tracks(path, layout="trajectron", name=scene))
    return recordings[0] if len(recordings) == 1 else join(recordings, scene, JOIN_GAP_FRAMES)


def check_recordings(scenes: Iterable[str]) -> list[str]:
    """The recordings a study asks for, each a fetched scene's name or a track file of your own:
    `PATH` (named after the file, without its suffix) or `NAME=PATH`. The scenes come first, in
    SCENES order, then the files in the order given.

    Raises:
        UnknownSceneError: neither a scene of SCENES nor an existing file.
        ValueError: no recording, or two with one name.
    """
    asked = list(scenes)
    if not asked:
        raise ValueError("name at least one scene or track file")
    files = [s for s in asked if s not in SCENES]
    for spec in files:
        if not _track_file(spec)[1].is_file():
            raise UnknownSceneError(
                f"{spec!r} is neither a scene nor a track file (PATH or NAME=PATH); scenes: {', '.join(SCENES)}"
            )
    names = [s for s in asked if s in SCENES] + [_track_file(s)[0] for s in files]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"two recordings named {', '.join(map(repr, twice))}: name them NAME=PATH")
    return check_scenes([s for s in asked if s in SCENES]) + files


def load_recording(spec: str, cache: str | Path | None = None) -> Recording:
    """A fetched scene by name (load_scene), or a track file given as `PATH` or `NAME=PATH` (read_tracks,
    layout "auto"; named NAME or after the file)."""
    if spec in SCENES:
        return load_scene(spec, cache)
    (spec,) = check_recordings([spec])
    name, path = _track_file(spec)
    return read_tracks(path, name=name)


def _track_file(spec: str) -> tuple[str, Path]:
    """The name and path of a track file given as PATH or NAME=PATH."""
    name, _, path = spec.partition("=") if not Path(spec).is_file() else ("", "", spec)
    return name or Path(path).stem, Path(path)


def _verify(path: Path, file: SceneFile, what: str) -> None:
    """Raise ChecksumError when the file at `path` is not `file`."""
    found = sha256(path)
    if found != file.sha256:
        raise ChecksumError(f"{what}: SHA-256 {found}, expected {file.sha256} ({file.name})")


def _copy(scene: str, file: SceneFile, source: Path, staged: Path, progress: bool) -> None:
    """Copy `file` from the first file of its name below `source` with the right checksum."""
    candidates = sorted(p for p in source.rglob(file.name) if p.is_file())
    if not candidates:
        raise FileNotFoundError(f"{file.name} (scene {scene}) is nowhere below {source}")
    for candidate in candidates:
        if sha256(candidate) == file.sha256:
            if progress:
                logger.info("%s: copying %s", scene, candidate)
            shutil.copyfile(candidate, staged)
            _verify(staged, file, f"{candidate} (copied)")
            return
    found = ", ".join(f"{p} ({sha256(p)})" for p in candidates)
    raise ChecksumError(
        f"no {file.name} below {source} has the pinned SHA-256 {file.sha256} (scene {scene}): found {found}"
    )


def _download(scene: str, file: SceneFile, base_url: str, staged: Path, progress: bool) -> None:
    """Download `file` from base_url into `staged` with pooch, checking its checksum."""
    import pooch

    url = base_url.rstrip("/") + "/" + file.path
    if progress:
        logger.info("%s: downloading %s", scene, url)
    pooch_logger = pooch.get_logger()
    level = pooch_logger.level
    pooch_logger.setLevel(logging.WARNING)  # its INFO line repeats ours
    try:
        pooch.retrieve(url, known_hash=None, fname=staged.name, path=staged.parent, progressbar=False)
    except Exception as exc:
        raise DownloadError(f"could not download {url}: {exc}") from exc
    finally:
        pooch_logger.setLevel(level)
    _verify(staged, file, f"{url} (scene {scene})")
