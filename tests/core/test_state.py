"""WorldState's derived arrays."""

import numpy as np

from socialzoo.core.state import WorldState


def _state_with_routes(b: int, h: int, length: int) -> WorldState:
    """b worlds of h people at random places, each with a random route of `length` points and a
    random waypoint on it."""
    rng = np.random.default_rng(0)
    return WorldState(
        robot_pose=np.zeros((b, 1, 3)), robot_vel=np.zeros((b, 1, 2)), robot_goal=np.zeros((b, 1, 2)),
        human_pos=rng.normal(size=(b, h, 2)), human_vel=np.zeros((b, h, 2)), human_pref_speed=np.ones((b, h)),
        human_mask=np.ones((b, h), dtype=bool), human_route=rng.normal(size=(b, h, length, 2)),
        human_route_len=np.full((b, h), length), human_waypoint=rng.integers(0, length, (b, h)),
        human_direction=np.ones((b, h), dtype=np.int64), step_count=np.zeros(b, dtype=np.int64),
        noise_key=np.zeros(b, dtype=np.uint64),
    )  # fmt: skip


def test_human_target_is_each_route_at_its_waypoint() -> None:
    b, h = 3, 5
    state = _state_with_routes(b, h, 4)
    rows, slots = np.indices((b, h))
    route, waypoint = state.human_route, state.human_waypoint
    assert np.array_equal(state.human_target, route[rows, slots, waypoint])
    assert state.human_target.dtype == route.dtype and state.human_target.shape == (b, h, 2)
