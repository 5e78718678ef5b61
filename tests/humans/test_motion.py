"""The people's motion step: walls stay solid whatever the step's length."""

import numpy as np
import pytest

from socialzoo.core.config import WorldConfig
from socialzoo.core.walls import WallIndex
from socialzoo.humans.models import ORCA, SOCIAL_FORCE
from socialzoo.humans.people import step_people


@pytest.mark.parametrize("model", [SOCIAL_FORCE, ORCA])
def test_a_step_longer_than_the_wall_index_reach_does_not_pass_a_wall(model):
    # 1.5 m/s for dt = 1 s: a 1.5 m step from 1.4 m before a wall, beyond the index's 1 m reach.
    walls = WallIndex(np.array([[0.0, 3.3, 4.0, 3.3]]))
    pos, vel = np.array([[[2.0, 1.9]]]), np.zeros((1, 1, 2))
    goal, speed, mask = np.array([[[2.0, 8.0]]]), np.full((1, 1), 1.5), np.ones((1, 1), dtype=bool)
    kinds, group = np.full((1, 1), model), np.full((1, 1), -1)
    for _ in range(10):
        pos, vel, _ = step_people(
            pos, vel, goal, speed, mask, kinds, group, np.zeros((1, 0, 2)), np.zeros((1, 0, 2)), walls,
            WorldConfig(dt=1.0),
        )  # fmt: skip
        assert pos[0, 0, 1] < 3.3
