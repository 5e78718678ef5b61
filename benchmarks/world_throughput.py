"""World step throughput: humans-only stepping on gdc1 with 25 humans (issue: the world).

Prints env-steps/s, agent-steps/s (humans stepped per second) and the peak memory of each batch
size; --json prints one JSON object per line (name, batch, env_steps_per_s, agent_steps_per_s,
peak_mem_mib). Run: python benchmarks/world_throughput.py [--json] [--batches 1 64 256 1024]
"""

from __future__ import annotations

import numpy as np
from _common import Figure, measure, parser, report, traced_peak_mib

from socialzoo.core.config import WorldConfig
from socialzoo.env.world import step_world
from socialzoo.nav.maps import load_map
from socialzoo.nav.scenarios import ScenarioConfig, generate_scenario, scenarios_to_state

HUMANS = 25


def build(batch: int, map_name: str = "gdc1"):
    """A stepping closure over `batch` worlds of 25 humans each (the robot stands still)."""
    m = load_map(map_name)
    cfg = ScenarioConfig(min_humans=HUMANS, max_humans=HUMANS)
    # A handful of distinct scenarios tiled over the batch: building 1024 would only cost time.
    distinct = [generate_scenario(m, seed, cfg) for seed in range(min(batch, 16))]
    state = scenarios_to_state([distinct[i % len(distinct)] for i in range(batch)])
    world = WorldConfig()
    command = np.zeros((batch, 1, 2))
    walls = m.wall_index
    holder = {"state": state}

    def step() -> None:
        holder["state"], _ = step_world(holder["state"], walls, world, command)

    return step


def main() -> None:
    p = parser(__doc__)
    p.add_argument("--batches", type=int, nargs="+", default=[1, 64, 256, 1024])
    p.add_argument("--map", default="gdc1")
    args = p.parse_args()
    # Load the shared map (and build its wall index) and the compiled kernels before tracing: the
    # peak is then what the batch itself costs, so peak / B is the memory per env beyond the map.
    shared = load_map(args.map)
    shared.wall_index.fine.cell_clearance  # noqa: B018
    shared.wall_index.nearest_candidates  # noqa: B018
    build(1, args.map)()
    for batch in args.batches:
        peak = traced_peak_mib(lambda b=batch: build(b, args.map))
        rate, _ = measure(build(batch, args.map), args.seconds)
        report(
            Figure(
                f"world humans-only {args.map} H={HUMANS}", batch, rate * batch, rate * batch * HUMANS, peak
            ),
            args.json,
        )
        if not args.json:
            print(f"{'':36} per env beyond the shared map: {peak / batch * 1024:,.0f} KiB")


if __name__ == "__main__":
    main()
