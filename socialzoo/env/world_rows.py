"""What every task's batched core shares: B rows of R robots and H person slots in one WorldState,
reset row by row from scenarios, and a robot navigator on a map's graph.

The action-selection core (socialzoo.env.core.SocialNavCore) and the CrowdNav core
(socialzoo.env.crowd_core.CrowdNavCore) both keep their world here; each adds its own commands,
observation and judgement on top, and steps the one socialzoo.env.world.step_world.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from socialzoo.core.state import WorldState, pad_to
from socialzoo.maps.map_file import Map
from socialzoo.nav.navigator import Navigator, Sight
from socialzoo.scenarios.scenario import Scenario, scenarios_to_state


class BatchedWorld:
    """B rows of R robots and H person slots in one WorldState (`state`, None before any reset).

    Args:
        batch_size: B.
        num_robots: R.
        max_humans: H.

    Raises:
        ValueError: a batch size that is not an int >= 1, naming the core.
    """

    def __init__(self, batch_size: int, num_robots: int, max_humans: int) -> None:
        if not isinstance(batch_size, int) or isinstance(batch_size, bool) or batch_size < 1:
            raise ValueError(f"{type(self).__name__}: batch_size must be an int >= 1, got {batch_size!r}")
        self.batch_size = batch_size
        self.num_robots = num_robots
        self.max_humans = max_humans
        self.state: WorldState | None = None

    def check_rows(self, rows: np.ndarray | Sequence[int], count: int) -> np.ndarray:
        """`rows` as an index array, refused (ValueError) unless one per scenario and in 0..B-1."""
        rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        if len(rows) != count:
            raise ValueError(f"reset_rows got {len(rows)} rows but {count} scenarios")
        if np.any((rows < 0) | (rows >= self.batch_size)):
            raise ValueError(f"reset_rows: rows {rows.tolist()} outside 0..{self.batch_size - 1}")
        return rows

    def write_rows(self, rows: np.ndarray, scenarios: Sequence[Scenario], models: Any) -> WorldState:
        """Write `scenarios` (one per row, people driven by `models`: (len, H) or one model id) into
        the state's `rows`, widening its route axis for a longer route; returns their fresh state."""
        fresh = scenarios_to_state(scenarios, num_robots=self.num_robots, max_humans=self.max_humans)
        fresh.human_model[:] = models
        if self.state is None:
            self.state = WorldState.concatenate([fresh.rows(0)] * self.batch_size)
        have, length = self.state.human_route.shape[2], fresh.human_route.shape[2]
        if length > have:
            route = self.state.human_route
            self.state.human_route = pad_to(route, (route.shape[1], length, 2), "human_route")
        self.state.set_rows(rows, fresh)
        return fresh

    def robot_rows(self, rows: np.ndarray) -> np.ndarray:
        """The flat robot indices (row * R + robot) of `rows`."""
        return (np.asarray(rows)[:, None] * self.num_robots + np.arange(self.num_robots)).reshape(-1)


def route_navigator(
    m: Map, batch_size: int, num_robots: int, planner: Any, recovery: Any = None
) -> tuple[Any, Navigator]:
    """(the map's wall distance field, a Navigator of its graph) for B x R robots: plans, carrots in
    sight of the planner's wall distance (the field also clears sight lines far from walls), and
    recovery when given (cached per map: the field and the graph)."""
    from socialzoo.nav.distance_field import distance_field
    from socialzoo.nav.graph import graph_of

    field = distance_field(m.wall_index, planner.field_resolution, planner.field_range, planner.field_pad)
    sight = Sight(field, planner.wall_distance)
    return field, Navigator(graph_of(m), batch_size, num_robots, sight=sight, recovery=recovery)
