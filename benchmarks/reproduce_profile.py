"""Where the time of `socialzoo reproduce` goes: measured rates of its pieces at a small size, and
the full protocol's wall time extrapolated from them (1 seed, and K seeds).

Measures in this process (one CPU), after a warm-up:
- an RL-curve checkpoint evaluation: the shipped PPO on the first curve scenarios (gdc1-test), one
  batch (what one checkpoint of `rl-curves` costs);
- the RL-curve batch: C PPO and C DQN checkpoints and Ref sharing one batch (as `rl-curves` runs
  them), with the checkpoints stacked (socialzoo.bench.policy_stack) and without;
- the performance batch: the seven policies on gdc1-test and on ghc3-test;
- PPO and DQN training rates (env steps/s) on a short run, and the validation evaluation of one
  checkpoint (the in-training checkpoint choice).
Each evaluation reports CPU seconds per row-step and mean episode steps; the extrapolation
multiplies the protocol's trials by them and divides by the workers (2 processes, 2 cores).

Run: python benchmarks/reproduce_profile.py [--json] [--curve-trials 4] [--perf-trials 16]
     [--checkpoints 21] [--train-steps 4000] [--seeds 5]
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from _common import positive_int

from socialzoo.reproduce.plan import full_settings

# The full protocol's counts (socialzoo.reproduce.plan.full_settings; SPEC section 10).
FULL = full_settings()
CHECKPOINTS = FULL.rl_total_steps // FULL.rl_checkpoint_every  # 42 per RL run
CURVE_TRIALS = FULL.curve_trials
LFD_POLICIES = 2 * len(FULL.lfd_sizes) + 1  # BC and GAIL at 5 sizes, PIPS
LFD_TRIALS = FULL.lfd_trials
TEST_TRIALS = FULL.performance_trials
VALIDATION_EVALS = FULL.rl_total_steps // FULL.select_every  # checkpoints chosen among, per RL run
VALIDATION_TRIALS = FULL.select_trials
RL_STEPS = FULL.rl_total_steps
# Training wall times of the other trainers from the last full run (REPRODUCTION.md, the
# 2-core machine when quiet): BC 0.5-1 min each, GAIL 1.2-2.8 min each, PIPS 12 s, demos 200 s.
OTHER_TRAINING_S = 5 * 37 + 5 * 106 + 12
DEMOS_S = 200


def _evaluate(specs: list[str], test_set: str, trials: int, batch: int, stack: bool = True) -> dict[str, Any]:
    from socialzoo.bench.runner import BatchedRunner, Trial, make_spec

    spec = make_spec(specs, [test_set], batch_size=batch)
    BatchedRunner(spec).run([Trial(specs[0], test_set, 0)])  # warm-up: kernels, map, files
    todo = [Trial(p, test_set, k) for p in specs for k in range(trials)]
    runner = BatchedRunner(spec, stack_policies=stack)
    wall, cpu = time.perf_counter(), time.process_time()
    results = runner.run(todo)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    row_steps = runner.stats.body_row_steps + runner.stats.tail_row_steps
    steps = sum(int(r.metrics["steps"]) for r in results)
    return {
        "trials": len(todo),
        "wall_s": round(wall, 2),
        "cpu_s": round(cpu, 2),
        "row_steps": row_steps,
        "mean_episode_steps": round(steps / len(todo), 1),
        "cpu_us_per_row_step": round(1e6 * cpu / row_steps, 1),
        "cpu_s_per_trial": round(cpu / len(todo), 3),
        "success": round(sum(bool(r.metrics["success"]) for r in results) / len(results), 3),
    }


class _Enough(Exception):
    pass


def _body_rate(
    specs: list[str], test_set: str, batch: int, finished: int, stack: bool = True
) -> dict[str, Any]:
    """CPU microseconds per row-step while the batch is full (the body of a long evaluation): a run
    of many trials stopped once `finished` of them have finished."""
    from socialzoo.bench.runner import BatchedRunner, Trial, make_spec

    spec = make_spec(specs, [test_set], batch_size=batch)
    BatchedRunner(spec).run([Trial(specs[0], test_set, 0)])  # warm-up
    runner = BatchedRunner(spec, stack_policies=stack)
    count = [0]

    def stop(done: list[Any]) -> None:
        count[0] += len(done)
        if count[0] >= finished:
            raise _Enough

    todo = [Trial(p, test_set, k) for p in specs for k in range(max(1, 4 * batch // len(specs) + 1))]
    wall, cpu = time.perf_counter(), time.process_time()
    try:
        runner.run(todo, on_results=stop)
    except _Enough:
        pass
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    row_steps = runner.stats.body_row_steps + runner.stats.tail_row_steps
    return {
        "batch": batch,
        "row_steps": row_steps,
        "cpu_s": round(cpu, 2),
        "wall_s": round(wall, 2),
        "cpu_us_per_row_step": round(1e6 * cpu / row_steps, 1),
    }


def _copies(folder: Path, algo: str, count: int) -> list[str]:
    from socialzoo.agents import SHIPPED_DIR

    specs = []
    for k in range(count):
        path = folder / f"{algo}_{k}.safetensors"
        shutil.copy(Path(SHIPPED_DIR) / f"{algo}.safetensors", path)
        specs.append(f"{algo}:{path}")
    return specs


def _train_rate(algo: str, steps: int, folder: Path) -> dict[str, Any]:
    from socialzoo.train import trainer_args, trainer_function

    args = trainer_args(algo)(out=folder / algo, total_steps=steps, checkpoint_every=2_000, progress=False)
    wall, cpu = time.perf_counter(), time.process_time()
    trainer_function(algo)(args)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return {
        "steps": steps,
        "wall_s": round(wall, 1),
        "cpu_s": round(cpu, 1),
        "steps_per_cpu_s": round(steps / cpu, 1),
    }


def _validation(folder: Path, trials: int) -> dict[str, Any]:
    from socialzoo.agents import SHIPPED_DIR
    from socialzoo.train.validation import validation_evaluator

    evaluate = validation_evaluator("ppo", "gdc1", trials)
    path = Path(SHIPPED_DIR) / "ppo.safetensors"
    evaluate(path)  # warm-up
    wall, cpu = time.perf_counter(), time.process_time()
    metrics = evaluate(path)
    return {
        "trials": trials,
        "wall_s": round(time.perf_counter() - wall, 1),
        "cpu_s": round(time.process_time() - cpu, 1),
        "success": round(metrics["success"], 3),
    }


def extrapolate(figures: dict[str, Any], seeds: int, workers: int = 2, batch: int = 64) -> dict[str, float]:
    """Wall seconds of each part of the full protocol with `seeds` seeds on `workers` cores, the
    evaluations at `batch` rows per worker (ghc3 at gdc1's cost per row-step)."""
    body = figures.get(f"body_performance_gdc1_B{batch}")
    body_curves = figures.get(f"body_curves_B{batch}")
    if body is None or body_curves is None:  # without body measures: whole small runs (tails included)
        curve = figures["curve_batch_stacked"]["cpu_s_per_trial"]
        perf = (
            figures["performance_gdc1"]["cpu_s_per_trial"],
            figures["performance_ghc3"]["cpu_s_per_trial"],
        )
    else:  # the body's cost per row-step times each set's mean episode length
        curve = (
            1e-6 * body_curves["cpu_us_per_row_step"] * figures["curve_batch_stacked"]["mean_episode_steps"]
        )
        perf = tuple(
            1e-6 * body["cpu_us_per_row_step"] * figures[f"performance_{m}"]["mean_episode_steps"]
            for m in ("gdc1", "ghc3")
        )
    one_ckpt = figures["curve_checkpoint"]["cpu_s_per_trial"]
    ppo = RL_STEPS / figures["train_ppo"]["steps_per_cpu_s"]
    dqn = RL_STEPS / figures["train_dqn"]["steps_per_cpu_s"]
    validation = (
        VALIDATION_EVALS
        * figures["validation"]["cpu_s"]
        * VALIDATION_TRIALS
        / figures["validation"]["trials"]
    )
    learned = 5
    trainings = seeds * (ppo + dqn + 2 * validation + OTHER_TRAINING_S)
    parts = {
        "demos": DEMOS_S,
        # Trainings of every seed side by side on the workers (one thread each).
        "training (all parts)": trainings / workers,
        "rl-curves evaluation": seeds * 2 * CHECKPOINTS * CURVE_TRIALS * curve / workers
        + CURVE_TRIALS * one_ckpt / workers,
        "lfd evaluation": seeds * LFD_POLICIES * LFD_TRIALS * (perf[0] * 0.9) / workers,
        "performance": TEST_TRIALS * (2 + learned * seeds) * perf[0] / workers,
        "transfer": TEST_TRIALS * (2 + learned * seeds) * perf[1] / workers,
    }
    parts["all"] = sum(parts.values())
    return {k: round(v) for k, v in parts.items()}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--json", action="store_true", help="print one JSON object")
    counts = (  # option, default, help: each a count of at least 1
        ("--curve-trials", 4, "scenarios per checkpoint in the curve batch"),
        ("--checkpoint-trials", 64, "scenarios of the one-checkpoint evaluation"),
        ("--perf-trials", 16, "scenarios per policy in the performance batch"),
        ("--checkpoints", 21, "PPO and DQN checkpoints in the curve batch"),
        ("--train-steps", 4_000, "env steps of each training-rate run"),
        ("--validation-trials", 32, "validation scenarios of one evaluation"),
        ("--seeds", 5, "also extrapolate this many seeds"),
        ("--batch-size", 64, None),
    )
    for option, default, text in counts:
        p.add_argument(option, type=positive_int, default=default, help=text)
    p.add_argument(
        "--body-batches",
        type=lambda t: [positive_int(x) for x in t.split(",")],
        default=[64, 256],
        help="batch sizes of the body-rate measures (comma-separated)",
    )
    p.add_argument(
        "--body-finished", type=positive_int, default=40, help="trials finished before a body measure stops"
    )
    args = p.parse_args()
    figures: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        checkpoints = _copies(folder, "ppo", args.checkpoints) + _copies(folder, "dqn", args.checkpoints)
        figures["curve_checkpoint"] = _evaluate(
            checkpoints[:1], "gdc1-test", args.checkpoint_trials, args.checkpoint_trials
        )
        for stack in (True, False):
            figures[f"curve_batch_{'stacked' if stack else 'unstacked'}"] = _evaluate(
                [*checkpoints, "ref"], "gdc1-test", args.curve_trials, args.batch_size, stack
            )
        seven = ["goalone", "ref", "bc", "gail", "pips", "dqn", "ppo"]
        for map_name in ("gdc1", "ghc3"):
            figures[f"performance_{map_name}"] = _evaluate(
                seven, f"{map_name}-test", args.perf_trials, args.batch_size
            )
        for batch in args.body_batches:
            figures[f"body_performance_gdc1_B{batch}"] = _body_rate(
                seven, "gdc1-test", batch, args.body_finished
            )
            figures[f"body_curves_B{batch}"] = _body_rate(
                [*checkpoints, "ref"], "gdc1-test", batch, args.body_finished
            )
        figures["validation"] = _validation(folder, args.validation_trials)
        for algo in ("ppo", "dqn"):
            figures[f"train_{algo}"] = _train_rate(algo, args.train_steps, folder)
    for batch in args.body_batches:
        figures[f"full_protocol_s_1_seed_B{batch}"] = extrapolate(figures, 1, batch=batch)
        figures[f"full_protocol_s_{args.seeds}_seeds_B{batch}"] = extrapolate(
            figures, args.seeds, batch=batch
        )
    if args.json:
        print(json.dumps(figures))
    else:
        for name, value in figures.items():
            print(f"{name}: {value}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
