"""Progress of a long loop: tqdm's bar on a terminal, a plain line every few percent in a log."""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable, Mapping
from typing import IO, Any

# A log line every LOG_STEP_PERCENT of the total, or every LOG_INTERVAL_S seconds when that comes
# first: at most ~10 lines for the percentages, and a slow run still shows a sign of life twice a
# minute (between updates nothing is written: no thread watches the clock).
LOG_STEP_PERCENT = 10.0
LOG_INTERVAL_S = 30.0

PROGRESS_ENV = "SOCIALZOO_PROGRESS"
"""Environment variable that forces the kind of progress output: "bar", "log" or "off"."""
MODES = ("bar", "log", "off")


class LogProgress:
    """Progress as whole lines: `desc: 40% 400/1000 trial, 12.3 trial/s, elapsed 0:32, left 0:48`.

    The part of tqdm's surface the package uses: update(n), set_postfix(**kw), set_postfix_str,
    close(), use as a context manager, and the attributes `n` and `total`. A line is written by
    the update that crosses the next LOG_STEP_PERCENT of the total or comes LOG_INTERVAL_S after
    the last line, and by close() when the count moved since the last line.

    A bar redraws itself with carriage returns, which a log file (`make run > log 2>&1`) keeps as
    hundreds of partial lines; where the output is not a terminal, a few whole lines say the same.

    Args:
        total: the count at the end (None or 0: unknown; lines then come by time only).
        desc: the label at the start of each line ("" for none).
        unit: what is counted, e.g. "trial".
        file: the stream to write to (default sys.stderr, looked up when the object is made).
        enabled: False writes nothing (the count still moves).
        clock: seconds, monotonic (injectable for tests).
    """

    def __init__(
        self,
        total: int | None,
        desc: str = "",
        unit: str = "step",
        file: IO[str] | None = None,
        *,
        enabled: bool = True,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.total = total
        self.desc = desc
        self.unit = unit
        self.n = 0
        self.file = sys.stderr if file is None else file
        self.enabled = enabled
        self._clock = clock
        self._start = clock()
        self._last_time = self._start
        self._last_n: int | None = None  # the count of the last line written, None before one
        self._last_slot = 0
        self._postfix = ""
        self._closed = False

    def update(self, n: int = 1) -> None:
        """Count n more; writes a line when the next step percent or the time interval is reached."""
        self.n += n
        if not self.enabled or self._closed:
            return
        now = self._clock()
        if self._slot() > self._last_slot or now - self._last_time >= LOG_INTERVAL_S:
            self._write(now)

    def set_postfix(
        self, ordered_dict: Mapping[str, Any] | None = None, refresh: bool = True, **kwargs: Any
    ) -> None:
        """Values shown in brackets at the end of the next lines, e.g. `(success=0.81)`.

        `refresh` is accepted for tqdm's signature; lines come only by percent and time.
        """
        items = {**(ordered_dict or {}), **kwargs}
        self._postfix = ", ".join(f"{key}={_value_text(value)}" for key, value in items.items())

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Text shown in brackets at the end of the next lines."""
        self._postfix = str(s)

    def close(self) -> None:
        """Write the final line (unless the last line already shows this count); idempotent."""
        if self._closed:
            return
        self._closed = True
        if self.enabled and self._last_n != self.n:
            self._write(self._clock())

    def __enter__(self) -> LogProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _slot(self) -> int:
        """How many whole LOG_STEP_PERCENT steps of the total are done."""
        if not self.total:
            return 0
        return math.floor(100.0 * self.n / self.total / LOG_STEP_PERCENT + 1e-9)

    def _write(self, now: float) -> None:
        self._last_time, self._last_n, self._last_slot = now, self.n, self._slot()
        self.file.write(self.line(now) + "\n")
        self.file.flush()

    def line(self, now: float | None = None) -> str:
        """The progress line at clock time `now` (default: the clock now), without a newline."""
        elapsed = max(0.0, (self._clock() if now is None else now) - self._start)
        if self.total:
            text = f"{100.0 * self.n / self.total:.0f}% {self.n}/{self.total} {self.unit}"
        else:
            text = f"{self.n} {self.unit}"
        rate = self.n / elapsed if elapsed > 0 else None
        if rate:
            text += f", {rate:.1f} {self.unit}/s" if rate >= 1 else f", {1 / rate:.1f} s/{self.unit}"
        text += f", elapsed {_duration_text(elapsed)}"
        if rate and self.total and self.n < self.total:
            text += f", left {_duration_text((self.total - self.n) / rate)}"
        if self._postfix:
            text += f" ({self._postfix})"
        return f"{self.desc}: {text}" if self.desc else text


def progress_bar(
    total: int | None, desc: str, enabled: bool = True, unit: str = "step", file: IO[str] | None = None
) -> Any:
    """A progress display of `total` units: tqdm on a terminal, LogProgress lines otherwise.

    Which one: nothing when `enabled` is False; else what SOCIALZOO_PROGRESS says ("bar": tqdm,
    "log": lines, "off": nothing); else tqdm.auto's bar when `file` is a terminal (or in a
    Jupyter kernel, where tqdm.auto draws a widget), and lines when it is not (a log file, a pipe).

    Args:
        total: the count at the end (None: unknown).
        desc: the label.
        enabled: False shows nothing (e.g. --no-progress).
        unit: what is counted, e.g. "trial".
        file: the stream (default sys.stderr).

    Returns:
        An object with tqdm's update(n), set_postfix(**kw), set_postfix_str(s), close(), context
        manager, `n` and `total`: a tqdm bar or a LogProgress (disabled, it writes nothing).

    Raises:
        ValueError: SOCIALZOO_PROGRESS holds something other than bar, log, off (or auto).
    """
    stream = sys.stderr if file is None else file
    mode = progress_mode(stream) if enabled else "off"
    if mode == "bar":
        from tqdm.auto import tqdm

        return tqdm(total=total, desc=desc, unit=unit, file=stream, dynamic_ncols=True, smoothing=0.05)
    return LogProgress(total, desc, unit, stream, enabled=mode == "log")


def progress_mode(file: IO[str]) -> str:
    """The kind of progress for output to `file`: SOCIALZOO_PROGRESS, else "bar" on a terminal, else "log".

    Raises:
        ValueError: SOCIALZOO_PROGRESS holds something other than bar, log, off (or auto, or empty).
    """
    forced = os.environ.get(PROGRESS_ENV, "").strip().lower()
    if forced and forced != "auto":
        if forced not in MODES:
            raise ValueError(f"{PROGRESS_ENV} must be one of {', '.join(MODES)} (or auto), got {forced!r}")
        return forced
    if file is sys.stderr and _in_jupyter():
        return "bar"
    return "bar" if _isatty(file) else "log"


def _isatty(file: IO[str]) -> bool:
    try:
        return bool(file.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def _in_jupyter() -> bool:
    """Whether this runs in a Jupyter kernel (its stderr is no terminal, but shows tqdm's widget)."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    try:
        shell = ipython.get_ipython()
        return shell is not None and "IPKernelApp" in shell.config
    except Exception:  # an IPython too old or too odd to ask: treat it as no kernel
        return False


def _duration_text(seconds: float) -> str:
    """0:32, 12:05 or 1:02:03 (tqdm's style)."""
    if not math.isfinite(seconds):
        return "?"
    minutes, secs = divmod(round(seconds), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def _value_text(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)
