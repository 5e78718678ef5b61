"""Human routes: shuttling forever between start and goal along a waypoint list.

A human walks to route[waypoint]; within the waypoint radius it moves on to the next waypoint in
its direction of travel, and turns back at either end of the route.
"""

from __future__ import annotations

import numpy as np


def advance_waypoints(
    pos: np.ndarray,
    target: np.ndarray,
    route_len: np.ndarray,
    waypoint: np.ndarray,
    direction: np.ndarray,
    radius: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Next waypoint index and direction for every human.

    Args:
        pos: (B, H, 2) positions, m.
        target: (B, H, 2) current waypoints, m.
        route_len: (B, H) number of waypoints per route (>= 1).
        waypoint: (B, H) current waypoint index.
        direction: (B, H) +1 towards the goal end, -1 towards the start.
        radius: reach radius, m.

    Returns:
        (waypoint, direction), new arrays of the same shapes.
    """
    reached = ((pos - target) ** 2).sum(-1) < radius * radius
    last = route_len - 1
    turn_back = reached & (((direction > 0) & (waypoint >= last)) | ((direction < 0) & (waypoint <= 0)))
    new_direction = np.where(turn_back, -direction, direction)
    new_waypoint = np.where(reached, waypoint + new_direction, waypoint)
    return np.minimum(np.maximum(new_waypoint, 0), last), new_direction
