"""A complete Map from walls and whatever of its graph and legal poses a source provides (`complete_map`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from socialzoo.core.walls import WallIndex
from socialzoo.maps.legal_poses import generate_legal_poses
from socialzoo.maps.map_file import Map, graph_components, validate_map
from socialzoo.maps.roadmap import (
    Box,
    FreeSpace,
    RoadmapConfig,
    build_edges,
    build_roadmap,
    connect_components,
    free_space,
)


def complete_map(
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
    validate: bool = True,
) -> Map:
    """A Map from walls, generating whatever of graph and legal poses is missing.

    Without nodes a roadmap is built; nodes without edges (or with none) are joined by build_edges
    and, if still disconnected, by walking paths; missing legal poses are generated. Where the
    free space had to close openings of the outline to unmapped space (roadmap.free_space), the
    map's provenance lists their virtual walls as "outline_closed".

    Raises:
        MapError: when validate is set and the result breaks a rule of validate_map.
    """
    config = config or RoadmapConfig()
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    index = WallIndex(walls)
    space: FreeSpace | None = None
    if nodes is None or len(nodes) == 0:
        roadmap = build_roadmap(walls, region, seed_point, config, seed, index)
        nodes, edges, space = roadmap.nodes, roadmap.edges, roadmap.space
    elif edges is None or len(edges) == 0:
        nodes = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
        edges = build_edges(
            nodes, index, config.edge_clearance, config.max_edge_length, config.detour_tolerance
        )
        if len(np.unique(graph_components(len(nodes), edges))) > 1:
            space = free_space(walls, region, seed_point, config, index)
            nodes, edges = connect_components(space, nodes, edges, index, config)
    nodes = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    if legal_poses is None or len(legal_poses) == 0:
        legal_poses = generate_legal_poses(
            walls, nodes, edges, space, region, seed_point, config, seed, index
        )
    m = Map(
        name=name,
        walls=walls,
        nodes=nodes,
        edges=edges,
        legal_poses=np.asarray(legal_poses, dtype=np.float64).reshape(-1, 3),
        source=source,
        licence=licence,
        region=None
        if region is None
        else (float(region[0]), float(region[1]), float(region[2]), float(region[3])),
    )
    if space is not None and len(space.closures):
        # Openings of the outline closed by virtual walls (roadmap.free_space): say so.
        m = dataclasses.replace(m, provenance={"outline_closed": space.closures.round(6).tolist()})
    if validate:
        validate_map(m)
    return m
