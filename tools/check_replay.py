"""Replay every recorded scene in the batched world and compare each person's position with the
file at every recorded frame (issue 37's goal: within 1 cm).

Each scene's test episodes are replayed (people spec "replay", the robot standing at its start,
the world step the recording's frame period split into steps of about 0.1 s: 0.1 s at 2.5 Hz) and
every present slot's position at each frame is compared with the recording (the files as read:
socialzoo.data.tracks). A scene too small for a test split (a recording of your own, registered as a
family) is checked on its validation, else its training episodes.

    SOCIALZOO_DATA_DIR=DIR python tools/check_replay.py [--scenes eth,hotel] [--cases 100]
"""

from __future__ import annotations

import argparse

import numpy as np

from socialzoo.cli.arg_types import positive_int
from socialzoo.core.config import WorldConfig
from socialzoo.core.walls import WallIndex
from socialzoo.env.core import BatchedCore
from socialzoo.humans.models import PeopleConfig
from socialzoo.scenarios.catalogue import get_family

# The longest world step: a frame period is split into whole steps of at most about this.
DT = 0.1


def check_scene(scene: str, cases: int) -> tuple[int, float, int]:
    """(positions compared, largest error in m, presence mismatches) over the scene's test episodes
    (its validation or training ones where it has no test split); `scene` a recorded scene's name
    (family recorded_SCENE) or a recorded family's registered name."""
    family = get_family(scene if scene.startswith("recorded_") else f"recorded_{scene}")
    split = next((s for s in ("test", "val", "train") if family.splits[s].size), "train")
    count = min(cases, family.splits[split].size or cases)
    scenarios = [family.make(family.case_seed(split, k)) for k in range(count)]
    frame_dt = scenarios[0].recorded.dt
    per_frame = max(1, round(frame_dt / DT))
    core = BatchedCore(
        len(scenarios), 1, max(s.num_humans for s in scenarios), WorldConfig(dt=frame_dt / per_frame),
        WallIndex(np.zeros((0, 4))), people=PeopleConfig(models="replay"),
    )  # fmt: skip
    core.reset_rows(np.arange(len(scenarios)), scenarios)
    frames = max(s.recorded.num_frames for s in scenarios)
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
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", default="eth,hotel,univ,zara1,zara2")
    parser.add_argument("--cases", type=positive_int, default=100, help="episodes per scene (default 100)")
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
