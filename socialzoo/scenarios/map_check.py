"""Whether a map is fit for the benchmark: validation, clearance along the graph, connectivity and feasible-route
statistics (`socialzoo map check`; the picture is socialzoo.render.map_plot)."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import numpy as np

from socialzoo.maps.map_file import (
    Map,
    MapError,
    graph_components,
    nearest_walls,
    segment_clearance,
    validate_map,
)
from socialzoo.nav.planner_config import LocalPlannerConfig
from socialzoo.scenarios.feasibility import MAX_ROUTE_LENGTH, RouteStats, max_humans_for, route_stats
from socialzoo.scenarios.generator import ScenarioConfig

# The benchmark's scenario settings (head count 5 to 25, SPEC section 4).
DEFAULT_SCENARIO = ScenarioConfig()
# Clearance reads are exact up to this (half the wall index's reach), m.
CLEARANCE_CAP = 0.5


@dataclass(frozen=True)
class MapCheck:
    """What `check_map` found.

    Attributes:
        problems: validation problems (empty for a valid map).
        node_clearance: (N,) wall distance of each node, m, capped at the wall index's reach
            (1 m by default; inf without walls).
        edge_clearance: (E,) least wall distance along each edge, m, capped at CLEARANCE_CAP.
        pose_clearance: (P,) wall distance of each legal pose, m, capped likewise.
        num_components: connected components of the graph.
        tight_edges: indices of edges closer to a wall than the robot's wall distance.
        routes: feasible-route statistics of the legal poses (None if the map is invalid).
        wall_distance: the robot wall distance used for tight_edges, m.
        repairs: repairs recorded in the map's provenance (kind -> count).
        max_humans: the largest crowd of the default scenario settings on this map.
        walkable: the map's walkable area as text ("n/a" for maps without one).
    """

    problems: tuple[str, ...]
    node_clearance: np.ndarray
    edge_clearance: np.ndarray
    pose_clearance: np.ndarray
    num_components: int
    tight_edges: tuple[int, ...]
    routes: RouteStats | None
    wall_distance: float
    repairs: dict[str, int]
    max_humans: int | None = None
    walkable: str = "n/a"

    @property
    def valid(self) -> bool:
        """True when the map has no problems (warnings allowed)."""
        return not self.problems

    def warnings(self) -> list[str]:
        """What may hurt episodes on a valid map, one line each."""
        out = []
        if self.tight_edges:
            out.append(
                f"{len(self.tight_edges)} graph edges pass closer than {self.wall_distance:.2f} m to a wall "
                "(the robot keeps off them there)"
            )
        r = self.routes
        if r is not None:
            if r.num_unreachable:
                out.append(f"{r.num_unreachable} pose pairs have no route")
            if r.feasible_share < 0.5:
                out.append(
                    f"only {100 * r.feasible_share:.0f}% of pose pairs have a feasible route "
                    f"(<= {r.max_route_length:g} m)"
                )
            if r.stranded:
                out.append(f"legal poses {list(r.stranded)} have no feasible route to any other pose")
        return out

    def lines(self) -> list[str]:
        """The report as text lines."""

        def spread(values: np.ndarray) -> str:
            finite = values[np.isfinite(values)]
            if len(finite) == 0:
                return "n/a"
            return f"min {finite.min():.2f}, median {np.median(finite):.2f} m"

        out = ["valid" if self.valid else f"INVALID ({len(self.problems)} problems)"]
        out += [f"  problem: {p}" for p in self.problems]
        out.append(
            f"clearance: nodes {spread(self.node_clearance)}; poses {spread(self.pose_clearance)} "
            f"(capped at 1 m); edges {spread(self.edge_clearance)} (capped at {CLEARANCE_CAP} m)"
        )
        out.append(
            f"connectivity: {self.num_components} graph component(s); "
            f"{len(self.tight_edges)} of {len(self.edge_clearance)} edges closer than "
            f"{self.wall_distance:.2f} m to a wall"
        )
        r = self.routes
        if r is not None:
            out.append(
                f"routes: {r.num_feasible} of {r.num_pairs} pose pairs feasible "
                f"({100 * r.feasible_share:.0f}%, route <= {r.max_route_length:g} m); lengths "
                f"min {r.shortest:.1f}, median {r.median:.1f}, max {r.longest:.1f} m"
            )
        if self.max_humans is not None:
            out.append(f"crowd: at most {self.max_humans} humans a scenario (walkable area {self.walkable})")
        if self.repairs:
            out.append("repairs on import: " + ", ".join(f"{k} {v}" for k, v in sorted(self.repairs.items())))
        out += [f"warning: {w}" for w in self.warnings()]
        return out


def check_map(
    m: Map, max_route_length: float = MAX_ROUTE_LENGTH, wall_distance: float | None = None
) -> MapCheck:
    """Check a map (see MapCheck); never raises for a map that breaks the rules, it lists them.

    Args:
        m: the map.
        max_route_length: the feasibility rule's limit, m.
        wall_distance: graph edges closer than this to a wall count as tight, m (default: the
            local planner's wall distance, where the robot leaves its path).
    """
    if wall_distance is None:
        wall_distance = LocalPlannerConfig().wall_distance
    try:
        validate_map(m)
        problems: tuple[str, ...] = ()
    except MapError as err:
        problems = tuple(line.split(": ", 1)[-1] for line in str(err).splitlines())
    index = m.wall_index
    nodes = np.asarray(m.nodes, dtype=np.float64).reshape(-1, 2)
    edges = np.asarray(m.edges, dtype=np.int64).reshape(-1, 2)
    poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)
    if index.num_walls:
        # Beyond the index's reach the distance reads inf: cap it there (it is at least that).
        node_clear = np.minimum(nearest_walls(index, nodes)[0], index.fine.reach)
        pose_clear = np.minimum(nearest_walls(index, poses[:, :2])[0], index.fine.reach)
    else:
        node_clear, pose_clear = np.full(len(nodes), math.inf), np.full(len(poses), math.inf)
    in_range = ((edges >= 0) & (edges < len(nodes))).all(axis=1)
    ok_edges = len(edges) and in_range.all()
    if ok_edges and index.num_walls:
        edge_clear = np.minimum(
            segment_clearance(index, nodes[edges[:, 0]], nodes[edges[:, 1]])[0], CLEARANCE_CAP
        )
    else:
        edge_clear = np.full(len(edges), CLEARANCE_CAP)
    # The components of the edges between existing nodes (validation lists the others).
    components = len(np.unique(graph_components(len(nodes), edges[in_range])))
    entries = (m.provenance or {}).get("repairs", [])
    repairs = Counter(str(r.get("kind", "?")) if isinstance(r, dict) else "?" for r in entries)
    return MapCheck(
        problems=problems,
        node_clearance=node_clear,
        edge_clearance=edge_clear,
        pose_clearance=pose_clear,
        num_components=components,
        tight_edges=tuple(int(k) for k in np.flatnonzero(edge_clear < wall_distance)),
        routes=None if problems else route_stats(m, max_route_length),
        wall_distance=wall_distance,
        repairs=dict(repairs),
        max_humans=max_humans_for(m, DEFAULT_SCENARIO.min_humans, DEFAULT_SCENARIO.max_humans),
        walkable="n/a" if m.walkable_area is None else f"{m.walkable_area:.0f} m^2",
    )
