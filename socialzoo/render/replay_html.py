"""The episode viewer's writer: recorded episodes -> one self-contained HTML file."""

from __future__ import annotations

import html
import json
import re
from collections.abc import Sequence
from functools import cache
from importlib import resources
from pathlib import Path

from socialzoo.core.files import write_text_atomic
from socialzoo.render.replay_data import Encoding, EpisodeTrace, ReplayScene, encode_replay


@cache
def _asset(name: str) -> str:
    """A file of socialzoo/render/viewer as text."""
    return resources.files("socialzoo.render").joinpath("viewer", name).read_text(encoding="utf-8")


def _script_safe_json(data: object) -> str:
    r"""JSON that can sit inside a <script> element: no '<', '>' or '&' (escaped as \u003c ...),
    so no text in it can close the element or open a comment."""
    text = json.dumps(data, separators=(",", ":"), allow_nan=False, ensure_ascii=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def replay_document(
    scene: ReplayScene,
    traces: Sequence[EpisodeTrace],
    *,
    encoding: Encoding | None = None,
    view: str = "follow",
) -> str:
    """The viewer page of `traces` (one panel each, sharing one timeline) as an HTML string; the
    arguments are socialzoo.render.replay_data.encode_replay's.

    The page inlines its stylesheet, its script (socialzoo/render/viewer/, package data) and the episodes as
    JSON, so it opens from disk with no network access and no other file.

    Raises:
        ValueError: no traces, a bad view, or values that are not finite.
    """
    data = encode_replay(scene, traces, encoding=encoding, view=view)
    try:
        payload = _script_safe_json(data)
    except ValueError as err:  # NaN or infinity in an array: the viewer cannot draw it
        raise ValueError(f"replay_document: the episode data must be finite ({err})") from None
    page = _asset("replay.html")
    # The placeholders of viewer/replay.html, each replaced exactly once.
    parts = {
        "{{TITLE}}": html.escape(scene.title),
        "{{STYLE}}": _asset("replay.css"),
        "{{DATA}}": payload,
        "{{SCRIPT}}": _asset("replay.js"),
    }
    for slot in parts:
        if page.count(slot) != 1:
            raise RuntimeError(f"viewer/replay.html must hold {slot} exactly once")
    # Replaced in one pass over the template, so text in one part never fills another's slot.
    return re.sub("|".join(map(re.escape, parts)), lambda slot: parts[slot.group()], page)


def write_replay_html(
    path: str | Path,
    scene: ReplayScene,
    traces: Sequence[EpisodeTrace],
    *,
    encoding: Encoding | None = None,
    view: str = "follow",
) -> Path:
    """Write the viewer page of `traces` (see `replay_document`) to `path`; returns the path.

    Raises:
        ValueError: as `replay_document`, or `path` not ending in .html / .htm.
    """
    path = Path(path)
    if path.suffix.lower() not in (".html", ".htm"):
        raise ValueError(f"write_replay_html: {path} must end in .html")
    text = replay_document(scene, traces, encoding=encoding, view=view)
    # Whole or not at all (a temporary file, then a rename): a page already there is kept by a rerun
    # (socialzoo suite's replays), so a half-written one (a killed run, a full disk) would stay half.
    return write_text_atomic(path, text)
