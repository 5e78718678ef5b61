"""Shared helpers of the benchmark scripts: timing loops, peak memory, printing figures."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import tracemalloc
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

from numba.core import event


@dataclass
class Figure:
    """One measured configuration (peak_mem_mib None: not measured)."""

    name: str
    batch: int
    env_steps_per_s: float
    agent_steps_per_s: float
    peak_mem_mib: float | None


def at_least(low: float, kind: type = int, above: bool = False) -> Callable[[str], Any]:
    """argparse type: a finite `kind` (int or float) >= `low` (> `low` with `above`), so that a bad option
    ends in argparse's "argument --X: expected ..., got VALUE" before any measurement, not in a
    traceback or a figure of nothing (the scripts run without socialzoo.cli.arg_types: an old tree)."""
    what = f"{'an integer' if kind is int else 'a finite number'} {'>' if above else '>='} {low:g}"

    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and (value > low if above else value >= low)):
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return value

    return parse


positive_int = at_least(1)
positive_seconds = at_least(0, float, above=True)


def parser(description: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--json", action="store_true", help="print one JSON object per line")
    p.add_argument("--seconds", type=positive_seconds, default=3.0, help="time per configuration (s)")
    return p


class _Compilations(event.Listener):
    """Counts numba's compilations in this process. A kernel compiles on its first call with new argument
    types (with a cold cache: a fresh checkout, a new NUMBA_CACHE_DIR), which can come many steps into a
    run (a code path first taken at step 6, arrays of another layout at B > 1): seconds and tens of MiB
    that belong to no step. Loading a kernel from the cache is no compilation."""

    count = 0

    def on_start(self, event: event.Event) -> None:
        pass

    def on_end(self, event: event.Event) -> None:
        self.count += 1


COMPILATIONS = _Compilations()
event.register("numba:compile", COMPILATIONS)


def measure(step: Callable[[], None], seconds: float, warmup: int = 5) -> tuple[float, int]:
    """Calls per second of `step`, run for about `seconds` after `warmup` calls; a call in which a
    kernel compiled starts the timing again after it."""
    for _ in range(warmup):
        step()
    calls, compiled, start = 0, COMPILATIONS.count, time.perf_counter()
    while True:
        step()
        calls += 1
        if COMPILATIONS.count != compiled:
            calls, compiled, start = 0, COMPILATIONS.count, time.perf_counter()
            continue
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return calls / elapsed, calls


def traced_peak_mib(build: Callable[[], Callable[[], None]], steps: int = 3) -> float:
    """Peak numpy/Python allocation (MiB) of building a workload and running a few steps of it (again
    where a kernel compiled meanwhile: the compiler's memory is no part of the workload's)."""
    while True:
        compiled = COMPILATIONS.count
        tracemalloc.start()
        step = build()
        for _ in range(steps):
            step()
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        del step
        if COMPILATIONS.count == compiled:
            return peak / 2**20


def report(fig: Figure, as_json: bool) -> None:
    if as_json:
        print(json.dumps(asdict(fig)))
    else:
        peak = "" if fig.peak_mem_mib is None else f"  peak {fig.peak_mem_mib:8.1f} MiB"
        print(
            f"{fig.name:<36} B={fig.batch:<5d} {fig.env_steps_per_s:>12,.0f} env-steps/s "
            f"{fig.agent_steps_per_s:>14,.0f} agent-steps/s{peak}"
        )
    sys.stdout.flush()
