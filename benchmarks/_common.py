"""Shared helpers of the benchmark scripts: timing loops, peak memory, printing figures."""

from __future__ import annotations

import argparse
import json
import sys
import time
import tracemalloc
from collections.abc import Callable
from dataclasses import asdict, dataclass


@dataclass
class Figure:
    """One measured configuration (peak_mem_mib None: not measured)."""

    name: str
    batch: int
    env_steps_per_s: float
    agent_steps_per_s: float
    peak_mem_mib: float | None


def parser(description: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--json", action="store_true", help="print one JSON object per line")
    p.add_argument("--seconds", type=float, default=3.0, help="time per configuration (s)")
    return p


def measure(step: Callable[[], None], seconds: float, warmup: int = 5) -> tuple[float, int]:
    """Calls per second of `step`, run for about `seconds` after `warmup` calls."""
    for _ in range(warmup):
        step()
    calls = 0
    start = time.perf_counter()
    while True:
        step()
        calls += 1
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return calls / elapsed, calls


def traced_peak_mib(build: Callable[[], Callable[[], None]], steps: int = 3) -> float:
    """Peak numpy/Python allocation (MiB) of building a workload and running a few steps of it."""
    tracemalloc.start()
    step = build()
    for _ in range(steps):
        step()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
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
