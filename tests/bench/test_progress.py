"""Progress output: whole lines, few of them, where the stream is not a terminal; tqdm on one."""

from __future__ import annotations

import io

import pytest

from socialzoo.bench import progress
from socialzoo.bench.progress import LOG_INTERVAL_S, LogProgress, progress_bar


class FakeClock:
    """A clock that moves only when told to."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.fixture(autouse=True)
def _no_forced_mode(monkeypatch):
    monkeypatch.delenv(progress.PROGRESS_ENV, raising=False)


def test_a_log_gets_whole_lines_every_ten_percent_and_no_carriage_returns():
    assert isinstance(progress_bar(1000, "benchmark", unit="trial", file=io.StringIO()), LogProgress)
    out = io.StringIO()
    bar = LogProgress(1000, "benchmark", "trial", out, clock=FakeClock())  # time stands still
    with bar:
        for _ in range(1000):
            bar.update(1)
    text = out.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert 10 <= len(lines) <= 12
    assert lines[0].startswith("benchmark: 10% 100/1000 trial")
    assert lines[-1].startswith("benchmark: 100% 1000/1000 trial")
    assert bar.n == 1000 and bar.total == 1000


def test_a_line_comes_after_the_interval_and_shows_rate_time_left_and_postfix():
    out, clock = io.StringIO(), FakeClock()
    bar = LogProgress(1000, "benchmark", "trial", out, clock=clock)
    bar.update(5)
    assert out.getvalue() == ""  # under 10% and no time passed
    clock.now += LOG_INTERVAL_S - 1
    bar.update(5)
    assert out.getvalue() == ""
    clock.now += 1.0
    bar.set_postfix(success=0.8125, refresh=False)
    bar.update(10)
    assert (
        out.getvalue()
        == "benchmark: 2% 20/1000 trial, 1.5 s/trial, elapsed 0:30, left 24:30 (success=0.8125)\n"
    )
    clock.now += 2.0
    bar.update(380)  # crosses 10%, 20%, 30%: one line
    assert len(out.getvalue().splitlines()) == 2
    assert (
        out.getvalue()
        .splitlines()[1]
        .startswith("benchmark: 40% 400/1000 trial, 12.5 trial/s, elapsed 0:32, left 0:48")
    )


def test_close_writes_a_final_line_once():
    out, clock = io.StringIO(), FakeClock()
    bar = LogProgress(None, "record", "episode", out, clock=clock)
    bar.update(3)
    clock.now += 2.0
    bar.set_postfix_str("loss 0.12")
    bar.close()
    bar.close()
    assert out.getvalue() == "record: 3 episode, 1.5 episode/s, elapsed 0:02 (loss 0.12)\n"


def test_disabled_writes_nothing():
    out, clock = io.StringIO(), FakeClock()
    with progress_bar(100, "benchmark", enabled=False, file=out) as bar:
        for _ in range(100):
            bar.update(1)
    assert out.getvalue() == "" and bar.n == 100
    quiet = LogProgress(100, "x", file=out, enabled=False, clock=clock)
    clock.now += 10 * LOG_INTERVAL_S
    quiet.update(100)
    quiet.close()
    assert out.getvalue() == ""


def test_a_terminal_gets_tqdm():
    from tqdm import tqdm

    bar = progress_bar(10, "benchmark", unit="trial", file=FakeTerminal())
    try:
        assert isinstance(bar, tqdm)
    finally:
        bar.close()


@pytest.mark.parametrize(
    ("forced", "stream", "kind"),
    [
        ("log", FakeTerminal, LogProgress),
        ("bar", io.StringIO, "tqdm"),
        ("off", io.StringIO, None),
        ("auto", io.StringIO, LogProgress),
    ],
)
def test_the_environment_variable_forces_the_kind(monkeypatch, forced, stream, kind):
    from tqdm import tqdm

    monkeypatch.setenv(progress.PROGRESS_ENV, forced)
    out = stream()
    bar = progress_bar(10, "benchmark", file=out)
    for _ in range(10):
        bar.update(1)
    bar.close()
    if kind == "tqdm":
        assert isinstance(bar, tqdm) and "\r" in out.getvalue()
    elif kind is None:
        assert out.getvalue() == ""
    else:
        assert isinstance(bar, kind) and "\r" not in out.getvalue() and out.getvalue()


def test_a_bad_environment_value_is_named(monkeypatch):
    monkeypatch.setenv(progress.PROGRESS_ENV, "fancy")
    with pytest.raises(ValueError, match=r"SOCIALZOO_PROGRESS must be one of bar, log, off .*'fancy'"):
        progress_bar(10, "benchmark", file=io.StringIO())
    # --no-progress wins without looking at it.
    assert progress_bar(10, "benchmark", enabled=False, file=io.StringIO()).enabled is False
