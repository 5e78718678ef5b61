"""Replay every recorded scene in the batched world and compare each person's position with the
file at every recorded frame (issue 37's goal: within 1 cm).

Each scene's test episodes are replayed (people spec "replay", the robot standing at its start,
the world step 0.1 s) and every present slot's position at each frame is compared with the
recording (the files as read: socialzoo.data.tracks).

    SOCIALZOO_DATA_DIR=DIR python tools/check_replay.py [--scenes eth,hotel] [--cases 100]
"""

from __future__ import annotations

import argparse

import numpy as np

from socialzoo.core.config import WorldConfig
from socialzoo.core.walls import WallIndex
from socialzoo.env.core import BatchedCore
from socialzoo.humans.models import PeopleConfig
from socialzoo.scenarios.catalogue import get_family

DT = 0.1


def check_scene(scene: str, cases: int) -> tuple[int, float, int]:
    """(positions compared, largest error in m, presence mismatches) over the scene's test episodes."""
    family = get_family(f"recorded_{scene}")
    size = family.splits["test"].size or 0
    scenarios = [family.make(family.case_seed("test", k)) for k in range(min(cases, size))]
    core = BatchedCore(
        len(scenarios), 1, max(s.num_humans for s in scenarios), WorldConfig(dt=DT),
        WallIndex(np.zeros((0, 4))), people=PeopleConfig(models="replay"),
    )  # fmt: skip
    core.reset_rows(np.arange(len(scenarios)), scenarios)
    frames = max(s.recorded.num_frames for s in scenarios)
    per_frame = round(scenarios[0].recorded.dt / DT)
    compared, worst, mismatched = 0, 0.0, 0
    for frame in range(frames):
        if frame:
            for _ in range(per_frame):
                core.step(np.zeros((len(scenarios), 1, 2)))
        state = core.state
        for row, s in enumerate(scenarios):
            if frame >= s.recorded.num_frames:
                continue
            truth = s.recorded.tracks[:, frame]
            present = ~np.isnan(truth[:, 0])
            n = s.num_humans
            mismatched += int((state.human_mask[row, :n] != present).sum())
            if present.any():
                err = np.hypot(*(state.human_pos[row, :n][present] - truth[present]).T)
                worst = max(worst, float(err.max()))
                compared += int(present.sum())
    return compared, worst, mismatched


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="eth,hotel,univ,zara1,zara2")
    parser.add_argument("--cases", type=int, default=100)
    args = parser.parse_args()
    bad = 0
    for scene in args.scenes.split(","):
        compared, worst, mismatched = check_scene(scene, args.cases)
        ok = worst < 0.01 and mismatched == 0
        bad += not ok
        print(
            f"{scene:6s} {compared:8d} positions compared, largest error {worst * 100:.4f} cm, "
            f"{mismatched} presence mismatches  {'ok' if ok else 'FAIL'}"
        )
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
