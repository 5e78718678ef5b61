"""People do not stay pinned against the robot: a person whose way a standing robot blocks in a
narrow corridor touches it for single steps at most, instead of pressing into it (the social
force model has no body force; socialzoo.humans.motion.keep_off_robots)."""

from __future__ import annotations

import numpy as np
import pytest

import socialzoo.env.world as world
from socialzoo.core.config import WorldConfig
from socialzoo.core.walls import WallIndex
from socialzoo.humans.models import LEARNED
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.start_state import scenarios_to_state


def _meet_in_a_corridor(width: float, steps: int = 800, learned: bool = False) -> tuple[int, int, float]:
    """(contact steps, longest contact, least centre distance) of a person walking along a
    corridor through a robot that halts in it (a learned person: one whose desired velocity,
    straight along the corridor, comes from outside, as an env-driven learned policy's does)."""
    walls = WallIndex(
        np.array([[0, 0, 10, 0], [0, width, 10, width], [0, 0, 0, width], [10, 0, 10, width]], float)
    )
    scenario = Scenario(
        map_name="corridor", seed=0, robot_starts=[[5.0, width / 2 + 0.05, 0.0]], robot_goals=[[9.0, 0.5, 0.0]],
        human_spawn=[[1.0, width / 2]], human_start_index=[-1], human_goal_index=[-1],
        human_routes=(np.array([[1.0, width / 2], [9.5, width / 2]]),), human_speed=[1.0],
    )  # fmt: skip
    state = scenarios_to_state([scenario])
    desired = mask = None
    if learned:
        state.human_model[:] = LEARNED
        desired, mask = np.array([[[1.0, 0.0]]]), np.ones((1, 1), bool)
    contact = longest = run = 0
    least = np.inf
    for _ in range(steps):
        state, events = world.step_world(
            state, walls, WorldConfig(), np.zeros((1, 1, 2)), np.ones((1, 1), bool), desired, mask
        )
        touching = bool(events.robot_human[0, 0, 0])
        contact += touching
        run = run + 1 if touching else 0
        longest = max(longest, run)
        least = min(least, float(np.hypot(*(state.human_pos[0, 0] - state.robot_pose[0, 0, :2]))))
    return contact, longest, least


@pytest.mark.parametrize("learned", [False, True])
@pytest.mark.parametrize("width", [1.0, 1.4])
def test_a_person_does_not_press_into_a_standing_robot(width, learned):
    contact, longest, least = _meet_in_a_corridor(width, learned=learned)
    assert longest <= 2 and contact <= 10  # a touch counts (as in the paper), pressing does not
    assert least > 0.38


def test_without_the_contact_rule_the_person_was_pinned(monkeypatch):
    monkeypatch.setattr(world, "keep_off_robots", lambda prev, pos, vel, *rest: (pos, vel))
    _, longest, least = _meet_in_a_corridor(1.0)
    assert longest >= 20 and least < 0.3
