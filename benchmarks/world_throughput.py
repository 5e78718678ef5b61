"""World step throughput: humans-only stepping on gdc1 with 25 humans (issue: the world), for each
people model (--humans: people specs of socialzoo.humans.models, e.g. sf orca groups
sf@0.5+orca@0.5; default sf), measured one after the other in the same run so that their
ratio is comparable.

Prints env-steps/s, agent-steps/s (humans stepped per second) and the peak memory of each batch
size; --json prints one JSON object per line (name, batch, env_steps_per_s, agent_steps_per_s,
peak_mem_mib). --counterfactual also times whole episodes (GoAlone and the world, the env core
with rows reset as they end) with and without the counterfactual rows (EnvConfig.people), and
prints their ratio (their peak memory is not measured: null in --json).
Run: python benchmarks/world_throughput.py [--json] [--batches 1 64 256 1024] [--humans sf orca]
[--counterfactual]
"""

from __future__ import annotations

import dataclasses

import numpy as np
from _common import Figure, measure, parser, positive_int, report, traced_peak_mib

from socialzoo.core.config import OrcaConfig, WorldConfig
from socialzoo.env.world import step_world
from socialzoo.humans.group_formation import with_groups
from socialzoo.humans.models import MODEL_IDS, PeopleConfig, assign_models
from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.start_state import scenarios_to_state

HUMANS = 25


def build(batch: int, map_name: str = "gdc1", humans: str = "sf", orca: str = "socialzoo"):
    """A stepping closure over `batch` worlds of 25 humans each (the robot stands still), the people
    driven by the models of the people spec `humans` (ORCA people with the parameter set `orca`)."""
    m = load_map(map_name)
    cfg = ScenarioConfig(min_humans=HUMANS, max_humans=HUMANS)
    parts = PeopleConfig(models=humans).parts
    # A handful of distinct scenarios tiled over the batch: building 1024 would only cost time.
    distinct, models = [], []
    for seed in range(min(batch, 16)):
        scenario = generate_scenario(m, seed, cfg)
        kinds = assign_models(parts, scenario.num_humans, seed)
        grouped = np.array([part.model == "groups" for part in parts])[kinds]
        distinct.append(with_groups(scenario, m, grouped, PeopleConfig().group_sizes))
        models.append(np.array([MODEL_IDS[parts[k].model] for k in kinds], dtype=np.int8))
    state = scenarios_to_state([distinct[i % len(distinct)] for i in range(batch)])
    state.human_model[:] = np.stack([models[i % len(models)] for i in range(batch)])
    world = WorldConfig(orca=OrcaConfig.preset(orca))
    command = np.zeros((batch, 1, 2))
    walls = m.wall_index
    holder = {"state": state}

    def step() -> None:
        holder["state"], _ = step_world(holder["state"], walls, world, command)

    return step


def episodes(batch: int, map_name: str, humans: str, counterfactual: bool, orca: str = "socialzoo"):
    """A stepping closure over the action-selection task of `batch` rows driven by GoAlone, rows reset with the
    next scenario of a pool drawn beforehand (25 humans each; drawing one costs more than many
    steps, and belongs to no episode) as their episodes end."""
    from socialzoo.agents import make_policy
    from socialzoo.env.config import EnvConfig
    from socialzoo.env.tasks.action_selection import ActionSelectionTask

    config = EnvConfig(map=map_name).replace(
        scenario={"min_humans": HUMANS, "max_humans": HUMANS},
        people={"models": humans, "counterfactual": counterfactual},
        world={"orca": dataclasses.asdict(OrcaConfig.preset(orca))},
    )
    task = ActionSelectionTask(config, batch)
    m, cfg = task.map, config.scenario
    pool = [generate_scenario(m, seed, cfg) for seed in range(2 * batch)]
    drawn = iter(range(10**9))
    task.reset_rows(np.arange(batch), [pool[next(drawn) % len(pool)] for _ in range(batch)])
    policy = make_policy("goalone")

    def step() -> None:
        task.step(policy.act(task.obs, task))
        ended = np.flatnonzero(task.core.done.all(axis=1))
        if len(ended):
            task.reset_rows(ended, [pool[next(drawn) % len(pool)] for _ in ended])

    return step


def main() -> None:
    p = parser(__doc__)
    p.add_argument("--batches", type=positive_int, nargs="+", default=[1, 64, 256, 1024])
    p.add_argument("--map", default="gdc1")
    p.add_argument("--humans", nargs="+", default=["sf"], help="people specs, measured in turn")
    p.add_argument("--orca", default="socialzoo", help="ORCA parameter set: socialzoo (default) or crowdnav")
    p.add_argument(
        "--counterfactual",
        action="store_true",
        help="also time episodes with and without counterfactual rows",
    )
    p.add_argument(
        "--repeats", type=positive_int, default=3, help="interleaved timings of the episodes, best kept"
    )
    args = p.parse_args()
    # Load the shared map (and build its wall index) and the compiled kernels before tracing: the
    # peak is then what the batch itself costs, so peak / B is the memory per env beyond the map.
    shared = load_map(args.map)
    shared.wall_index.fine.cell_clearance  # noqa: B018
    shared.wall_index.nearest_candidates  # noqa: B018
    for humans in args.humans:
        build(1, args.map, humans, args.orca)()  # compile each model's kernels outside the traced peaks
    for batch in args.batches:
        peaks = {
            h: traced_peak_mib(lambda b=batch, h=h: build(b, args.map, h, args.orca)) for h in args.humans
        }
        steps = {h: build(batch, args.map, h, args.orca) for h in args.humans}
        rates = dict.fromkeys(args.humans, 0.0)
        # Several models: interleaved, best of --repeats (other load hits them alike).
        for _ in range(args.repeats if len(args.humans) > 1 else 1):
            for humans, step in steps.items():
                rates[humans] = max(rates[humans], measure(step, args.seconds)[0])
        for humans, rate in rates.items():
            peak = peaks[humans]
            name = f"world humans-only {args.map} H={HUMANS}" + ("" if humans == "sf" else f" {humans}")
            report(Figure(name, batch, rate * batch, rate * batch * HUMANS, peak), args.json)
            if not args.json:
                print(f"{'':36} per env beyond the shared map: {peak / batch * 1024:,.0f} KiB")
        if not args.json and len(rates) > 1:
            first = args.humans[0]
            print(
                f"{'':36} relative to {first}: "
                + ", ".join(f"{h} {rates[h] / rates[first]:.2f}" for h in args.humans[1:])
            )
    if args.counterfactual:
        for batch in args.batches:
            for humans in args.humans:
                steps = {cf: episodes(batch, args.map, humans, cf, args.orca) for cf in (False, True)}
                rates = dict.fromkeys(steps, 0.0)
                # Interleaved, best of --repeats: other load on the machine hits both alike.
                for _ in range(args.repeats):
                    for counterfactual, step in steps.items():
                        rates[counterfactual] = max(
                            rates[counterfactual], measure(step, args.seconds, warmup=2)[0]
                        )
                for counterfactual, rate in rates.items():
                    label = f"episodes {humans}" + (" + counterfactual" if counterfactual else "")
                    report(Figure(label, batch, rate * batch, rate * batch * HUMANS, None), args.json)
                if not args.json:
                    print(f"{'':36} counterfactual rows cost {rates[False] / rates[True]:.2f}x")


if __name__ == "__main__":
    main()
