"""The episode viewer in a real browser: headless Chromium (Debian's chromium package, driven by
Playwright) opens a replay of two policies with no console errors and no network requests, the
scrubber and the play button move the drawn frame, and the robot is drawn where its pose says.

Skipped where Chromium or Playwright is missing, except under CI=true, where it fails instead
(`make test` installs both).
"""

from __future__ import annotations

import base64
import io
import os
from pathlib import Path

import numpy as np
import pytest

from socialzoo.agents import make_policy
from socialzoo.bench.replay import benchmark_scenario, record_episode, replay_scene
from socialzoo.env.config import EnvConfig
from socialzoo.maps.map_file import load_map
from socialzoo.render.replay_data import Encoding
from socialzoo.render.replay_html import write_replay_html

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
ROBOT_RGB = np.array([245, 140, 30])  # the viewer's robot colour (replay.js COLORS.robot)
STRIDE = 2


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
def replay_file(tmp_path_factory):
    """GoAlone and Ref on one open_room scenario (about 120 steps each)."""
    config = EnvConfig(map="open_room", max_steps=120)
    m = load_map(config.map)
    scenario = benchmark_scenario(config, 3, m)
    traces = [
        record_episode(config, scenario, make_policy(name), laser_rays=40, laser_stride=STRIDE, world_map=m)
        for name in ("goalone", "ref")
    ]
    path = tmp_path_factory.mktemp("viewer") / "episode.html"
    write_replay_html(
        path,
        replay_scene(config, m, "goalone vs ref"),
        traces,
        encoding=Encoding(stride=STRIDE, laser_rays=40),
    )
    return path, traces


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


@pytest.fixture
def page(browser, replay_file):
    """The replay, loaded; the fixture checks at teardown that nothing went wrong or out."""
    path, _ = replay_file
    page = browser.new_page()
    errors: list[str] = []
    requests: list[str] = []
    page.on("console", lambda m: errors.append(f"console {m.type}: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
    page.on("request", lambda r: requests.append(r.url) if not r.url.startswith("file:") else None)
    page.goto(path.as_uri())
    page.wait_for_function("document.body.dataset.ready === 'true'", timeout=15_000)
    yield page
    page.close()
    assert errors == []
    assert requests == []  # self-contained: no network at all


def canvas_url(page, panel: int = 0) -> str:
    return page.evaluate(f"document.querySelectorAll('canvas.scene')[{panel}].toDataURL('image/png')")


def robot_pixels(png: bytes) -> np.ndarray:
    """(N, 2) x, y of the pixels in the robot's colour."""
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    close = np.abs(rgb - ROBOT_RGB).max(axis=-1) <= 12
    ys, xs = np.nonzero(close)
    return np.stack((xs, ys), axis=1)


def test_page_loads_with_both_panels(page, replay_file):
    _, traces = replay_file
    assert page.title() == "goalone vs ref"
    assert page.locator("section.panel").count() == 2
    assert page.locator("section.panel h2").all_inner_texts()[1].startswith("ref")
    max_step = page.evaluate("window.socialzooReplay.maxStep")
    assert max_step == max(t.num_steps for t in traces)
    assert page.locator("#scrub").get_attribute("max") == str(max_step)


def test_the_scrubber_moves_the_frame(page):
    first = [canvas_url(page, 0), canvas_url(page, 1)]
    scrub = page.locator("#scrub")
    scrub.focus()
    page.keyboard.press("End")  # the range input's own keyboard handling fires "input"
    max_step = page.evaluate("window.socialzooReplay.maxStep")
    assert scrub.input_value() == str(max_step) and page.evaluate("window.socialzooReplay.step") == max_step
    last = [canvas_url(page, 0), canvas_url(page, 1)]
    assert last[0] != first[0] and last[1] != first[1]  # both panels follow the shared clock
    # A click in the middle of the slider lands near the middle of the episode.
    box = scrub.bounding_box()
    page.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    middle = page.evaluate("window.socialzooReplay.step")
    assert abs(middle - max_step / 2) <= 0.1 * max_step
    assert canvas_url(page, 0) not in (first[0], last[0])
    assert page.locator("#clock").inner_text().startswith(f"t = {middle * 0.025:.2f} s")
    # Arrow keys step one stored frame (outside the slider, which steps itself by one).
    page.evaluate("document.activeElement.blur()")
    page.keyboard.press("ArrowRight")
    assert page.evaluate("window.socialzooReplay.step") == middle + STRIDE


def test_play_advances_and_pause_stops(page):
    page.click("#play")
    page.wait_for_function("window.socialzooReplay.step >= 10", timeout=10_000)
    page.click("#play")
    stopped = page.evaluate("window.socialzooReplay.step")
    assert page.evaluate("window.socialzooReplay.playing") is False
    page.wait_for_timeout(200)
    assert page.evaluate("window.socialzooReplay.step") == stopped


@pytest.mark.parametrize("camera", ["follow", "map"])
def test_screenshot_shows_the_robot_where_it_is(page, replay_file, camera):
    _, traces = replay_file
    trace = traces[1]
    step = (trace.num_steps // 2) // STRIDE * STRIDE  # a stored frame
    page.evaluate(f"window.socialzooReplay.setCamera('{camera}')")
    page.evaluate("document.getElementById('show-laser').click()")  # the laser dots are red, not orange
    page.evaluate(f"window.socialzooReplay.seek({step})")
    canvas = page.locator("canvas.scene").nth(1)
    box = canvas.bounding_box()
    width, height = box["width"], box["height"]
    if camera == "follow":
        expected = np.array([width / 2, height / 2])
    else:
        bounds = page.evaluate("JSON.parse(document.getElementById('replay-data').textContent).scene.bounds")
        x0, y0, x1, y1 = bounds
        scale = 0.97 * min(width / (x1 - x0), height / (y1 - y0))
        x, y = trace.robot_pose[step, :2]
        expected = np.array(
            [(x - (x0 + x1) / 2) * scale + width / 2, ((y0 + y1) / 2 - y) * scale + height / 2]
        )
    shot = canvas.screenshot()
    found = robot_pixels(shot)
    assert len(found) >= 30, "no robot in the screenshot"
    assert np.abs(found.mean(axis=0) - expected).max() <= 4.0
    assert np.abs(found - expected).max() <= 25  # and nowhere else
    # The same pixels come back from the canvas itself (what the screenshot shows is what it drew).
    url = canvas_url(page, 1)
    assert len(robot_pixels(base64.b64decode(url.split(",", 1)[1]))) >= 30


# (lo, hi, maxTicks, minSpan): constant, all zero, near-constant (1e-9 spread), tiny, large,
# negative, and ordinary ranges.
AXIS_CASES = [
    (5.0, 5.0, 3, 0),
    (0.0, 0.0, 3, 0),
    (0.0, 0.0, 3, 0.1),
    (1.0, 1.0 + 1e-9, 3, 0),
    (0.0, 1e-9, 3, 0),
    (-3.4e-5, 2.4e-5, 3, 0.1),
    (1e9, 1e9 + 1e-3, 3, 0),
    (-2e6, 7.5e6, 6, 0),
    (-7.5, -7.5, 3, 0),
    (-1234.5, -1234.5 + 1e-9, 4, 0),
    (-0.3, -0.1, 3, 0),
    (-0.0405, 0.003, 3, 0.1),
    (0.0, 1.0, 3, 0),
    (-7.3, 123.4, 8, 0),
]


def test_chart_axes_have_few_distinct_ticks_around_the_data(page):
    for lo, hi, max_ticks, min_span in AXIS_CASES:
        axis = page.evaluate(
            "([lo, hi, n, s]) => window.socialzooReplay.niceAxis(lo, hi, n, s)", [lo, hi, max_ticks, min_span]
        )
        case = f"niceAxis({lo}, {hi}, {max_ticks}, {min_span}) = {axis}"
        assert axis["hi"] - axis["lo"] > 0, case
        assert axis["lo"] <= lo and axis["hi"] >= hi, case  # the data stay inside
        assert axis["hi"] - axis["lo"] >= max(min_span, 0.1 * max(abs(lo), abs(hi))) * (1 - 1e-9), case
        ticks, labels = axis["ticks"], axis["labels"]
        assert 2 <= len(ticks) <= max_ticks and len(labels) == len(ticks), case
        assert len(set(labels)) == len(labels), case
        assert not any(label.startswith("-0") and float(label) == 0 for label in labels), case
        step = axis["step"]
        for tick, label in zip(ticks, labels, strict=True):
            assert axis["lo"] - 1e-3 * step <= tick <= axis["hi"] + 1e-3 * step, case
            assert abs(float(label) - tick) <= 1e-6 * step, case  # the label says its tick
    # Decimals follow the step: no more, no fewer.
    assert page.evaluate("window.socialzooReplay.niceAxis(0, 1, 3, 0).labels") == ["0.0", "0.5", "1.0"]
    assert page.evaluate("window.socialzooReplay.niceAxis(0, 0, 3, 0).labels") == ["-1", "0", "1"]
    assert page.evaluate("window.socialzooReplay.niceAxis(-5, -5, 3, 0).labels") == [
        "-5.25",
        "-5.00",
        "-4.75",
    ]


def test_a_stuck_episode_charts_its_reward_flat(browser, make_scene, make_trace, tmp_path):
    """A robot standing still: its reward is noise of 1e-4 around 0. The chart draws it as a flat
    line (before, the noise filled the chart and its clipped-value labels ran into each other)."""
    steps = 400
    noise = np.round(np.random.default_rng(0).normal(0.0, 6e-5, steps), 4)
    trace = make_trace(steps=steps, reward=noise, force=np.zeros(steps), blame=np.full(steps, 1e-5))
    path = tmp_path / "stuck.html"
    write_replay_html(path, make_scene(), [trace])
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(path.as_uri())
    page.wait_for_function("document.body.dataset.ready === 'true'", timeout=15_000)
    page.evaluate("window.socialzooReplay.seek(0)")
    shot = page.locator("canvas.charts").screenshot()
    page.close()
    assert errors == []
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB")).astype(int)
    # The reward chart (the top third), between the name on the left and the tick labels on the
    # right; the cursor is at step 0, on the left edge. Grid lines are light (212 and up), the
    # antialiased line is darker.
    height, width = rgb.shape[:2]
    band = rgb[: height // 3, int(0.15 * width) : int(0.8 * width)]
    line = band.max(axis=-1) < 190
    rows = np.nonzero(line.any(axis=1))[0]
    assert line.sum() > 0.5 * band.shape[1], "no reward line drawn"
    assert rows.max() - rows.min() <= 3, f"the reward line spans rows {rows.min()}-{rows.max()}"


def test_people_are_drawn_only_while_present(browser, make_scene, make_trace, tmp_path):
    """People of a recorded scene come and go: one absent at the start, the other gone at the end
    is not drawn (before, the viewer never drew newcomers and kept drawing those who had left)."""
    present = np.ones((10, 2), bool)
    present[:4, 1] = False
    present[6:, 0] = False
    trace = make_trace(steps=9, human_present=present, laser_ranges=np.full((10, 8), 10.0))
    path = tmp_path / "come_and_go.html"
    write_replay_html(path, make_scene(), [trace], encoding=Encoding(stride=1), view="map")
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(path.as_uri())
    page.wait_for_function("document.body.dataset.ready === 'true'", timeout=15_000)
    human = np.array([70, 120, 205])  # replay.js COLORS.human
    counts = []
    for step in (0, 5, 9):
        page.evaluate(f"window.socialzooReplay.seek({step})")
        rgb = np.asarray(_image(page.locator("canvas.scene").screenshot())).astype(int)
        # Human 0 walks along x = 3 m (the middle of the map view), human 1 along x = 4 m: split
        # their discs at x = 3.5 m (the view's scale is 0.97 x the width over the 7 m bounds).
        _, xs = np.nonzero(np.abs(rgb - human).max(axis=-1) <= 12)
        split = rgb.shape[1] * (0.5 + 0.5 * 0.97 / 7)
        counts.append((int((xs < split).sum()), int((xs >= split).sum())))
    page.close()
    assert errors == []
    (a0, b0), (a5, b5), (a9, b9) = counts
    assert a0 > 20 and b0 == 0  # only human 0 at the start
    assert a5 > 20 and b5 > 20  # both
    assert a9 == 0 and b9 > 20  # only human 1 at the end


def test_the_other_robots_are_drawn(browser, make_scene, make_trace, tmp_path):
    others = np.tile([5.0, 2.5, 0.0], (10, 1, 1))  # a second robot standing at (5, 2.5)
    path = tmp_path / "two_robots.html"
    write_replay_html(path, make_scene(), [make_trace(steps=9, other_robots=others)], view="map")
    page = browser.new_page()
    page.goto(path.as_uri())
    page.wait_for_function("document.body.dataset.ready === 'true'", timeout=15_000)
    rgb = np.asarray(_image(page.locator("canvas.scene").screenshot())).astype(int)
    assert "other robots" in page.locator("#legend").inner_text()
    page.close()
    scale = 0.97 * rgb.shape[1] / 7  # the map view of the 7 m x 4 m bounds, centred on (3, 1.5)
    x, y = round(rgb.shape[1] / 2 + 2 * scale), round(rgb.shape[0] / 2 - scale)
    near = rgb[y - 15 : y + 15, x - 15 : x + 15]  # the footprint is 0.5 m x 0.43 m, 60 px a metre
    assert (np.abs(near - [168, 168, 180]).max(axis=-1) <= 3).sum() >= 200  # replay.js COLORS.other


def _image(png: bytes):
    from PIL import Image

    return Image.open(io.BytesIO(png)).convert("RGB")
