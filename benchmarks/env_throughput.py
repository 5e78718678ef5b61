"""Environment throughput on gdc1 with 25 humans and random actions: the single-agent benchmark env,
the VectorEnv (B = 256), and the ParallelEnv with 4 robots and 8 learned humans.

Run: python benchmarks/env_throughput.py [--json] [--vector-batch 256]
"""

from __future__ import annotations

import numpy as np
from _common import Figure, measure, parser, positive_int, report, traced_peak_mib

import socialzoo  # noqa: F401
from socialzoo.env import ActionSelectionEnv, ActionSelectionVectorEnv, parallel_env

CROWD = {"scenario": {"min_humans": 25, "max_humans": 25}}


def single(map_name: str):
    env = ActionSelectionEnv(map=map_name, **CROWD)
    env.reset(seed=0)
    rng = np.random.default_rng(0)

    def step() -> None:
        _, _, terminated, truncated, _ = env.step(int(rng.integers(4)))
        if terminated or truncated:
            env.reset()

    return step


def vector(map_name: str, batch: int):
    env = ActionSelectionVectorEnv(batch, map=map_name, **CROWD)
    env.reset(seed=0)
    rng = np.random.default_rng(0)

    def step() -> None:
        env.step(rng.integers(0, 4, batch))

    return step


def parallel(map_name: str):
    env = parallel_env(map=map_name, num_robots=4, num_learned_humans=8, episode_info=False, **CROWD)
    env.reset(seed=0)
    for k, agent in enumerate(env.possible_agents):  # the same random actions in every run
        env.action_space(agent).seed(k)
    rng = np.random.default_rng(0)

    def step() -> None:
        if not env.agents:
            env.reset()
        actions = {agent: env.action_space(agent).sample() for agent in env.agents}
        for agent in actions:
            if agent.startswith("robot"):
                actions[agent] = int(rng.integers(4))
        env.step(actions)

    return step


def main() -> None:
    p = parser(__doc__)
    p.add_argument("--map", default="gdc1")
    p.add_argument("--vector-batch", type=positive_int, default=256)
    args = p.parse_args()
    single(args.map)()  # shared map tables outside the traced peaks
    rate, _ = measure(single(args.map), args.seconds)
    report(
        Figure(f"ActionSelectionEnv {args.map}", 1, rate, rate, traced_peak_mib(lambda: single(args.map))),
        args.json,
    )
    b = args.vector_batch
    rate, _ = measure(vector(args.map, b), args.seconds, warmup=2)
    peak = traced_peak_mib(lambda: vector(args.map, b), steps=2)
    report(Figure(f"ActionSelectionVectorEnv {args.map}", b, rate * b, rate * b, peak), args.json)
    rate, _ = measure(parallel(args.map), args.seconds)
    peak = traced_peak_mib(lambda: parallel(args.map))
    report(Figure(f"ParallelEnv {args.map} R=4 learned H=8", 1, rate, rate * 12, peak), args.json)


if __name__ == "__main__":
    main()
