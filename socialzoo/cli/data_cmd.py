"""`socialzoo data fetch|list`: bring the recorded ETH/UCY pedestrian trajectories into the local
cache (never into the repository) and see what is there (socialzoo.data)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import split_commas

if TYPE_CHECKING:
    from socialzoo.data.tracks import Recording

DATASETS = ("eth-ucy",)


def _scene_list(text: str) -> list[str]:
    """argparse type: comma-separated scene names of socialzoo.data.fetch.SCENES."""
    from socialzoo.data.fetch import UnknownSceneError, check_scenes

    names = split_commas(text)
    if not names:
        raise argparse.ArgumentTypeError(f"expected scene names separated by commas, got {text!r}")
    try:
        return check_scenes(names)
    except UnknownSceneError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def register(subparsers: Any) -> None:
    """Add `data` and its subcommands."""
    parser = subparsers.add_parser("data", help=command_help("data"))
    sub = parser.add_subparsers(dest="data_command", required=True, metavar="ACTION")

    fetch = sub.add_parser(
        "fetch",
        help="download (or copy from a folder) the ETH/UCY recordings into the cache",
        description=(
            "Bring the five ETH/UCY scenes (eth, hotel, univ, zara1, zara2) as prepared by Trajectron++ "
            "into the cache, from their pinned public copy or from a local folder (--from), checking "
            "every file's SHA-256. A wrong checksum stops it with nothing new left in the cache. The "
            "cache is $SOCIALZOO_DATA_DIR, else the user cache folder's socialzoo/eth-ucy."
        ),
    )
    fetch.add_argument("dataset", choices=DATASETS, help="the data set")
    fetch.add_argument(
        "--scenes", type=_scene_list, default=None, help="comma-separated scenes (default: all five)"
    )
    fetch.add_argument(
        "--from",
        dest="source_dir",
        type=Path,
        default=None,
        metavar="DIR",
        help="copy the files from this folder (found by name anywhere below it) instead of downloading",
    )
    fetch.add_argument("--cache", type=Path, default=None, help="the cache folder")
    fetch.set_defaults(func=run_fetch)

    listing = sub.add_parser(
        "list", help="each scene: fetched or not, tracks, frames, duration, people at once"
    )
    listing.add_argument("--cache", type=Path, default=None, help="the cache folder")
    listing.set_defaults(func=run_list)


def run_fetch(args: argparse.Namespace) -> int:
    """`socialzoo data fetch eth-ucy`: print the credit, fetch, say where each scene's files are."""
    from socialzoo.data.fetch import CREDIT, DownloadError, data_dir, fetch_scenes

    cache = data_dir(args.cache)
    print("ETH/UCY pedestrian trajectories. Cite the recordings when you use them:")
    print(CREDIT)
    try:
        fetched = fetch_scenes(args.scenes, source_dir=args.source_dir, cache=cache)
    except (ValueError, OSError) as exc:  # a failed download: 1, anything else: 2
        fail("data fetch", exc)
        return 1 if isinstance(exc, DownloadError) else 2
    print(f"cache: {cache}")
    for scene, paths in fetched.items():
        print(f"  {scene:6s} {', '.join(p.name for p in paths)}")
    return 0


def people_at_once(recording: Recording) -> int:
    """The most tracks of a Recording present on one frame."""
    count = np.zeros(recording.num_frames + 1, dtype=np.int64)
    for track in recording.tracks:
        count[track.first_frame] += 1
        count[track.last_frame + 1] -= 1
    return int(np.cumsum(count).max())


def run_list(args: argparse.Namespace) -> int:
    """`socialzoo data list`: a table of the scenes in the cache."""
    from socialzoo.data.fetch import SCENES, data_dir, load_scene

    cache = data_dir(args.cache)
    print(f"cache: {cache}")
    print(f"{'scene':6s}  {'fetched':7s}  {'tracks':>6s}  {'frames':>6s}  {'duration':>9s}  {'at once':>7s}")
    status = 0
    for scene in SCENES:
        try:
            recording = load_scene(scene, cache=cache)
        except FileNotFoundError:
            print(f"{scene:6s}  {'no':7s}")
            continue
        except ValueError as exc:  # a changed file (ChecksumError) or an unreadable one (TrackFileError)
            print(f"{scene:6s}  {'broken':7s}  {exc}")
            status = 2
            continue
        duration = (recording.num_frames - 1) * recording.dt
        print(
            f"{scene:6s}  {'yes':7s}  {len(recording.tracks):6d}  {recording.num_frames:6d}  "
            f"{duration:7.1f} s  {people_at_once(recording):7d}"
        )
    if any(not (cache / f.name).is_file() for files in SCENES.values() for f in files):
        hint = "" if args.cache is None else f" --cache {cache}"
        print(f"fetch the missing scenes with `socialzoo data fetch eth-ucy{hint}`")
    return status
