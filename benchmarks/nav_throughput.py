"""Navigation throughput: the robot running GoAlone among 25 humans on gdc1 (world step plus global
and local planning), through the batched env core without observations' consumers.

Run: python benchmarks/nav_throughput.py [--json] [--batches 1 256]
"""

from __future__ import annotations

import numpy as np
from _common import Figure, measure, parser, positive_int, report, traced_peak_mib

from socialzoo.core.config import WorldConfig
from socialzoo.env.world import step_world
from socialzoo.maps.map_file import load_map
from socialzoo.nav.distance_field import distance_field
from socialzoo.nav.graph import graph_of
from socialzoo.nav.local_planner import LocalPlannerConfig
from socialzoo.nav.navigator import Navigator, Sight
from socialzoo.nav.subpolicies import SubPolicyConfig, subpolicy_commands
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.start_state import scenarios_to_state

HUMANS = 25


def build(batch: int, map_name: str = "gdc1"):
    """A closure doing one GoAlone step (plan, command, world step) for `batch` robots."""
    m = load_map(map_name)
    cfg = ScenarioConfig(min_humans=HUMANS, max_humans=HUMANS)
    distinct = [generate_scenario(m, seed, cfg) for seed in range(min(batch, 16))]
    state = scenarios_to_state([distinct[i % len(distinct)] for i in range(batch)])
    world, sub, planner = WorldConfig(), SubPolicyConfig(), LocalPlannerConfig()
    # The carrot kept in sight, as the envs track it.
    field = distance_field(m.wall_index, planner.field_resolution, planner.field_range, planner.field_pad)
    navigator = Navigator(graph_of(m), batch, sight=Sight(field, planner.wall_distance))
    navigator.reset(np.arange(batch), state.robot_pose[..., :2], state.robot_goal[..., :2])
    action = np.zeros(batch, dtype=np.int64)
    holder = {"state": state}

    def step() -> None:
        s = holder["state"]
        carrot = navigator.update(s.robot_pose[..., :2])
        command, halt, _ = subpolicy_commands(
            action,
            s.robot_pose[:, 0],
            s.robot_vel[:, 0],
            carrot[:, 0],
            s.human_pos,
            s.human_vel,
            s.human_mask,
            m.wall_index,
            sub,
            planner,
            world.robot,
            world.dt,
        )
        holder["state"], _ = step_world(s, m.wall_index, world, command[:, None], halt[:, None])

    return step


def main() -> None:
    p = parser(__doc__)
    p.add_argument("--batches", type=positive_int, nargs="+", default=[1, 256])
    p.add_argument("--map", default="gdc1")
    args = p.parse_args()
    build(1, args.map)()  # shared map tables and planner fields, outside the traced peak
    for batch in args.batches:
        peak = traced_peak_mib(lambda b=batch: build(b, args.map))
        rate, _ = measure(build(batch, args.map), args.seconds)
        report(
            Figure(f"GoAlone + world {args.map} H={HUMANS}", batch, rate * batch, rate * batch, peak),
            args.json,
        )


if __name__ == "__main__":
    main()
