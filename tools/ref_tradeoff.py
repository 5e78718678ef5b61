"""Ref's parameters against its success and blame: is the engineered rule on its own Pareto front?

    python tools/ref_tradeoff.py [--trials 400] [--workers 2] [--map gdc1]
                                 [--learned NAME:FILE ...] [--halt-offsets -1,-0.5,0,0.5,1]

Runs Ref (socialzoo.agents.engineered.RefConfig) for every combination of corridor half-width
(0.45, 0.62, 0.8 m), lookahead margin (0.4, 0.9, 1.5 m) and heading tolerance (0.8, 1.3 rad) on
the first N scenarios of the map's validation set (`<map>-val`: never a test set) and prints one
Markdown row per setting: success, mean blame, human-collision and not-reached episodes, and
whether some other setting has at least its success with less blame ("dominated"). The paper's
setting is (0.62, 0.9, 0.8). A learner that only imitates Ref more closely can at best land on
this front; docs/reproduce.md ("A learned policy against Ref") gives the measured table.

`--learned NAME:FILE` adds a learned policy's own trade-off on the same scenarios: the policy with
its Halt score raised by each of `--halt-offsets` (a copy of the file with the last layer's Halt
bias shifted, written to a temporary folder), so it halts more (positive) or less (negative). Its
rows say whether some Ref setting has at least their success with less blame: a learner that
gets past Ref's front has a row that no Ref setting dominates at Ref's success or more.
"""

from __future__ import annotations

import argparse
import itertools
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.agents.mlp import MlpPolicy
from socialzoo.bench.runner import RunSpec, Trial, env_config_for, run_chunk
from socialzoo.nav.scenarios import validation_set
from socialzoo.nav.subpolicies import HALT

GRID = {
    "corridor_half_width": (0.45, 0.62, 0.8),
    "lookahead_margin": (0.4, 0.9, 1.5),
    "heading_tolerance": (0.8, 1.3),
}


def evaluate(map_name: str, trials: int, params: dict[str, float], policy: str = "ref") -> dict[str, Any]:
    """`policy` (Ref, or "NAME:FILE") with keyword arguments `params` on the first `trials`
    validation scenarios of `map_name`."""
    test_set = validation_set(map_name)
    spec = RunSpec(
        test_sets={test_set.name: test_set},
        env_configs={test_set.name: env_config_for(test_set)},
        policies={policy: params},
        batch_size=min(trials, 250),
    )
    metrics = [r.metrics for r in run_chunk([Trial(policy, test_set.name, k) for k in range(trials)], spec)]
    return {
        **params,
        "success": float(np.mean([m["success"] for m in metrics])),
        "blame": float(np.mean([m["mean_blame"] for m in metrics])),
        "human_collision": int(sum(m["human_collisions"] > 0 for m in metrics)),
        "not_reached": int(sum(not m["reached"] for m in metrics)),
    }


def with_halt_offset(spec: str, offset: float, folder: Path) -> str:
    """The spec ("NAME:FILE") of a copy of the learned policy `spec` (an MlpPolicy file's
    "NAME:FILE") whose Halt score is raised by `offset`, written into `folder`."""
    name, _, path = spec.partition(":")
    policy = MlpPolicy.load(path)
    weight, bias = policy.layers[-1]
    shifted = bias.copy()
    shifted[HALT] += offset
    policy.layers = [*policy.layers[:-1], (weight, shifted)]
    header = dict(policy.header)
    header["training"] = {**header.get("training", {}), "halt_offset": offset, "from": path}
    out = policy.save(folder / f"{Path(path).stem}_{len(list(folder.iterdir()))}.safetensors", header)
    return f"{name}:{out}"


def dominated(row: dict[str, Any], rows: list[dict[str, Any]]) -> bool:
    """Whether another setting has at least `row`'s success with less blame."""
    return any(o["success"] >= row["success"] and o["blame"] < row["blame"] for o in rows if o is not row)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=400, help="validation scenarios per setting")
    parser.add_argument("--workers", type=int, default=2, help="settings evaluated side by side")
    parser.add_argument("--map", default="gdc1", help="map whose validation set is driven")
    parser.add_argument(
        "--learned",
        nargs="*",
        default=[],
        metavar="NAME:FILE",
        help="learned MlpPolicy files to trace beside Ref",
    )
    parser.add_argument(
        "--halt-offsets",
        default="-1,-0.5,0,0.5,1",
        help="comma-separated Halt score offsets of each learned policy",
    )
    args = parser.parse_args()
    offsets = [float(x) for x in args.halt_offsets.split(",")]
    settings = [dict(zip(GRID, values, strict=True)) for values in itertools.product(*GRID.values())]
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(max_workers=args.workers) as pool:
        learned = [(spec, o, with_halt_offset(spec, o, Path(tmp))) for spec in args.learned for o in offsets]
        policies = ["ref"] * len(settings) + [shifted for _, _, shifted in learned]
        params = settings + [{}] * len(learned)
        n = len(policies)
        rows = list(pool.map(evaluate, [args.map] * n, [args.trials] * n, params, policies))
    ref_rows = rows[: len(settings)]
    print(f"| {' | '.join(GRID)} | success % | blame | human collision | not reached | dominated |")
    print("|" + "---|" * (len(GRID) + 5))
    for row in ref_rows:
        worse = dominated(row, ref_rows)
        values = " | ".join(f"{row[name]:g}" for name in GRID)
        print(
            f"| {values} | {100 * row['success']:.1f} | {row['blame']:.4f} | {row['human_collision']} "
            f"| {row['not_reached']} | {'yes' if worse else 'no'} |"
        )
    if learned:
        print("\n| learned policy | Halt offset | success % | blame | dominated by a Ref setting |")
        print("|---|---|---|---|---|")
        for (spec, offset, _), row in zip(learned, rows[len(settings) :], strict=True):
            worse = dominated(row, ref_rows)
            success = f"{100 * row['success']:.1f}"
            print(f"| {spec} | {offset:+g} | {success} | {row['blame']:.4f} | {'yes' if worse else 'no'} |")
    print(
        f"\n{len(rows)} policies x {args.trials} {args.map}-val scenarios in {time.perf_counter() - start:.0f} s"
    )


if __name__ == "__main__":
    main()
