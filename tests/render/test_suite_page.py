"""The scenario suite's results page in a real browser: headless Chromium (Debian's chromium package,
driven by Playwright) opens results.html with no console errors and no network requests, shows every
heatmap (decoded images), a card per scenario and the tables, and its replay links open the viewer.

Skipped where Chromium or Playwright is missing, except under CI=true, where it fails instead
(`make test` installs both), as the viewer's browser test.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from socialzoo.bench.suite import SuiteConfig, run_suite
from socialzoo.scenarios import catalogue
from socialzoo.scenarios.families import Doorway

CHROMIUM = Path(os.environ.get("SOCIALZOO_CHROMIUM", "/usr/bin/chromium"))
CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
METRICS = ("success", "time_to_goal")


class FrontalStandIn(Doorway):
    """The doorway family under suite scenario (a)'s name."""

    name = "frontal_approach"


def _need_browser() -> None:
    """Skip without Chromium or Playwright; fail instead under CI, which must run this test."""
    problems = []
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        problems.append("the Python package playwright is missing (pip install -e '.[dev]')")
    if not CHROMIUM.is_file():
        problems.append(f"{CHROMIUM} is missing (apt-get install chromium; make test installs it)")
    if problems:
        message = "browser test: " + "; ".join(problems)
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(message + " (CI=true: this test must run)")
        pytest.skip(message)


@pytest.fixture(scope="module")
def suite_run(tmp_path_factory):
    """GoAlone and Ref on suite scenario (a) (a stand-in) and the crossing family, one seed each."""
    pytest.importorskip("matplotlib")
    _need_browser()
    out = tmp_path_factory.mktemp("suite")
    with pytest.MonkeyPatch.context() as patch:
        patch.setitem(catalogue.FAMILIES, "frontal_approach", FrontalStandIn())
        config = SuiteConfig(
            policies=("goalone", "ref"),
            scenarios=("a", "crossing"),
            seeds=1,
            workers=1,
            metrics=METRICS,
        )
        result = run_suite(config, out)
    return out / "results.html", result


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    _need_browser()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            str(tmp_path_factory.mktemp("chromium-profile")),  # a fresh profile every run
            executable_path=str(CHROMIUM),
            headless=True,
            args=CHROMIUM_FLAGS,
            viewport={"width": 1200, "height": 900},
            device_scale_factor=1,
        )
        yield context
        context.close()


def _open(browser, url: str, errors: list[str], requests: list[str]):
    page = browser.new_page()
    page.on("console", lambda m: errors.append(f"console {m.type}: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
    page.on("request", lambda r: requests.append(r.url) if not r.url.startswith(("file:", "data:")) else None)
    page.goto(url)
    return page


def test_the_page_shows_heatmaps_cards_and_tables_without_errors(browser, suite_run):
    path, result = suite_run
    errors: list[str] = []
    requests: list[str] = []
    page = _open(browser, path.as_uri(), errors, requests)
    page.wait_for_load_state("load")
    images = page.locator("figure.heatmap img")
    assert images.count() == len(METRICS)
    decoded = page.evaluate(
        "Array.from(document.querySelectorAll('figure.heatmap img')).map(i => i.complete && i.naturalWidth)"
    )
    assert all(width and width > 100 for width in decoded)
    for name in METRICS:
        assert page.locator(f"#heatmap-{name} img").is_visible()
        assert page.locator(f"#table-{name} tr").count() == 1 + len(result.policies)
    assert page.locator("article.card").count() == 2
    assert page.locator("#scenario-frontal_approach h3").inner_text() == "a. Frontal approach"
    card = page.locator("#scenario-frontal_approach details")
    if card.count():  # the suite's cards (socialzoo.scenarios.cards): folded until asked for
        assert not card.locator("dl").is_visible()
        card.locator("summary").click()
        assert card.locator("dt", has_text="defining event").is_visible()
    page.close()
    assert errors == []
    assert requests == []  # self-contained: no network at all


def test_a_replay_link_opens_the_viewer(browser, suite_run):
    path, result = suite_run
    assert result.replays
    errors: list[str] = []
    requests: list[str] = []
    page = _open(browser, path.as_uri(), errors, requests)
    link = page.locator("#scenario-crossing a").first
    link.click()
    page.wait_for_function("document.body.dataset.ready === 'true'", timeout=15_000)
    assert page.url.startswith((path.parent / "replays" / "crossing").as_uri())
    assert page.locator("section.panel").count() == 1
    page.close()
    assert errors == []
    assert requests == []
