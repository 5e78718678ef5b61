"""The viewer's writer: one self-contained HTML page with the episodes as JSON inside."""

import json
import re

import numpy as np
import pytest

from socialzoo.render.replay_data import Encoding, encode_replay
from socialzoo.render.replay_html import replay_document, write_replay_html


def embedded_data(page: str) -> dict:
    match = re.search(r'<script type="application/json" id="replay-data">(.*?)</script>', page, re.S)
    assert match is not None
    return json.loads(match.group(1))


def test_document_is_self_contained(make_trace, make_scene):
    page = replay_document(make_scene(), [make_trace()])
    assert page.startswith("<!DOCTYPE html>")
    # Nothing to fetch: no URLs, no external scripts, stylesheets or images.
    assert "http:" not in page and "https:" not in page and "//cdn" not in page
    assert re.search(r"\b(src|href)\s*=", page) is None
    assert "<link" not in page and "@import" not in page and "url(" not in page
    for slot in ("{{TITLE}}", "{{STYLE}}", "{{DATA}}", "{{SCRIPT}}"):
        assert slot not in page
    assert "socialzooReplay" in page and ".panel" in page  # the script and the stylesheet are inline


def test_embedded_data_is_the_encoded_replay(make_trace, make_scene):
    scene, traces = make_scene(), [make_trace(), make_trace(label="goalone", action=np.zeros(9, int))]
    encoding = Encoding(stride=3, laser_rays=4)
    page = replay_document(scene, traces, encoding=encoding, view="map")
    assert embedded_data(page) == encode_replay(scene, traces, encoding=encoding, view="map")


def test_text_cannot_break_out_of_the_page(make_trace, make_scene):
    evil = "</script><script>alert(1)</script><!--"
    page = replay_document(make_scene(title=evil), [make_trace(label=evil)])
    assert page.count("</script>") == 2  # the data's and the viewer's own
    assert "<title>&lt;/script&gt;&lt;script&gt;alert(1)&lt;/script&gt;&lt;!--</title>" in page
    data = embedded_data(page)
    assert data["title"] == evil and data["episodes"][0]["label"] == evil


def test_not_finite_values_are_refused(make_trace, make_scene):
    pose = np.zeros((10, 3))
    pose[4, 0] = np.nan
    with pytest.raises(ValueError, match="must be finite"):
        replay_document(make_scene(), [make_trace(robot_pose=pose)])


def test_write_replay_html(tmp_path, make_trace, make_scene):
    path = write_replay_html(tmp_path / "sub" / "ep.html", make_scene(), [make_trace()])
    assert path.read_text(encoding="utf-8") == replay_document(make_scene(), [make_trace()])
    with pytest.raises(ValueError, match=r"ep.gif must end in .html"):
        write_replay_html(tmp_path / "ep.gif", make_scene(), [make_trace()])


def test_a_page_is_written_whole_or_not_at_all(tmp_path, make_trace, make_scene):
    # `socialzoo suite` keeps a replay page already there on a rerun, so a page cut short (a full disk, a
    # killed run) stayed cut short. A file-size limit stands in for the full disk: the write fails half way.
    resource = pytest.importorskip("resource")
    signal = pytest.importorskip("signal")
    size = len(replay_document(make_scene(), [make_trace()]).encode())
    path = tmp_path / "ep.html"
    limits = resource.getrlimit(resource.RLIMIT_FSIZE)
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
    try:
        resource.setrlimit(resource.RLIMIT_FSIZE, (size // 2, limits[1]))
        with pytest.raises(OSError):
            write_replay_html(path, make_scene(), [make_trace()])
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, limits)
        signal.signal(signal.SIGXFSZ, handler)
    assert list(tmp_path.iterdir()) == []  # no page, and no temporary file left
