"""GoAlone on real floor plans from a folder: import with default options, success and failure causes.

    python tools/drive_buildings.py DIR [--episodes 30] [--out OUT] [--only NAME,...] [--pictures]

DIR holds AMRL vector maps, NAME.vectormap.txt, each optionally with its navigation graph
NAME.navigation.json. Each building is imported as `socialzoo map import --walls
NAME.vectormap.txt [--nav NAME.navigation.json] --name NAME` does (default options), written to
OUT/NAME.json, and GoAlone runs on the first N scenarios of the test set `socialzoo benchmark
--maps OUT/NAME.json` generates (base seed 20220100, stored in OUT/test_sets). The table gives
success and every failure by cause (socialzoo.env.metrics.failure_cause: human collision, wall
collision, stuck, timeout while moving). With --pictures each failure is drawn to
OUT/NAME-fail-K.png (walls, plan, the robot's track, start and goal). Nothing here is data of
the repository: the floor plans are read through the path argument only.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.runner import BatchedRunner, RunSpec, Trial, env_config_for
from socialzoo.bench.test_sets import stored_test_set
from socialzoo.env.metrics import FAILURE_CAUSES, failure_cause
from socialzoo.nav.maps import Map


def import_building(
    walls_file: Path, nav_file: Path | None, name: str, out: Path
) -> tuple[Map | None, str, str]:
    """(map or None, what the import said, its status) for one building, as `socialzoo map import`."""
    import contextlib
    import io

    from socialzoo.cli import map_cmd

    args = [
        "--walls", str(walls_file), "--name", name, "--out", str(out / f"{name}.json"),
    ]  # fmt: skip
    if nav_file is not None:
        args += ["--nav", str(nav_file)]
    parser = argparse.ArgumentParser()
    map_cmd.register(parser.add_subparsers())
    ns = parser.parse_args(["map", "import", *args])
    text = io.StringIO()
    with contextlib.redirect_stdout(text), contextlib.redirect_stderr(text):
        status = ns.func(ns)
    if status != 0:
        return None, text.getvalue(), f"refused ({status})"
    from socialzoo.nav.maps import read_map

    return read_map(out / f"{name}.json"), text.getvalue(), "ok"


def evaluate(map_path: Path, out: Path, episodes: int, batch_size: int) -> tuple[list[Any], dict]:
    """GoAlone on the first `episodes` scenarios of the map's generated test set."""
    test_set = stored_test_set(str(map_path), out, episodes)
    spec = RunSpec(
        test_sets={"eval": test_set},
        env_configs={"eval": env_config_for(test_set)},
        policies={"goalone": {}},
        batch_size=batch_size,
    )
    traces: dict[int, list[np.ndarray]] = {}
    plans: dict[int, np.ndarray] = {}

    def on_step(core, row_trial, obs, actions, result) -> None:  # type: ignore[no-untyped-def]
        pos = core.state.robot_pose[:, 0, :2]
        for row, t in enumerate(row_trial):
            if t is None:
                continue
            if t.index not in plans:
                p = core.navigator.plans
                plans[t.index] = p.paths[row, 0, : p.lengths[row, 0]].copy()
            if core.state.step_count[row] % 10 == 0:
                traces.setdefault(t.index, []).append(pos[row].copy())

    trials = [Trial("goalone", "eval", k) for k in range(episodes)]
    results = BatchedRunner(spec).run(trials, on_step=on_step)
    extra = {"traces": traces, "plans": plans, "test_set": test_set}
    return results, extra


def draw_failure(m: Map, scenario: Any, trace: np.ndarray, plan: np.ndarray, title: str, path: Path) -> None:
    """Walls around the episode, its first plan, the robot's track, start (green) and goal (red)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    fig, ax = plt.subplots(figsize=(9, 8))
    pts = np.concatenate((trace, plan, scenario.robot_start[None, :2], scenario.robot_goal[None, :2]))
    lo, hi = pts.min(axis=0) - 3.0, pts.max(axis=0) + 3.0
    walls = np.asarray(m.walls).reshape(-1, 2, 2)
    ax.add_collection(LineCollection(walls, colors="0.1", linewidths=0.8))
    if len(m.edges):
        ax.add_collection(LineCollection(m.nodes[m.edges], colors="tab:blue", linewidths=0.5, alpha=0.4))
    ax.plot(plan[:, 0], plan[:, 1], "--", color="tab:blue", lw=1)
    ax.plot(trace[:, 0], trace[:, 1], "-", color="tab:orange", lw=1.2)
    ax.plot(trace[-1, 0], trace[-1, 1], "x", color="k", ms=9)
    s, g = scenario.robot_start, scenario.robot_goal
    ax.plot(*s[:2], "o", color="tab:green", ms=7)
    ax.plot(*g[:2], "o", color="tab:red", ms=7)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("buildings", type=Path, help="folder of NAME.vectormap.txt [+ NAME.navigation.json]")
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--batch-size", type=int, default=30)
    parser.add_argument("--out", type=Path, default=Path("/tmp/drive_buildings"))
    parser.add_argument("--only", default=None, help="comma-separated building names")
    parser.add_argument("--pictures", action="store_true", help="draw every failure to OUT/NAME-fail-K.png")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    wanted = None if args.only is None else set(args.only.split(","))
    causes = [c for c in FAILURE_CAUSES if c != "success"]
    print("| building | own graph | import | nodes | poses | routes driven on import | repairs | "
          "GoAlone success % | " + " | ".join(c.replace("_", " ") for c in causes)
          + " | episodes stuck (metric) | s |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|" + "---|" * len(causes) + "---|---|")
    worst = 100.0
    for walls_file in sorted(args.buildings.glob("*.vectormap.txt")):
        name = walls_file.name[: -len(".vectormap.txt")]
        if wanted is not None and name not in wanted:
            continue
        nav = walls_file.with_name(f"{name}.navigation.json")
        nav_file = nav if nav.is_file() else None
        start = time.perf_counter()
        m, said, status = import_building(walls_file, nav_file, name, args.out)
        (args.out / f"{name}.import.txt").write_text(said)
        own = "yes" if nav_file else "no"
        if m is None:
            worst = 0.0
            why = said.strip().splitlines()[-1] if said.strip() else status
            print(f"| {name} | {own} | {why} | | | | | 0 |" + " |" * (len(causes) + 1), end="")
            print(f" {time.perf_counter() - start:.0f} |", flush=True)
            continue
        results, extra = evaluate(args.out / f"{name}.json", args.out, args.episodes, args.batch_size)
        counts = dict.fromkeys(FAILURE_CAUSES, 0)
        for r in results:
            cause = failure_cause(r.metrics)
            counts[cause] += 1
            if args.pictures and cause != "success":
                k = r.trial.index
                scenario = extra["test_set"].scenario(k)
                trace = np.array(extra["traces"].get(k, [scenario.robot_start[:2]]))
                mt = r.metrics
                title = (
                    f"{name} scenario {k}: {cause}; reached {mt['reached']}, {mt['distance_from_goal']:.1f} m "
                    f"from goal, travelled {mt['distance_travelled']:.0f} m, humans coll. "
                    f"{mt['human_collisions']}, wall {mt['wall_collisions']}"
                )
                draw_failure(m, scenario, trace, extra["plans"][k], title, args.out / f"{name}-fail-{k}.png")
        rate = 100.0 * counts["success"] / len(results)
        worst = min(worst, rate)
        drive = (m.provenance or {}).get("drive", {})
        driven = f"{drive['routes_completed']}/{drive['routes_driven']}" if drive else "-"
        repairs = len((m.provenance or {}).get("repairs", []))
        stuck = sum(bool(r.metrics.get("stuck")) for r in results)
        print(
            f"| {name} | {own} | {status} | {m.num_nodes} | {len(m.legal_poses)} | {driven} | {repairs} | "
            f"{rate:.0f} | "
            + " | ".join(str(counts[c]) for c in causes)
            + f" | {stuck} | {time.perf_counter() - start:.0f} |",
            flush=True,
        )
    return 0 if worst >= 90.0 else 1


if __name__ == "__main__":
    sys.exit(main())
