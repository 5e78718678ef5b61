"""Fit ORCA's parameters to the benchmark's social-force people (the defaults of OrcaConfig).

Walks the social-force people and ORCA people of each candidate parameter set on the same
validation scenarios (socialzoo.studies.human_report.walk, no robot) and ranks the candidates by
how closely their people walk like the social-force ones: the relative differences of mean speed,
10th-percentile speed (how much people slow down for each other), route-goal reach rate and
median time to goal, summed. Prints one line per candidate as it is scored (grid order), then the best one.

Run: python tools/fit_orca.py [--map gdc1] [--scenarios 8] [--seconds 40]
"""

from __future__ import annotations

import argparse
import itertools

from socialzoo.studies.human_report import HumanReportConfig, walk

KEYS = ("mean_speed", "speed_p10", "reach_rate", "time_to_goal_median")
# The obstacle horizon keeps the walls' reach (0.45 s x 1.3 m/s + radius) within the wall index's
# 1 m, where the wall lookup is cheapest.
GRID = {
    "time_horizon": (1.0, 2.0, 3.0),
    "radius": (0.2, 0.25, 0.3, 0.35, 0.4),
    "neighbor_dist": (4.0,),
    "time_horizon_obst": (0.45,),
}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--map", default="gdc1")
    p.add_argument("--scenarios", type=int, default=8)
    p.add_argument("--seconds", type=float, default=40.0)
    args = p.parse_args()
    base = {"map": args.map, "scenarios": args.scenarios, "seconds": args.seconds}
    reference = walk("sf", HumanReportConfig(humans=("sf",), **base)).row
    print("social force: " + ", ".join(f"{k} {reference[k]:.3f}" for k in KEYS))
    unscored = [k for k in KEYS if not abs(reference[k]) > 0]  # zero or NaN: no relative difference
    if unscored:
        p.error(
            f"the social-force people give {', '.join(unscored)} of 0 or nan on {args.scenarios} scenarios "
            f"of {args.seconds:g} s (nobody reached a route goal?): give more --seconds or --scenarios"
        )
    scored = []
    for values in itertools.product(*GRID.values()):
        orca = dict(zip(GRID, values, strict=True))
        cfg = HumanReportConfig(humans=("orca",), env_overrides={"world": {"orca": orca}}, **base)
        row = walk("orca", cfg).row
        score = sum(abs(row[k] - reference[k]) / abs(reference[k]) for k in KEYS)
        scored.append((score, orca, row))
        print(f"{orca}: score {score:.3f}; " + ", ".join(f"{k} {row[k]:.3f}" for k in KEYS), flush=True)
    scored.sort(key=lambda item: -item[0])
    print("best:", scored[-1][1], f"score {scored[-1][0]:.3f}")


if __name__ == "__main__":
    main()
