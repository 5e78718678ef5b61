"""Cost per person-step of recorded scenes against the 20-person CrowdNav task, in one run: the
CrowdNav VectorEnv at B = 256 on a recorded scene (people replaying or hybrid) and on CrowdNav++'s
arena with 20 ORCA people (the "20" variant) and CrowdNav's own 5, with random velocity actions and
autoreset.

A person-step is one present person for one decision step (a recorded scene's absent slots, people
who have not entered yet or have left, do not count); microseconds per person-step is the run's
wall time over the present people summed over every step of every row.

With --floor, it also runs the arena with 1 person, and with 5 people in as many person slots as the
first scene's rows have: what a sparse row costs whoever walks in it (microseconds per row-step, one
robot's decision step in one row, are printed beside the person-steps).

With --warmup S, each case first runs S seconds untimed: a recorded scene builds each track's scenario
the first time the track is drawn and keeps it, so a short run from a cold start mostly measures
those builds, and a long training run does not.

With --rounds N, every case (its env built and warmed up first) runs --seconds per round, the cases
one after another, N rounds: the arena and each scene are measured close in time, round after round,
and each case also gets its ratio to the 20-person arena per round, median (min-max) over the rounds.
The machine's speed drifts within a run; a ratio of one round compares like with like.

With --memory STEPS, it prints instead what the replay holds of the recordings after STEPS steps of each
scene in replay at B = 256: the bytes of its bank of recordings (socialzoo.env.recording_bank), or, run with
an older socialzoo on the path (PYTHONPATH=old/checkout), of the rows' own copies of their recordings; and of
all of the replay's arrays.

Run: SOCIALZOO_DATA_DIR=DIR python benchmarks/recorded_throughput.py [--scenes eth,zara1] [--seconds 5]
[--warmup 0] [--rounds 1] [--floor] [--memory STEPS] [--json]
"""

from __future__ import annotations

import json
import statistics
import time

import numpy as np
from _common import at_least, parser, positive_int

from socialzoo.env.vector import CrowdNavVectorEnv
from socialzoo.scenarios.crowd_cases import CrowdCaseConfig

BATCH = 256
# Before the bank (0be8e2f and earlier), each row's recording was its copy in these ReplayRunner arrays.
ROW_COPIES = ("tracks", "track_vel", "route_frame", "entry", "exit", "first", "last", "occupant_speed", "shared",
              "robot_track")  # fmt: skip


class Case:
    """One vector env stepped with random velocity actions and autoreset, its time and present people
    added up over every slice it is run for."""

    def __init__(self, warmup: float = 0.0, **config: object) -> None:
        self.env = CrowdNavVectorEnv(BATCH, **config)
        self.env.reset(seed=0)
        self.actions = np.random.default_rng(0).uniform(-1, 1, (64, BATCH, 2)).astype(np.float32)
        self.steps = self.people = 0
        self.wall = 0.0
        for k in range(3):
            self.env.step(self.actions[k])
        self._k, start = 3, time.perf_counter()
        while time.perf_counter() - start < warmup:
            self.step()

    def step(self) -> None:
        self.env.step(self.actions[self._k % 64])
        self._k += 1

    def run(self, seconds: float) -> dict[str, float]:
        """Step for `seconds`; this slice's figures (figures() gives every slice's together)."""
        core = self.env.task.core
        steps, people, start = 0, 0, time.perf_counter()
        while time.perf_counter() - start < seconds:
            self.step()
            people += int(core.state.human_mask.sum())
            steps += 1
        wall = time.perf_counter() - start
        self.steps, self.people, self.wall = self.steps + steps, self.people + people, self.wall + wall
        return self.figures(steps, people, wall)

    def figures(
        self, steps: int | None = None, people: int | None = None, wall: float | None = None
    ) -> dict[str, float]:
        """env-steps/s, person slots per row, and microseconds per present person-step and per row-step."""
        steps = self.steps if steps is None else steps
        people = self.people if people is None else people
        wall = self.wall if wall is None else wall
        return {
            "env_steps_per_s": round(steps * BATCH / wall),
            "people_per_row": round(people / steps / BATCH, 1),
            "slots": self.env.task.core.max_humans,
            "us_per_person_step": round(wall / max(people, 1) * 1e6, 3),
            "us_per_row_step": round(wall / (steps * BATCH) * 1e6, 3),
        }


def memory(scene: str, steps: int) -> dict[str, float]:
    """MiB of the recordings the replay holds after `steps` steps of `scene` in replay (its bank's arrays, or
    the rows' copies before the bank), of their content (the bank's arrays, grown by doubling, hold room to
    grow), of all the replay's arrays, and the recordings held (0: no bank)."""
    env = CrowdNavVectorEnv(
        BATCH, family=f"recorded_{scene}", humans="replay", robot_visible=True, time_limit=200.0
    )
    env.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (64, BATCH, 2)).astype(np.float32)
    for k in range(steps):
        env.step(actions[k % 64])
    runner = env.task.core.replay
    arrays = {k: v for k, v in vars(runner).items() if isinstance(v, np.ndarray)}
    bank = getattr(runner, "bank", None)
    held = bank.nbytes if bank is not None else sum(arrays[k].nbytes for k in ROW_COPIES)
    mib = 1 / 2**20
    content = sum(bank.used_bytes) if bank is not None else held
    return {
        "recordings_mib": round(held * mib, 2),
        "recordings_content_mib": round(content * mib, 2),
        "replay_mib": round((sum(v.nbytes for v in arrays.values()) + (bank.nbytes if bank else 0)) * mib, 2),
        "recordings_held": bank.entries if bank is not None else 0,
    }


def main() -> None:
    p = parser(__doc__.split("\n\n")[0])
    p.add_argument(
        "--scenes", default="eth,zara1", help="recorded scenes (socialzoo data fetch eth-ucy first)"
    )
    p.add_argument(
        "--warmup",
        type=at_least(0, float),
        default=0.0,
        help="untimed seconds before each case's measurement",
    )
    p.add_argument(
        "--rounds",
        type=positive_int,
        default=1,
        help="run every case --seconds per round, interleaved, ROUNDS times",
    )
    p.add_argument(
        "--floor", action="store_true", help="also the arena with 1 person and 5 people in many slots"
    )
    p.add_argument(
        "--memory",
        type=at_least(0),
        default=0,
        metavar="STEPS",
        help="print the recordings' bytes after STEPS",
    )
    args = p.parse_args()
    if args.memory:
        for scene in args.scenes.split(","):
            figure = {
                "case": f"{scene} replay",
                "batch": BATCH,
                "steps": args.memory,
                **memory(scene, args.memory),
            }
            print(json.dumps(figure) if args.json else "  ".join(f"{k}={v}" for k, v in figure.items()))
        return
    # The reference (20 people) and CrowdNav's own 5, as sparse as the recorded scenes.
    cases = [("CrowdNav 20 ORCA people", {"variant": "20"}), ("CrowdNav 5 ORCA people", {"variant": ""})]
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
    if args.floor:
        first = f"recorded_{args.scenes.split(',')[0]}"
        slots = CrowdNavVectorEnv(1, family=first, humans="replay").task.core.max_humans
        cases[2:2] = [
            ("CrowdNav 1 ORCA person", {"cases": CrowdCaseConfig(num_humans=1)}),
            (f"CrowdNav 5 in {slots} slots", {"variant": "", "max_humans": slots}),
        ]
    built = [(label, Case(args.warmup, **config)) for label, config in cases]
    # Rounds interleave the cases: each round runs every case once, so the arena (the first case)
    # and a scene are measured minutes apart at most, and each round gives its own ratio.
    ratios: dict[str, list[float]] = {label: [] for label, _ in built}
    for _ in range(args.rounds):
        arena = None
        for label, case in built:
            cost = case.run(args.seconds)["us_per_person_step"]
            arena = cost if arena is None else arena
            ratios[label].append(cost / arena)
    for label, case in built:
        figure: dict[str, object] = {"case": label, "batch": BATCH, "warmup_s": args.warmup, **case.figures()}
        spread = ""
        if args.rounds > 1 and label != built[0][0]:
            r = ratios[label]
            figure |= {"rounds": args.rounds, "ratio_median": round(statistics.median(r), 3),
                       "ratio_min": round(min(r), 3), "ratio_max": round(max(r), 3)}  # fmt: skip
            spread = f"  ratio to the arena {statistics.median(r):.2f} ({min(r):.2f}-{max(r):.2f})"
        print(
            json.dumps(figure)
            if args.json
            else f"{label:26s} B={BATCH}  {figure['env_steps_per_s']:10,} env-steps/s  "
            f"{figure['people_per_row']:5.1f} people/row  {figure['us_per_person_step']:7.3f} us/person-step  "
            f"{figure['us_per_row_step']:6.2f} us/row-step{spread}"
        )


if __name__ == "__main__":
    main()
