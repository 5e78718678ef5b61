"""Repairs of imported building data: what real floor plans and their navigation graphs get wrong (`repair_map`)."""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import ndimage

from socialzoo.core.walls import WallIndex
from socialzoo.maps.legal_poses import generate_legal_poses
from socialzoo.maps.map_file import (
    POSE_CLEARANCE,
    Map,
    graph_components,
    nearest_walls,
    reaches_graph,
    segment_clearance,
    validate_map,
)
from socialzoo.maps.roadmap import (
    CLOSING_RADII,
    Box,
    FreeSpace,
    RoadmapConfig,
    Walker,
    add_chain,
    build_edges,
    build_roadmap,
    connect_components,
    describe_closures,
    free_space,
)

logger = logging.getLogger(__name__)

# Farthest a node or pose is moved to clear the walls, m.
MAX_MOVE = 1.5
# A rerouted edge's walking path may be at most this many times the edge's length (plus 2 m).
MAX_DETOUR = 2.0


@dataclass(frozen=True)
class Repair:
    """One change made to imported data.

    Attributes:
        kind: what was done: "outline_closed", "graph_generated", "edges_built",
            "node_moved", "node_dropped", "edge_rerouted", "edge_dropped", "component_joined",
            "component_dropped", "pose_moved", "pose_dropped", "poses_generated" (and, after
            the drive check, socialzoo.bench.map_repair's "pose_moved", "pose_dropped",
            "edge_dropped").
        message: the change in words, naming the source entry (e.g. "graph.nodes[5]").
    """

    kind: str
    message: str

    def to_json(self) -> dict[str, str]:
        """The repair as plain JSON (kind, message), as stored in a map's provenance."""
        return {"kind": self.kind, "message": self.message}


@dataclass
class RepairReport:
    """Every repair made while importing a map, in the order they were made."""

    repairs: list[Repair] = field(default_factory=list)

    def add(self, kind: str, message: str) -> None:
        """Record a repair of `kind` and log its message."""
        self.repairs.append(Repair(kind, message))
        logger.debug("repair: %s", message)

    def to_json(self) -> list[dict[str, str]]:
        """Every repair as plain JSON, in the order made."""
        return [r.to_json() for r in self.repairs]


def _at(p: np.ndarray) -> str:
    return f"({p[0]:.2f}, {p[1]:.2f})"


def _nearest_cells(
    space: FreeSpace, allowed: np.ndarray, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Centres (K, 2) of the nearest `allowed` cells to points (K, 2), and the distance to them, m."""
    if not allowed.any():
        return np.array(points, dtype=np.float64), np.full(len(points), np.inf)
    _, (ii, jj) = ndimage.distance_transform_edt(~allowed, return_indices=True)
    cells = space.cell_of(points)
    target = np.stack((ii[cells[:, 0], cells[:, 1]], jj[cells[:, 0], cells[:, 1]]), axis=1)
    centre = space.centres(target)
    return centre, np.hypot(*(centre - points).T)


def _repair_nodes(
    nodes: np.ndarray,
    space: FreeSpace,
    index: WallIndex,
    config: RoadmapConfig,
    max_move: float,
    report: RepairReport,
    region: Box | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Nodes moved clear of walls, those outside `region` dropped; (nodes (N, 2), keep (N,) bool)."""
    keep = np.ones(len(nodes), dtype=bool)
    nodes = nodes.copy()
    if region is not None:  # a part of a building imported with the whole building's graph
        x0, y0, x1, y1 = region
        keep = (nodes[:, 0] >= x0) & (nodes[:, 0] <= x1) & (nodes[:, 1] >= y0) & (nodes[:, 1] <= y1)
        if not keep.all():
            out = np.flatnonzero(~keep)
            report.add(
                "node_dropped",
                f"{len(out)} of the graph's {len(nodes)} nodes lie outside the region {list(region)}: dropped "
                f"(graph.nodes{out.tolist()})",
            )
    if len(nodes) == 0 or index.num_walls == 0:
        return nodes, keep
    dist, wall = nearest_walls(index, nodes)
    passable = space.clearance >= config.free_clearance
    # Shut inside a wall loop: passable but in a pocket of fewer cells than a robot needs.
    labels, _ = ndimage.label(passable)
    sizes = np.bincount(labels.ravel())
    cells = space.cell_of(nodes)
    pocket = sizes[labels[cells[:, 0], cells[:, 1]]] * space.resolution**2 < 1.0
    pocket &= labels[cells[:, 0], cells[:, 1]] > 0
    bad = np.flatnonzero(((dist < config.free_clearance) | pocket) & keep)
    if len(bad) == 0:
        return nodes, keep
    roomy = passable & (sizes[labels] * space.resolution**2 >= 1.0) & (labels > 0)
    target, moved = _nearest_cells(space, roomy, nodes[bad])
    for k, new, step in zip(bad.tolist(), target, moved, strict=True):
        what = f"graph.nodes[{k}] at {_at(nodes[k])}"
        why = (
            "lies inside a closed wall loop"
            if dist[k] >= config.free_clearance
            else ("lies on wall" if dist[k] <= 1e-9 else f"is {dist[k]:.2f} m from wall") + f" {wall[k]}"
        )
        if step <= max_move:
            report.add("node_moved", f"{what} {why}: moved {step:.2f} m to {_at(new)}")
            nodes[k] = new
        else:
            report.add("node_dropped", f"{what} {why}: dropped (no clear point within {max_move:g} m)")
            keep[k] = False
    return nodes, keep


def _repair_edges(
    nodes: np.ndarray,
    edges: np.ndarray,
    keep: np.ndarray,
    walker: Walker,
    max_detour: float,
    report: RepairReport,
) -> tuple[np.ndarray, np.ndarray]:
    """Edges that keep clear of walls (rerouted or dropped); returns (nodes, edges), nodes appended."""
    index, config = walker.index, walker.config
    edges = edges[keep[edges].all(axis=1)] if len(edges) else edges
    if len(edges) == 0 or index.num_walls == 0:
        return nodes, edges
    a, b = nodes[edges[:, 0]], nodes[edges[:, 1]]
    clear, wall = segment_clearance(index, a, b)
    crossing = index.crosses(a, b)
    bad = crossing | (clear < config.edge_clearance)
    node_list = list(nodes)
    out = [tuple(e) for e in edges[~bad].tolist()]
    for k in np.flatnonzero(bad).tolist():
        i, j = int(edges[k, 0]), int(edges[k, 1])
        what = f"graph edge (node {i} - node {j})"
        why = (
            f"passes through wall {wall[k]}"
            if crossing[k]
            else f"passes {clear[k]:.2f} m from wall {wall[k]}"
        )
        length = float(np.hypot(*(nodes[i] - nodes[j])))
        # Grid path costs are walking metres times at most 3 (the clearance penalty).
        corners = walker.path(nodes[i], nodes[j], 3.0 * (max_detour * length + 2.0))
        walked = None if corners is None else float(np.hypot(*np.diff(corners, axis=0).T).sum())
        if corners is None or walked is None or walked > max_detour * length + 2.0:
            report.add(
                "edge_dropped", f"{what} {why}: dropped (no walking path within {max_detour:g}x its length)"
            )
            continue
        add_chain(node_list, out, i, j, corners)
        report.add(
            "edge_rerouted",
            f"{what} {why}: rerouted along a {walked:.1f} m walking path with {len(corners) - 2} new nodes",
        )
    return np.array(node_list, dtype=np.float64).reshape(-1, 2), np.array(
        sorted(set(out)), dtype=np.int64
    ).reshape(-1, 2)


def _keep_largest(
    nodes: np.ndarray, edges: np.ndarray, report: RepairReport
) -> tuple[np.ndarray, np.ndarray]:
    """Drop every graph component but the largest; returns (nodes, edges)."""
    label = graph_components(len(nodes), edges)
    names, sizes = np.unique(label, return_counts=True)
    main = names[np.argmax(sizes)] if len(names) else -1
    for name, size in zip(names.tolist(), sizes.tolist(), strict=True):
        if name != main:
            centre = nodes[label == name].mean(axis=0)
            report.add(
                "component_dropped",
                f"graph component of {size} node(s) around {_at(centre)} cannot be joined to the rest "
                "through the free space: dropped",
            )
    return _subgraph(nodes, edges, np.flatnonzero(label == main))


def _subgraph(nodes: np.ndarray, edges: np.ndarray, kept: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nodes `kept` (indices, ascending) and the edges between them, renumbered; (nodes, edges)."""
    new_index = np.full(len(nodes), -1, dtype=np.int64)
    new_index[kept] = np.arange(len(kept))
    edges = new_index[edges.reshape(-1, 2)]
    return nodes[kept], edges[(edges >= 0).all(axis=1)]


def _repair_poses(
    poses: np.ndarray,
    nodes: np.ndarray,
    edges: np.ndarray,
    space: FreeSpace,
    index: WallIndex,
    max_move: float,
    report: RepairReport,
) -> np.ndarray:
    """Legal poses clear of walls that reach the graph (moved or dropped)."""
    poses = poses.copy()
    keep = np.ones(len(poses), dtype=bool)
    need = POSE_CLEARANCE + space.resolution
    if index.num_walls:
        dist, wall = nearest_walls(index, poses[:, :2])
        bad = np.flatnonzero(dist < POSE_CLEARANCE)
        if len(bad):
            allowed = space.interior & (space.clearance >= need)
            target, moved = _nearest_cells(space, allowed, poses[bad, :2])
            for k, new, step in zip(bad.tolist(), target, moved, strict=True):
                what = f"legal_poses[{k}] at {_at(poses[k])} is {dist[k]:.2f} m from wall {wall[k]}"
                if step <= max_move:
                    report.add("pose_moved", f"{what}: moved {step:.2f} m to {_at(new)}")
                    poses[k, :2] = new
                else:
                    report.add("pose_dropped", f"{what}: dropped (no clear point within {max_move:g} m)")
                    keep[k] = False
    alive = np.flatnonzero(keep)
    reach = reaches_graph(index, poses[alive, :2], nodes, edges)
    for k in alive[~reach].tolist():
        report.add("pose_dropped", f"legal_poses[{k}] at {_at(poses[k])} cannot reach the graph: dropped")
        keep[k] = False
    return poses[keep]


def repair_map(
    name: str,
    walls: np.ndarray,
    *,
    nodes: np.ndarray | None = None,
    edges: np.ndarray | None = None,
    legal_poses: np.ndarray | None = None,
    region: Box | None = None,
    seed_point: tuple[float, float] | np.ndarray | None = None,
    source: str = "",
    licence: str = "",
    config: RoadmapConfig | None = None,
    seed: int = 0,
    max_move: float = MAX_MOVE,
    max_detour: float = MAX_DETOUR,
    provenance: dict[str, Any] | None = None,
) -> tuple[Map, RepairReport]:
    """A valid Map from imported data, repairing what breaks the rules (below).

    What the source lacks is generated as `map_completion.complete_map` does (a roadmap without nodes,
    edges between nodes without edges, legal poses without poses); each such step is reported too.

    Real navigation graphs put nodes in doorways and on walls, draw edges through walls and carry
    stray components; their legal poses stand too close to walls. This fixes each of these and records
    every change in a RepairReport, which importers store in the map's provenance:

    - a node closer to a wall than the passable clearance (config.free_clearance), or shut inside a
      wall loop, moves to the nearest passable grid cell within `max_move`; else it is dropped;
    - an edge that touches a wall or passes closer than config.edge_clearance is rerouted along a
      walking path through the free space (its corners become new nodes) when that path is at most
      `max_detour` times longer; else it is dropped;
    - graph components are joined along walking paths where the free space joins them; those that
      stay apart (outside the building, behind a door too narrow for the robot) are dropped, the
      largest kept;
    - a legal pose too close to a wall moves to the nearest cell with the pose clearance, a pose that
      cannot reach the graph is dropped, and with fewer than two left the poses are generated afresh.

    With a given graph the free space is where that graph lies (`_graph_free_space`): the enclosed
    area holding most of its nodes, with wider openings of the outline closed where needed. Without
    one, openings of the outline to unmapped space that leave no enclosed room are closed by virtual
    walls (socialzoo.maps.roadmap.free_space), reported as "outline_closed" with their ends.
    What only driving shows (a pose the robot cannot reach, a gap too narrow) is repaired afterwards
    by socialzoo.bench.map_repair.

    Args:
        name: map name.
        walls: (W, 4) wall segments, m.
        nodes: the source's graph nodes (N, 2), m, if any.
        edges: the source's graph edges (E, 2), node index pairs, if any.
        legal_poses: the source's legal poses (P, 3), m and rad, if any.
        region: the area to map, [xmin, ymin, xmax, ymax] (see roadmap.free_space).
        seed_point: a point inside the building (see roadmap.free_space).
        source: stored in the map.
        licence: stored in the map.
        config: roadmap settings (clearances of nodes, edges and poses).
        seed: seeds node placement and pose sampling.
        max_move: farthest a node or pose is moved, m.
        max_detour: a rerouted edge's walking path is at most this many times its length plus 2 m.
        provenance: extra provenance entries (importer, inputs); the report is added as "repairs".

    Returns:
        (map, report). The map passes validate_map.

    Raises:
        MapError: the repaired map still breaks a rule of validate_map (the message names it).
        ValueError: no free space, or a seed point on a wall.
    """
    config = config or RoadmapConfig()
    report = RepairReport()
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    index = WallIndex(walls)
    if nodes is not None and len(nodes) and seed_point is None:
        given = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
        space = _graph_free_space(walls, given, region, config, index, report)
    else:
        space = free_space(walls, region, seed_point, config, index)
        if len(space.closures):  # virtual walls closed the outline's openings to unmapped space
            report.add("outline_closed", describe_closures(space.closures))
    if nodes is None or len(nodes) == 0:
        roadmap = build_roadmap(walls, region, seed_point, config, seed, index, space)
        nodes, edges = roadmap.nodes, roadmap.edges
        report.add("graph_generated", f"navigation graph generated: {len(nodes)} nodes, {len(edges)} edges")
    else:
        nodes = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
        nodes, keep = _repair_nodes(nodes, space, index, config, max_move, report, region)
        if edges is None or len(edges) == 0:
            edges = build_edges(
                nodes[keep], index, config.edge_clearance, config.max_edge_length, config.detour_tolerance
            )
            edges = np.flatnonzero(keep)[edges] if len(edges) else edges.reshape(-1, 2)
            report.add("edges_built", f"graph edges built between the given nodes: {len(edges)} edges")
        else:
            edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
            nodes, edges = _repair_edges(nodes, edges, keep, Walker(space, index, config), max_detour, report)
            keep = np.concatenate((keep, np.ones(len(nodes) - len(keep), dtype=bool)))
        nodes, edges = _join_and_prune(nodes, edges, keep, space, index, config, report)
    nodes = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    poses = None if legal_poses is None else np.asarray(legal_poses, dtype=np.float64).reshape(-1, 3)
    if poses is not None and len(poses):
        poses = _repair_poses(poses, nodes, edges, space, index, max_move, report)
    if poses is None or len(poses) < 2:
        had = 0 if poses is None else len(poses)
        poses = generate_legal_poses(walls, nodes, edges, space, region, seed_point, config, seed, index)
        why = "the source has none" if legal_poses is None or len(legal_poses) == 0 else f"{had} left"
        report.add("poses_generated", f"legal poses generated ({why}): {len(poses)} poses")
    m = Map(
        name=name,
        walls=walls,
        nodes=nodes,
        edges=edges,
        legal_poses=poses,
        source=source,
        licence=licence,
        region=None
        if region is None
        else (float(region[0]), float(region[1]), float(region[2]), float(region[3])),
        walkable_area=float(space.interior.sum()) * space.resolution**2,
        provenance={**(provenance or {}), "repairs": report.to_json()},
    )
    validate_map(m)
    return m, report


def _graph_free_space(
    walls: np.ndarray,
    nodes: np.ndarray,
    region: Box | None,
    config: RoadmapConfig,
    index: WallIndex,
    report: RepairReport,
) -> FreeSpace:
    """The free space people walk in by the source's own graph: the enclosed area holding most of
    its nodes (not merely the largest one). Where most nodes lie outside every enclosed area
    (an outline drawn with gaps wider than 2 x closing_radius), wider openings are closed, one
    CLOSING_RADII step at a time, until at least half of them lie inside."""
    space = free_space(walls, region, None, config, index, anchors=nodes)
    # Nodes on the grid in passable space (nodes on walls are moved later and do not count).
    cells = space.cell_of(nodes)
    on_grid = space.contains(nodes) | (
        (space.clearance[cells[:, 0], cells[:, 1]] >= config.free_clearance)
        & (nodes >= space.origin).all(axis=1)
        & (nodes < space.origin + np.array(space.shape) * space.resolution).all(axis=1)
    )
    wanted = int(on_grid.sum())
    best, held = space, int(space.contains(nodes).sum())
    if wanted == 0 or 2 * held >= wanted:
        return space
    for radius in CLOSING_RADII:
        if radius <= config.closing_radius:
            continue
        wider = free_space(
            walls, region, None, dataclasses.replace(config, closing_radius=radius), index, nodes
        )
        count = int(wider.contains(nodes).sum())
        if count > held:
            best, held = wider, count
            report.add(
                "outline_closed",
                f"{wanted - int(space.contains(nodes).sum())} of the navigation graph's {wanted} nodes lie "
                f"outside every enclosed area: openings in the building's outline up to {2 * radius:g} m "
                f"wide count as closed, so that {count} lie inside",
            )
            if 2 * held >= wanted:
                break
    return best


def _join_and_prune(
    nodes: np.ndarray,
    edges: np.ndarray,
    keep: np.ndarray,
    space: FreeSpace,
    index: WallIndex,
    config: RoadmapConfig,
    report: RepairReport,
) -> tuple[np.ndarray, np.ndarray]:
    """Join components along walking paths where possible, then keep the largest one."""
    sub_nodes, sub_edges = _subgraph(nodes, edges, np.flatnonzero(keep))
    before = len(np.unique(graph_components(len(sub_nodes), sub_edges)))
    if before > 1:
        joined_nodes, joined_edges = connect_components(space, sub_nodes, sub_edges, index, config)
        after = len(np.unique(graph_components(len(joined_nodes), joined_edges)))
        if after < before:
            report.add(
                "component_joined",
                f"{before - after} graph component(s) joined to the rest along walking paths "
                f"({len(joined_nodes) - len(sub_nodes)} new nodes)",
            )
        sub_nodes, sub_edges = joined_nodes, joined_edges
    return _keep_largest(sub_nodes, sub_edges, report)
