"""Cost per person-step of recorded scenes against the 20-person CrowdNav task, in one run: the
CrowdNav VectorEnv at B = 256 on a recorded scene (people replaying or hybrid) and on CrowdNav++'s
arena with 20 ORCA people (the "20" variant), with random velocity actions and autoreset.

A person-step is one present person for one decision step (a recorded scene's absent slots, people
who have not entered yet or have left, do not count); microseconds per person-step is the run's
wall time over the present people summed over every step of every row.

Run: SOCIALZOO_DATA_DIR=DIR python benchmarks/recorded_throughput.py [--scenes eth,zara1] [--seconds 5] [--json]
"""

from __future__ import annotations

import json
import time

import numpy as np
from _common import parser

from socialzoo.env.vector import CrowdNavVectorEnv

BATCH = 256


def measure(seconds: float, **config: object) -> dict[str, float]:
    """env-steps/s and microseconds per present person-step of one vector env."""
    env = CrowdNavVectorEnv(BATCH, **config)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (64, BATCH, 2)).astype(np.float32)
    for k in range(3):
        env.step(actions[k])
    core = env.task.core
    steps, people, start = 0, 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        env.step(actions[steps % 64])
        people += int(core.state.human_mask.sum())
        steps += 1
    wall = time.perf_counter() - start
    return {
        "env_steps_per_s": round(steps * BATCH / wall),
        "people_per_row": round(people / steps / BATCH, 1),
        "us_per_person_step": round(wall / max(people, 1) * 1e6, 3),
    }


def main() -> None:
    p = parser(__doc__.splitlines()[0])
    p.add_argument(
        "--scenes", default="eth,zara1", help="recorded scenes (socialzoo data fetch eth-ucy first)"
    )
    args = p.parse_args()
    cases = [("CrowdNav 20 ORCA people", {"variant": "20"})]
    for scene in args.scenes.split(","):
        for humans in ("replay", "hybrid:orca"):
            cases.append(
                (
                    f"{scene} {humans}",
                    {
                        "family": f"recorded_{scene}",
                        "humans": humans,
                        "robot_visible": True,
                        "time_limit": 200.0,
                    },
                )
            )
    for label, config in cases:
        figure = {"case": label, "batch": BATCH, **measure(args.seconds, **config)}
        print(
            json.dumps(figure)
            if args.json
            else f"{label:26s} B={BATCH}  {figure['env_steps_per_s']:10,} env-steps/s  "
            f"{figure['people_per_row']:5.1f} people/row  {figure['us_per_person_step']:7.3f} us/person-step"
        )


if __name__ == "__main__":
    main()
