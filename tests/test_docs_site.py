"""The documentation site builds without a warning, and its API reference covers every subpackage."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _subpackages() -> list[str]:
    return sorted(p.parent.name for p in (ROOT / "socialzoo").glob("*/__init__.py"))


def test_every_subpackage_has_an_api_page():
    nav = (ROOT / "mkdocs.yml").read_text()
    for name in _subpackages():
        page = ROOT / "docs" / "api" / f"{name}.md"
        assert page.is_file(), (
            f"no API page for socialzoo.{name}: add docs/api/{name}.md and list it in mkdocs.yml"
        )
        assert f"::: socialzoo.{name}" in page.read_text(), f"{page} does not render socialzoo.{name}"
        assert f"api/{name}.md" in nav, f"mkdocs.yml's nav does not list api/{name}.md"


def test_every_doc_page_is_in_the_nav():
    nav = (ROOT / "mkdocs.yml").read_text()
    for page in sorted((ROOT / "docs").rglob("*.md")):
        rel = page.relative_to(ROOT / "docs").as_posix()
        assert f": {rel}" in nav, f"docs/{rel} is not in mkdocs.yml's nav"


def test_site_builds_strict(tmp_path):
    pytest.importorskip("mkdocs", reason="the docs extra: pip install -e '.[docs]'")
    pytest.importorskip("material", reason="the docs extra: pip install -e '.[docs]'")
    pytest.importorskip("mkdocstrings_handlers.python", reason="the docs extra: pip install -e '.[docs]'")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    run = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-4000:]
    assert "WARNING" not in run.stderr, run.stderr[-4000:]
    # The API reference rendered the env classes' docstrings.
    env_page = (tmp_path / "site" / "api" / "env" / "index.html").read_text()
    assert "ActionSelectionEnv" in env_page
    assert "Observation Space" in env_page
