"""Ref's parameters against its success and blame: is the engineered rule on its own Pareto front?"""

from __future__ import annotations

import itertools
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.agents import POLICIES, check_policy_spec, policy_file, split_policy_spec
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.bench.runner import RunSpec, Trial, env_config_for, run_chunk
from socialzoo.core.validation import check_int
from socialzoo.nav.subpolicies import HALT
from socialzoo.scenarios.scenario_sets import validation_set

# The class of the policies whose Halt score the study shifts (socialzoo.agents.POLICIES).
_MLP_POLICY = "socialzoo.agents.mlp:MlpPolicy"
GRID = {
    "corridor_half_width": (0.45, 0.62, 0.8),
    "lookahead_margin": (0.4, 0.9, 1.5),
    "heading_tolerance": (0.8, 1.3),
}


@dataclass(frozen=True, kw_only=True)
class RefTradeoffConfig:
    """What the study runs.

    Attributes:
        trials: validation scenarios per setting (the first ones of `<map>-val`).
        workers: settings evaluated side by side (local processes).
        map: the map whose validation set is driven.
        learned: learned MlpPolicy files traced beside Ref: "NAME:FILE", or a learned policy's
            name alone ("dagger") for its shipped file.
        halt_offsets: Halt score offsets of each learned policy.
    """

    trials: int = 400
    workers: int = 2
    map: str = "gdc1"
    learned: tuple[str, ...] = ()
    halt_offsets: tuple[float, ...] = (-1.0, -0.5, 0.0, 0.5, 1.0)

    def __post_init__(self) -> None:
        check_int("RefTradeoffConfig", "trials", self.trials, low=1)
        check_int("RefTradeoffConfig", "workers", self.workers, low=1)
        for spec in self.learned:
            try:
                check_policy_spec(spec)
            except ValueError as err:
                raise ValueError(f"RefTradeoffConfig.learned: {err}") from None
            if POLICIES[split_policy_spec(spec)[0]] != _MLP_POLICY:
                mlp = ", ".join(k for k, v in POLICIES.items() if v == _MLP_POLICY)
                raise ValueError(f"RefTradeoffConfig.learned: {spec!r} is not a learned MlpPolicy ({mlp})")


@dataclass(frozen=True)
class RefTradeoff:
    """What the study measured.

    Attributes:
        config: what it ran.
        ref_rows: one row per Ref setting (GRID's names, success, blame, human_collision,
            not_reached), in GRID's order.
        learned_rows: (learned spec, Halt offset, row) per learned policy and offset.
        seconds: wall time.
    """

    config: RefTradeoffConfig
    ref_rows: list[dict[str, Any]]
    learned_rows: list[tuple[str, float, dict[str, Any]]]
    seconds: float


def ref_settings() -> list[dict[str, float]]:
    """Every combination of GRID's values, as Ref keyword arguments."""
    return [dict(zip(GRID, values, strict=True)) for values in itertools.product(*GRID.values())]


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
    "NAME:FILE", or a learned policy's name for its shipped file) whose Halt score is raised by
    `offset`, written into `folder`."""
    name = split_policy_spec(spec)[0]
    path = policy_file(spec)
    if path is None:
        raise ValueError(f"policy {spec!r} has no file")
    policy = MlpPolicy.load(path)
    weight, bias = policy.layers[-1]
    shifted = bias.copy()
    shifted[HALT] += offset
    policy.layers = [*policy.layers[:-1], (weight, shifted)]
    header = dict(policy.header)
    header["training"] = {**header.get("training", {}), "halt_offset": offset, "from": spec}
    out = policy.save(folder / f"{path.stem}_{len(list(folder.iterdir()))}.safetensors", header)
    return f"{name}:{out}"


def dominated(row: dict[str, Any], rows: list[dict[str, Any]]) -> bool:
    """Whether another setting has at least `row`'s success with less blame."""
    return any(o["success"] >= row["success"] and o["blame"] < row["blame"] for o in rows if o is not row)


def run_ref_tradeoff(config: RefTradeoffConfig) -> RefTradeoff:
    """Every Ref setting of GRID, and each learned policy at each Halt offset, on the first
    config.trials validation scenarios of config.map.

    Ref (socialzoo.agents.engineered.RefConfig) runs for every combination of corridor half-width (0.45, 0.62,
    0.8 m), lookahead margin (0.4, 0.9, 1.5 m) and heading tolerance (0.8, 1.3 rad) on the first N scenarios
    of the map's validation set (`<map>-val`: never a test set); the table has one Markdown row per setting:
    success, mean blame, human-collision and not-reached episodes, and whether some other setting has at least
    its success with less blame ("dominated"). The paper's setting is (0.62, 0.9, 0.8).

    `learned` ("NAME:FILE", or a learned policy's name for its shipped file) adds a learned policy's own trade-off
    on the same scenarios: the policy with its Halt score raised by each of `halt_offsets` (a copy of the file with
    the last layer's Halt bias shifted, written to a temporary folder), so it halts more (positive) or less
    (negative). Its rows say whether some Ref setting has at least their success with less blame: a learner that
    gets past Ref's front has a row that no Ref setting dominates at Ref's success or more.
    """
    settings = ref_settings()
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(max_workers=config.workers) as pool:
        learned = [
            (spec, offset, with_halt_offset(spec, offset, Path(tmp)))
            for spec in config.learned
            for offset in config.halt_offsets
        ]
        policies = ["ref"] * len(settings) + [shifted for _, _, shifted in learned]
        params = settings + [{}] * len(learned)
        n = len(policies)
        rows = list(pool.map(evaluate, [config.map] * n, [config.trials] * n, params, policies))
    learned_rows = [
        (spec, offset, row) for (spec, offset, _), row in zip(learned, rows[len(settings) :], strict=True)
    ]
    return RefTradeoff(config, rows[: len(settings)], learned_rows, time.perf_counter() - start)


def tradeoff_table(result: RefTradeoff) -> str:
    """The study as Markdown: Ref's settings, the learned policies' rows (if any), and a last line
    with the count of policies, scenarios and seconds."""
    ref_rows = result.ref_rows
    lines = [
        f"| {' | '.join(GRID)} | success % | blame | human collision | not reached | dominated |",
        "|" + "---|" * (len(GRID) + 5),
    ]
    for row in ref_rows:
        values = " | ".join(f"{row[name]:g}" for name in GRID)
        lines.append(
            f"| {values} | {100 * row['success']:.1f} | {row['blame']:.4f} | {row['human_collision']} "
            f"| {row['not_reached']} | {_yes_no(dominated(row, ref_rows))} |"
        )
    if result.learned_rows:
        lines += [
            "",
            "| learned policy | Halt offset | success % | blame | dominated by a Ref setting |",
            "|---|---|---|---|---|",
        ]
        for spec, offset, row in result.learned_rows:
            success = f"{100 * row['success']:.1f}"
            worse = _yes_no(dominated(row, ref_rows))
            lines.append(f"| {spec} | {offset:+g} | {success} | {row['blame']:.4f} | {worse} |")
    config = result.config
    count = len(ref_rows) + len(result.learned_rows)
    lines += [
        "",
        f"{count} policies x {config.trials} {config.map}-val scenarios in {result.seconds:.0f} s",
    ]
    return "\n".join(lines) + "\n"


def _yes_no(flag: bool) -> str:
    return "yes" if flag else "no"
