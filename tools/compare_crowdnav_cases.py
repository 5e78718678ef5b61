"""Our CrowdNav cases against CrowdNav's own: every test case of both layouts, position by position.

    python tools/compare_crowdnav_cases.py --crowdnav PATH [--cases 500]

PATH is a checkout of vita-epfl/CrowdNav (never part of this repository). Its simulator imports
rvo2 and the old gym at module level; neither is needed to draw cases, so both are stubbed here.
Prints the largest coordinate difference over the people's starts and goals (0 when identical).
"""

from __future__ import annotations

import argparse
import configparser
import sys
import types
from pathlib import Path

import numpy as np

from socialzoo.scenarios.crowd_cases import CrowdCaseConfig, crowd_family


def _stub_imports() -> None:
    """rvo2 and gym as empty modules: CrowdSim draws its cases without them."""
    sys.modules.setdefault("rvo2", types.ModuleType("rvo2"))
    gym = types.ModuleType("gym")
    gym.Env = object  # type: ignore[attr-defined]
    sys.modules.setdefault("gym", gym)
    for name in ("gym.envs", "gym.envs.registration"):
        module = types.ModuleType(name)
        module.register = lambda **kwargs: None  # type: ignore[attr-defined]
        sys.modules.setdefault(name, module)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--crowdnav", type=Path, required=True, help="a checkout of vita-epfl/CrowdNav")
    p.add_argument("--cases", type=int, default=500, help="test cases per layout")
    args = p.parse_args()
    _stub_imports()
    sys.path.insert(0, str(args.crowdnav))
    from crowd_sim.envs.crowd_sim import CrowdSim
    from crowd_sim.envs.utils.robot import Robot

    config = configparser.RawConfigParser()
    config.read(args.crowdnav / "crowd_nav" / "configs" / "env.config")

    class _Policy:
        multiagent_training = True  # SARL's: every case holds all the people
        time_step = 0.25

    for layout in ("circle_crossing", "square_crossing"):
        config.set("sim", "test_sim", layout)
        env = CrowdSim()
        env.configure(config)
        robot = Robot(config, "robot")
        robot.policy = _Policy()
        env.set_robot(robot)
        worst = 0.0
        family = crowd_family(CrowdCaseConfig(layout=layout))
        for k in range(args.cases):
            env.reset("test", test_case=k)
            theirs = np.array([[h.px, h.py, h.gx, h.gy] for h in env.humans])
            ours = family.make(family.case_seed("test", k))
            mine = np.hstack([ours.human_spawn, np.array([r[0] for r in ours.human_routes])])
            worst = max(worst, float(np.abs(theirs - mine).max()))
        print(f"{layout}: {args.cases} test cases, largest difference {worst:g} m")


if __name__ == "__main__":
    main()
