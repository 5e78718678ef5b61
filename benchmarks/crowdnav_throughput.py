"""Throughput of the CrowdNav task: env-steps/s of CrowdNavVectorEnv (random velocity actions, the
same-step autoreset included) at several batch sizes and head counts.

CrowdNav's own simulator (one process, env.step alone) steps about 5,035 times a second with 5 people
and 253 with 20 on the 2-core machine (the issue's measurement); the goal is at least 10x that with 5
ORCA people at B = 256 (>= 50,000 env-steps/s) and 20x with 20 (>= 5,000).

With 20 people in CrowdNav's own arena (a circle of radius 4 m) a case's people can jam before all
are placed (3 of the first 3,000 seeds): CrowdNav's draw would never end, socialzoo's refuses the case
after 2^24 draws with a ValueError (socialzoo.scenarios.crowd_cases.crowd_case_arrays), which ends
the run. The default 256x20 case meets one after some 10^5 env-steps of autoreset (on the 2-core
machine --seconds 3 passes, --seconds 25 does not): a long run measures 20 people in CrowdNav++'s
arena, `--variant 20 --cases 256x20`.

Run: python benchmarks/crowdnav_throughput.py [--seconds 3] [--json] [--variant SocialForce]
[--cases 1x5,256x5,1x20,256x20] (B x people per case)
"""

from __future__ import annotations

import json

import numpy as np
from _common import measure, parser

try:
    from socialzoo.env.vector import CrowdNavVectorEnv
except ImportError:  # a tree before the task interface (benchmarks/compare_commits.py)
    from socialzoo.env.crowd_env import CrowdNavVectorEnv  # type: ignore[no-redef]

CASES = "1x5,256x5,1x20,256x20"  # B x people


def throughput(batch: int, people: int, variant: str, seconds: float) -> float:
    """env-steps/s of a vector env of `batch` rows with `people` people each."""
    env = CrowdNavVectorEnv(batch, variant=variant, cases={"num_humans": people})
    env.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (256, batch, 2)).astype(np.float32)
    steps = iter(range(10**12))

    def step() -> None:
        env.step(actions[next(steps) % 256])

    return measure(step, seconds)[0] * batch


def main() -> None:
    p = parser(__doc__.split("\n\n")[0])
    p.add_argument("--variant", default="", help="a registered variant of the task ('' CrowdNav's own)")
    p.add_argument(
        "--cases", default=CASES, help=f"B x people of each case, comma-separated (default {CASES})"
    )
    args = p.parse_args()
    for case in args.cases.split(","):
        try:
            batch, people = (int(n) for n in case.split("x"))
        except ValueError:
            p.error(f"--cases: {case!r} is not B x people, e.g. 256x5")
        if batch < 1 or people < 0:
            p.error(f"--cases: {case!r} needs B >= 1 and people >= 0")
        rate = throughput(batch, people, args.variant, args.seconds)
        figure = {
            "variant": args.variant or "CrowdNav",
            "batch": batch,
            "people": people,
            "env_steps_per_s": round(rate),
        }
        print(
            json.dumps(figure)
            if args.json
            else f"{figure['variant']:12s} B={batch:4d} people={people:3d}  {rate:12,.0f} env-steps/s"
        )


if __name__ == "__main__":
    main()
