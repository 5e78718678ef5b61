"""Ref's parameters against its success and blame: is the engineered rule on its own Pareto front?

    python tools/ref_tradeoff.py [--trials 400] [--workers 2] [--map gdc1]

Runs Ref (socialzoo.agents.engineered.RefConfig) for every combination of corridor half-width
(0.45, 0.62, 0.8 m), lookahead margin (0.4, 0.9, 1.5 m) and heading tolerance (0.8, 1.3 rad) on
the first N scenarios of the map's validation set (`<map>-val`: never a test set) and prints one
Markdown row per setting: success, mean blame, human-collision and not-reached episodes, and
whether some other setting has at least its success with less blame ("dominated"). The paper's
setting is (0.62, 0.9, 0.8). A learner that only imitates Ref more closely can at best land on
this front; docs/reproduce.md ("A learned policy against Ref") gives the measured table.
"""

from __future__ import annotations

import argparse
import itertools
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np

from socialzoo.bench.runner import RunSpec, Trial, env_config_for, run_chunk
from socialzoo.nav.scenarios import validation_set

GRID = {
    "corridor_half_width": (0.45, 0.62, 0.8),
    "lookahead_margin": (0.4, 0.9, 1.5),
    "heading_tolerance": (0.8, 1.3),
}


def evaluate(map_name: str, trials: int, params: dict[str, float]) -> dict[str, Any]:
    """Ref with `params` on the first `trials` validation scenarios of `map_name`."""
    test_set = validation_set(map_name)
    spec = RunSpec(
        test_sets={test_set.name: test_set},
        env_configs={test_set.name: env_config_for(test_set)},
        policies={"ref": params},
        batch_size=min(trials, 250),
    )
    metrics = [r.metrics for r in run_chunk([Trial("ref", test_set.name, k) for k in range(trials)], spec)]
    return {
        **params,
        "success": float(np.mean([m["success"] for m in metrics])),
        "blame": float(np.mean([m["mean_blame"] for m in metrics])),
        "human_collision": int(sum(m["human_collisions"] > 0 for m in metrics)),
        "not_reached": int(sum(not m["reached"] for m in metrics)),
    }


def dominated(row: dict[str, Any], rows: list[dict[str, Any]]) -> bool:
    """Whether another setting has at least `row`'s success with less blame."""
    return any(o["success"] >= row["success"] and o["blame"] < row["blame"] for o in rows if o is not row)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=400, help="validation scenarios per setting")
    parser.add_argument("--workers", type=int, default=2, help="settings evaluated side by side")
    parser.add_argument("--map", default="gdc1", help="map whose validation set is driven")
    args = parser.parse_args()
    settings = [dict(zip(GRID, values, strict=True)) for values in itertools.product(*GRID.values())]
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        rows = list(pool.map(evaluate, [args.map] * len(settings), [args.trials] * len(settings), settings))
    print(f"| {' | '.join(GRID)} | success % | blame | human collision | not reached | dominated |")
    print("|" + "---|" * (len(GRID) + 5))
    for row in rows:
        worse = dominated(row, rows)
        values = " | ".join(f"{row[name]:g}" for name in GRID)
        print(
            f"| {values} | {100 * row['success']:.1f} | {row['blame']:.4f} | {row['human_collision']} "
            f"| {row['not_reached']} | {'yes' if worse else 'no'} |"
        )
    print(
        f"\n{len(rows)} settings x {args.trials} {args.map}-val scenarios in {time.perf_counter() - start:.0f} s"
    )


if __name__ == "__main__":
    main()
