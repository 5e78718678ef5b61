"""Human routes: shuttling forever between start and goal along a waypoint list."""

from __future__ import annotations

import numpy as np

from socialzoo.core.jit import kernel


def advance_waypoints(
    pos: np.ndarray,
    route: np.ndarray,
    route_len: np.ndarray,
    waypoint: np.ndarray,
    direction: np.ndarray,
    radius: float,
    target: np.ndarray | None = None,
    moving: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Next waypoint index and direction for every human.

    A human walks to route[waypoint]; within the waypoint radius it moves on to the next waypoint in
    its direction of travel, and turns back at either end of the route.

    Args:
        pos: (B, H, 2) positions, m.
        route: (B, H, L, 2) waypoints, m; each human's current one is route[waypoint], read
            here point by point unless `target` is given.
        route_len: (B, H) number of waypoints per route (>= 1).
        waypoint: (B, H) current waypoint index.
        direction: (B, H) +1 towards the goal end, -1 towards the start.
        radius: reach radius, m.
        target: (B, H, 2) route[waypoint] (WorldState.human_target) where the caller gathered it
            for its models already: read instead of the route, whose second pass over a long
            recorded route array misses the cache again. A recorded scene's step gathers none (its
            packing gathers those of the people it steps) and leaves this None.
        moving: (B, H) bool, the people whose waypoint advances, or None (everyone); the others
            keep theirs and their routes are not read (on a recorded scene only the people a model
            moved advance: the replay places its replayed people on their tracks and points one at
            its route itself when it starts to react or enters a slot).

    Returns:
        (waypoint, direction), new arrays of the same shapes.
    """
    dtype = np.result_type(waypoint, direction, route_len)
    new_waypoint = np.empty(np.shape(waypoint), dtype=dtype)
    new_direction = np.empty(np.shape(direction), dtype=np.asarray(direction).dtype)
    # The current waypoints as points[b, h, w if at_waypoint else 0]: one kernel either way.
    points, at_waypoint = (route, True) if target is None else (target[:, :, None], False)
    everyone = moving is None
    _advance(
        pos, points, at_waypoint, route_len, waypoint, direction, radius * radius,
        _EVERYONE if everyone else moving, everyone, new_waypoint, new_direction,
    )  # fmt: skip
    return new_waypoint, new_direction


# moving=None's stand-in: one array type for the kernel whether or not everyone moves.
_EVERYONE = np.ones((1, 1), dtype=bool)


@kernel
def _advance(
    pos, points, at_waypoint, route_len, waypoint, direction, radius2, moving, everyone, new_waypoint, new_direction
):  # fmt: skip
    """`advance_waypoints` in one pass over (B, H); the current waypoint is points[b, h, k], k the
    waypoint index if at_waypoint (points the route), else 0 (points the gathered targets); unless
    `everyone`, only the people `moving` marks advance (the others' points are not read)."""
    for b in range(waypoint.shape[0]):
        for h in range(waypoint.shape[1]):
            d, w = direction[b, h], waypoint[b, h]
            if not (everyone or moving[b, h]):
                new_direction[b, h] = d
                new_waypoint[b, h] = w
                continue
            k = w if at_waypoint else 0
            dx, dy = pos[b, h, 0] - points[b, h, k, 0], pos[b, h, 1] - points[b, h, k, 1]
            reached = dx * dx + dy * dy < radius2
            last = route_len[b, h] - 1
            if reached and ((d > 0 and w >= last) or (d < 0 and w <= 0)):
                d = -d
            if reached:
                w = w + d
            new_direction[b, h] = d
            new_waypoint[b, h] = min(max(w, 0), last)
