"""tools/render_suite_docs.py: a seeded episode's picture of an existing family, the suite page from
the cards (a section per card, the pictures found linked), the families it cannot play skipped, and
the committed page is the tool's output."""

from __future__ import annotations

import io
import re
import subprocess
import sys
from pathlib import Path

import pytest

from socialzoo.scenarios.cards import CardError, suite_cards
from socialzoo.scenarios.catalogue import FAMILIES
from socialzoo.scenarios.suite import SUITE

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("matplotlib", reason="the plot extra: pip install -e '.[plot]'")


@pytest.fixture(scope="module")
def tool(load_tool):
    return load_tool("render_suite_docs")


def test_draws_a_seeded_episode_of_an_existing_family(tool, tmp_path):
    path = tool.draw_episode("crossing", tmp_path, seed=0, title="Crossing")
    assert path == tmp_path / "crossing.png"
    data = path.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 20_000


def test_the_page_has_a_section_per_card_and_links_the_pictures_found(tool, tmp_path):
    images = tmp_path / "images" / "suite"
    images.mkdir(parents=True)
    (images / "blind_corner.png").write_bytes(b"")
    doc = tmp_path / "docs" / "suite.md"
    text = tool.page_text(suite_cards(), doc, images)
    headings = re.findall(r"^## \((\w)\) (.+)$", text, flags=re.MULTILINE)
    assert headings == [(e.letter, e.title) for e in SUITE]
    assert text.count("](../images/suite/") == 1
    assert "![Blind corner: seed 0 played by GoAlone](../images/suite/blind_corner.png)" in text
    assert text.count("*No picture yet:") == len(SUITE) - 1
    # The index's links go to the headings' anchors.
    anchors = {tool.slug(f"({letter}) {title}") for letter, title in headings}
    assert set(re.findall(r"\]\(#([\w-]+)\)", text)) == anchors
    for card in suite_cards():
        assert f"`{card.family}`" in text and card.defining_event in text and card.limitations[0] in text


def test_a_family_that_cannot_be_played_is_skipped(tool, tmp_path, monkeypatch):
    monkeypatch.delitem(FAMILIES, "frontal_approach", raising=False)
    out = io.StringIO()
    doc, images = tmp_path / "suite.md", tmp_path / "images"
    written, skipped = tool.render(only="a", doc=doc, image_dir=images, out=out)
    assert (written, skipped) == ([], ["frontal_approach"])
    assert (
        "skipped (a) frontal_approach: the family 'frontal_approach' is not registered yet" in out.getvalue()
    )
    assert doc.read_text().count("\n## (") == len(SUITE)
    with pytest.raises(CardError, match="not a suite scenario"):
        tool.render(only="crossing", doc=doc, image_dir=images, out=out)


def test_only_names_a_suite_scenario():
    run = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "render_suite_docs.py"), "--only", "nowhere"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert run.returncode == 2 and "nowhere: (name): not a suite scenario" in run.stderr


def test_the_committed_page_is_the_tools_output(tool):
    assert tool.DOC.read_text() == tool.page_text(suite_cards(), tool.DOC, tool.IMAGES), (
        "docs/suite_scenarios.md is out of date: run python tools/render_suite_docs.py"
    )
