"""The registered variants of the CrowdNav task, as plain overrides of CrowdNavConfig."""

from __future__ import annotations

import math
from typing import Any

# The version of the CrowdNav task's ids (a change to a seeded rollout of the task bumps it; the
# benchmark ids have their own, socialzoo.env.registration.ENV_VERSION).
CROWD_ENV_VERSION = 1

# Variant name -> (one line, CrowdNavConfig overrides as plain JSON values).
VARIANTS: dict[str, tuple[str, dict[str, Any]]] = {
    "": ("CrowdNav's circle crossing: 5 ORCA people, holonomic invisible robot", {}),
    "Square": ("square crossing, 5 ORCA people", {"cases": {"layout": "square_crossing"}}),
    "20": (
        "CrowdNav++'s arena: 20 ORCA people crossing a circle of radius 6 sqrt 2 m, the robot's start and goal "
        "uniform in the arena at least 6 m apart, 50 s",
        {
            "cases": {"num_humans": 20, "circle_radius": 6 * math.sqrt(2), "robot_layout": "random"},
            "time_limit": 50.0,
        },
    ),
    "Unicycle": (
        "a unicycle robot (turns at most pi/4 a step, CrowdNav's rotation limit)",
        {"robot": {"kinematics": "unicycle"}},
    ),
    "Visible": ("the people see the robot and avoid it", {"robot_visible": True}),
    "SocialForce": (
        "social-force people (the benchmark's PedSim model at its 0.025 s step) instead of ORCA",
        {"humans": "social_force", "physics_substeps": 10},
    ),
    "Walls": (
        "crowd navigation among walls: the velocity robot on gdc1 with the benchmark's scenarios and people, "
        "guided along its nav-graph route and seeing walls through a 16-ray scan",
        {
            "map": "gdc1",
            # The benchmark's people: radius 0.2 m (its HumanConfig), not CrowdNav's 0.3.
            "cases": {"human_radius": 0.2},
            "humans": "social_force",
            "robot_visible": True,
            "physics_substeps": 10,
            "time_limit": 81.0,
            "max_humans": 25,
            "wall_rays": 16,
        },
    ),
}


def crowd_env_id(variant: str) -> str:
    """The Gymnasium id of a variant ("" for CrowdNav's own task).

    socialzoo/CrowdNav-v1 is CrowdNav's own task, and socialzoo/CrowdNav<Name>-v1 each variant of
    VARIANTS.
    """
    return f"socialzoo/CrowdNav{variant}-v{CROWD_ENV_VERSION}"
