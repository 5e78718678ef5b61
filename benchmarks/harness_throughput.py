"""Evaluation-harness throughput: trials/s of the batched runner (one process, B env rows) over a
whole test set, in its body (while the trial queue still refills rows) and in its tail (after the
queue ran dry, when only the last B episodes are left to finish).

Run: python benchmarks/harness_throughput.py [--json] [--map gdc1] [--trials 100] [--batch-size 64]
     [--no-compact]

The tail starts at the step on which the last queued trial got a row: with N trials and B rows
that is the step on which the (N - B)-th trial finished, so the split is measured from the
outside, from the finish times alone, whatever the runner does inside.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from _common import positive_int

from socialzoo.bench.runner import BatchedRunner, Trial, TrialResult, make_spec


def rate(count: int, seconds: float) -> float | None:
    """`count` per second, or None (JSON's null) for a part that took no time: with N <= B there is
    no body, and NaN is not JSON."""
    return count / seconds if seconds > 0 else None


def per_s(value: float | int | str | None, digits: int) -> str:
    """A rate to print, "-" where there is none."""
    return "-" if value is None else f"{value:.{digits}f}"


def measure(
    map_name: str, policies: list[str], trials: int, batch: int, compact: bool = True
) -> dict[str, float | int | str | None]:
    """Run `trials` scenarios of `<map>-quick` per policy once; return the figures."""
    test_set = f"{map_name}-quick"
    spec = make_spec(policies, [test_set], batch_size=batch)
    # Warm-up: compiled kernels, the map's tables and the policies, outside the timed run.
    BatchedRunner(spec).run([Trial(p, test_set, 0) for p in policies])
    runner = BatchedRunner(spec) if compact else BatchedRunner(spec, compact_tail=False)
    todo = [Trial(p, test_set, k) for p in policies for k in range(trials)]
    n, b = len(todo), min(batch, len(todo))
    finishes: list[tuple[float, float, int]] = []

    def clocks() -> tuple[float, float]:
        return time.perf_counter(), time.process_time()

    def on_results(done: list[TrialResult]) -> None:
        finishes.append((*clocks(), len(done)))

    start, start_cpu = clocks()
    runner.run(todo, on_results=on_results)
    end, end_cpu = clocks()
    count, (tail_start, tail_start_cpu), body_trials = 0, (start, start_cpu), 0
    for when, when_cpu, k in finishes:  # with N <= B every trial had a row from the start: no body
        if count >= n - b:
            break
        count += k
        tail_start, tail_start_cpu, body_trials = when, when_cpu, count
    body_s, tail_s = tail_start - start, end - tail_start
    body_cpu, tail_cpu = tail_start_cpu - start_cpu, end_cpu - tail_start_cpu
    figures: dict[str, float | int | str | None] = {
        "name": f"BatchedRunner {test_set} {'+'.join(policies)}{'' if compact else ' (no compaction)'}",
        "batch": b,
        "trials": n,
        "seconds": end - start,
        "trials_per_s": rate(n, end - start),
        "body_trials": body_trials,
        "body_trials_per_s": rate(body_trials, body_s),
        "tail_trials": n - body_trials,
        "tail_seconds": tail_s,
        "tail_trials_per_s": rate(n - body_trials, tail_s),
        # Per CPU second of this process: steadier than wall time on a shared machine.
        "cpu_seconds": end_cpu - start_cpu,
        "body_trials_per_cpu_s": rate(body_trials, body_cpu),
        "tail_trials_per_cpu_s": rate(n - body_trials, tail_cpu),
    }
    stats = getattr(runner, "stats", None)  # row counts, where the runner keeps them
    if stats is not None:
        figures.update(
            body_steps=stats.body_steps,
            body_row_steps=stats.body_row_steps,
            tail_steps=stats.tail_steps,
            tail_row_steps=stats.tail_row_steps,
            compactions=stats.compactions,
        )
    return figures


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--map", default="gdc1", help="map of the quick test set (default gdc1)")
    p.add_argument("--policies", default="goalone,ref", help="comma-separated policies")
    p.add_argument("--trials", type=positive_int, default=100, help="scenarios per policy (at most 100)")
    p.add_argument("--batch-size", type=positive_int, default=64, help="env rows stepped together (B)")
    p.add_argument("--no-compact", action="store_true", help="keep finished rows in the batch (the old tail)")
    args = p.parse_args()
    fig = measure(args.map, args.policies.split(","), args.trials, args.batch_size, not args.no_compact)
    if args.json:
        print(json.dumps(fig, allow_nan=False))
    else:
        print(
            f"{fig['name']}  B={fig['batch']}  {fig['trials']} trials in {fig['seconds']:.1f} s: "
            f"{per_s(fig['trials_per_s'], 1)} trials/s overall, {per_s(fig['body_trials_per_s'], 1)} in the body "
            f"({fig['body_trials']} trials), {per_s(fig['tail_trials_per_s'], 1)} in the tail "
            f"({fig['tail_trials']} trials, {fig['tail_seconds']:.1f} s)"
        )
        print(
            f"  per CPU second: {per_s(fig['body_trials_per_cpu_s'], 2)} trials in the body, "
            f"{per_s(fig['tail_trials_per_cpu_s'], 2)} in the tail ({fig['cpu_seconds']:.1f} CPU s in all)"
        )
        if "tail_row_steps" in fig:
            print(
                f"  rows stepped: body {fig['body_row_steps']:,} over {fig['body_steps']:,} steps, "
                f"tail {fig['tail_row_steps']:,} over {fig['tail_steps']:,} steps, "
                f"{fig['compactions']} compactions"
            )
    sys.stdout.flush()


if __name__ == "__main__":
    main()
