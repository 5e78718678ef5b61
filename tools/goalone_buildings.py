"""GoAlone on buildings imported with default options: success, timeouts and stuck episodes.

    python tools/goalone_buildings.py [--episodes 50] [--out DIR] [--only NAME,...]

Buildings: the second floor plan in the social_gym GDC1 data (below y = -5 m, which the benchmark
never uses), the raw GHC3 walls, and seeded synthetic plans (socialzoo.nav.floorplans: offices
along corridors, atria with pillars, winding corridors with sharp corners, grids of rooms with
0.9-1.2 m doors, a 150 m corridor). Each is imported as `socialzoo map import --walls FILE
--name NAME` does (repairs on, the drive check and its repairs included, no seed point, no
region), written to DIR, and GoAlone runs on the
first N scenarios of a seeded test set of the map (base seed 20261123, generated as `socialzoo
benchmark --maps DIR/NAME.json` generates its own; humans at most at the benchmark's crowd
density, or 5 to 25 with --spec-crowd). An episode is stuck when it times out with the robot
less than 1 m from where it stood 20 s before the end; "never moved" when it stayed within 1 m
of its start throughout.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from socialzoo.bench.map_repair import repair_by_driving
from socialzoo.bench.runner import BatchedRunner, RunSpec, Trial, env_config_for
from socialzoo.nav import floorplans
from socialzoo.nav.importers import drop_zero_length, read_table, write_vector_map
from socialzoo.nav.repair import repair_map
from socialzoo.nav.scenarios import TestSet

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "maps" / "reference" / "socialgym"
# Base seed of the evaluation scenarios (not a benchmark test set's).
EVAL_SEED = 20261123


def buildings() -> dict[str, np.ndarray]:
    """Walls (W, 4) of every evaluation building, by name."""
    gdc1 = read_table(REFERENCE / "gdc1_walls.txt", 4, "x1 y1 x2 y2")
    out = {
        "gdc1_floor2": drop_zero_length(gdc1[(gdc1[:, 1] < -5.0) & (gdc1[:, 3] < -5.0)]),
        "ghc3_raw": read_table(REFERENCE / "ghc3_walls.txt", 4, "x1 y1 x2 y2"),
    }
    for seed in (1, 2):
        out[f"office_corridor_{seed}"] = floorplans.office_corridor(seed, num_offices=10).walls
        out[f"atrium_{seed}"] = floorplans.atrium(seed).walls
        out[f"winding_corridor_{seed}"] = floorplans.winding_corridor(
            seed, num_legs=8, leg_length=(3.0, 10.0)
        ).walls
        out[f"room_grid_{seed}"] = floorplans.room_grid(seed, rows=3, cols=4).walls
    out["long_corridor"] = floorplans.long_corridor(150.0).walls
    return out


def evaluate_map(path: Path, episodes: int, batch_size: int) -> dict[str, float]:
    """GoAlone on the first `episodes` scenarios of the map's evaluation test set."""
    test_set = TestSet(str(path), EVAL_SEED, episodes, name="eval")
    spec = RunSpec(
        test_sets={"eval": test_set},
        env_configs={"eval": env_config_for(test_set)},
        policies={"goalone": {}},
        batch_size=batch_size,
    )
    start_pos: dict[int, np.ndarray] = {}
    trace: dict[int, list[np.ndarray]] = {}

    def on_step(core, row_trial, obs, actions, result) -> None:  # type: ignore[no-untyped-def]
        pos = core.state.robot_pose[:, 0, :2]
        for row, t in enumerate(row_trial):
            if t is None:
                continue
            start_pos.setdefault(t.index, pos[row].copy())
            if core.state.step_count[row] % 40 == 0:  # one sample a second
                trace.setdefault(t.index, []).append(pos[row].copy())

    results = BatchedRunner(spec).run([Trial("goalone", "eval", k) for k in range(episodes)], on_step=on_step)
    stuck = never = timeouts = 0
    for r in results:
        m = r.metrics
        if m["reached"] or m["wall_collisions"]:
            continue
        timeouts += 1
        h = np.array(trace.get(r.trial.index, [start_pos[r.trial.index]]))
        last = h[-20:]
        stuck += bool(np.hypot(*(last - last[-1]).T).max() < 1.0)
        never += bool(np.hypot(*(h - start_pos[r.trial.index]).T).max() < 1.0)
    return {
        "episodes": len(results),
        "success": sum(bool(r.metrics["success"]) for r in results),
        "reached": sum(bool(r.metrics["reached"]) for r in results),
        "human_collision_episodes": sum(r.metrics["human_collisions"] > 0 for r in results),
        "wall_collision_episodes": sum(r.metrics["wall_collisions"] > 0 for r in results),
        "timeouts": timeouts,
        "stuck": stuck,
        "never_moved": never,
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--batch-size", type=int, default=25)
    parser.add_argument("--out", type=Path, default=Path("results/buildings"))
    parser.add_argument("--only", default=None, help="comma-separated building names")
    parser.add_argument(
        "--spec-crowd",
        action="store_true",
        help="5 to 25 humans on every building (drop the walkable area: no crowd-density cap)",
    )
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    wanted = None if args.only is None else set(args.only.split(","))
    print("| building | walls | nodes | poses | repairs | GoAlone success % | reached | human coll. | "
          "wall coll. | timeouts | stuck | never moved | s |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, walls in buildings().items():
        if wanted is not None and name not in wanted:
            continue
        start = time.perf_counter()
        vector = write_vector_map(args.out / f"{name}.txt", walls)
        m, report = repair_map(name, walls, source=f"tools/goalone_buildings.py: {vector.name}")
        m, driven, _ = repair_by_driving(m)
        if args.spec_crowd:
            m = dataclasses.replace(m, walkable_area=None)
        path = m.save(args.out / f"{name}.json")
        s = evaluate_map(path, args.episodes, args.batch_size)
        print(
            f"| {name} | {m.num_walls} | {m.num_nodes} | {len(m.legal_poses)} | {len(report) + len(driven)} | "
            f"{100 * s['success'] / s['episodes']:.0f} | {s['reached']}/{s['episodes']} | "
            f"{s['human_collision_episodes']} | {s['wall_collision_episodes']} | {s['timeouts']} | "
            f"{s['stuck']} | {s['never_moved']} | {time.perf_counter() - start:.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
