"""The baselines in a recorded person's place (issue 37): every policy on the test tracks of each
recorded scene, with the people replaying their tracks and reacting (hybrid), and a table of the
measures against the recording (socialzoo.env.replay).

    SOCIALZOO_DATA_DIR=DIR python tools/recorded_baselines.py --scenes eth,hotel --tracks 100 --out results/recorded
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from socialzoo.agents import make_policy
from socialzoo.bench.episodes import play_cases
from socialzoo.bench.tables import markdown_table
from socialzoo.env.registration import RECORDED_IDS
from socialzoo.scenarios.catalogue import get_family

# Policy -> (task, the id's config overrides).
POLICIES = {
    "goalone": "action_selection",
    "ref": "action_selection",
    "ppo": "action_selection",
    "dqn": "action_selection",
    "pips": "action_selection",
    "orca": "crowdnav",
    "social_force": "crowdnav",
    "crowdnav": "crowdnav",
    "suite_crowdnav": "crowdnav",
}
KEYS = (
    "success",
    "collision_rate",
    "person_time_ratio",
    "person_path_deviation",
    "people_walked_into_robot",
    "people_reacting",
    "reacting_time_lost",
    "reacting_extra_distance",
)


def _config(task: str) -> dict:
    for kwargs in RECORDED_IDS.values():
        if kwargs["task"] == task:
            return {k: v for k, v in kwargs.items() if k != "task"}
    raise KeyError(task)


def _learned_crowd_overrides(name: str) -> dict:
    """A learned CrowdNav policy's config in a recorded scene: its own actions and signals, its own
    id's wall rays, and as many observed people (the nearest) as it has person slots."""
    from socialzoo.env.crowd_config import resolve_config
    from socialzoo.env.registration import task_ids

    policy = make_policy(name, task="crowdnav")
    if not hasattr(policy, "slots"):
        return {}
    # The id it was trained on, or where that id's version was bumped since (the shipped suite_crowdnav's
    # socialzoo/CrowdNavSuite-v1, now -v2: gymnasium refuses the old one as deprecated), its current one.
    ids, trained_id = task_ids(), str(policy.header["env_id"])
    same = [k for k in ids if k.rpartition("-v")[0] == trained_id.rpartition("-v")[0]]
    if trained_id not in ids and not same:
        raise KeyError(f"{name}: trained on {trained_id}, which socialzoo registers under no version")
    trained = {k: v for k, v in ids[trained_id if trained_id in ids else same[0]].items() if k != "task"}
    rays = resolve_config(None, trained).wall_rays
    return {**policy.task_overrides, "wall_rays": rays, "observed_people": policy.slots - rays}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", default="eth,hotel,univ,zara1,zara2")
    parser.add_argument("--policies", default=",".join(POLICIES))
    parser.add_argument("--people", default="replay,hybrid:sf")
    parser.add_argument("--tracks", type=int, default=100)
    parser.add_argument("--out", type=Path, default=Path("results/recorded"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rows = []
    for scene in args.scenes.split(","):
        family = f"recorded_{scene}"
        size = get_family(family).splits["test"].size or 0
        cases = list(range(min(args.tracks, size)))
        for people in args.people.split(","):
            for name in args.policies.split(","):
                task = POLICIES[name]
                overrides = _config(task) | {"family": family}
                if task == "action_selection":
                    overrides["people"] = {"models": people}
                else:
                    overrides["humans"] = people.replace("hybrid:sf", "hybrid:orca")
                    overrides |= _learned_crowd_overrides(name)
                start = time.perf_counter()
                from socialzoo.env.tasks import task_class

                probe = task_class(task)(batch_size=1, **overrides)
                policy = make_policy(name, task=probe)
                episodes = play_cases(task, policy.act, "test", cases, batch_size=50, **overrides)
                row = {
                    "scene": scene,
                    "people": overrides.get("humans", people),
                    "policy": name,
                    "episodes": len(episodes),
                }
                for key in KEYS:
                    if key == "collision_rate":
                        vals = [float(e.get("collision", e.get("human_collisions", 0) > 0)) for e in episodes]
                        vals = [float(bool(v)) for v in vals]
                    else:
                        vals = [float(e[key]) for e in episodes if key in e]
                    vals = [v for v in vals if not math.isnan(v)]
                    row[key] = float(np.mean(vals)) if vals else float("nan")
                row["seconds"] = round(time.perf_counter() - start, 1)
                rows.append(row)
                print(json.dumps(row), flush=True)
    (args.out / "recorded_baselines.json").write_text(json.dumps(rows, indent=1))
    head = ["scene", "people", "policy", "episodes", *KEYS]
    cells = [[f"{r[k]:.3f}" if isinstance(r[k], float) else str(r[k]) for k in head] for r in rows]
    lines = markdown_table(head, cells)
    (args.out / "recorded_baselines.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
