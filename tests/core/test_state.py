"""WorldState's derived arrays."""

import numpy as np

from socialzoo.core.state import WorldState


def test_human_target_is_each_route_at_its_waypoint() -> None:
    rng = np.random.default_rng(0)
    b, h, length = 3, 5, 4
    route = rng.normal(size=(b, h, length, 2))
    waypoint = rng.integers(0, length, (b, h))
    state = WorldState(
        robot_pose=np.zeros((b, 1, 3)), robot_vel=np.zeros((b, 1, 2)), robot_goal=np.zeros((b, 1, 2)),
        human_pos=np.zeros((b, h, 2)), human_vel=np.zeros((b, h, 2)), human_pref_speed=np.ones((b, h)),
        human_mask=np.ones((b, h), dtype=bool), human_route=route, human_route_len=np.full((b, h), length),
        human_waypoint=waypoint, human_direction=np.ones((b, h), dtype=np.int64),
        step_count=np.zeros(b, dtype=np.int64), noise_key=np.zeros(b, dtype=np.uint64),
    )  # fmt: skip
    rows, slots = np.indices((b, h))
    assert np.array_equal(state.human_target, route[rows, slots, waypoint])
    assert state.human_target.dtype == route.dtype and state.human_target.shape == (b, h, 2)
