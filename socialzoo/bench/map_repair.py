"""Repairs an imported map needs after driving it: what `drive_map` could not complete is moved, dropped or
rerouted, so that every start/goal pair a scenario may draw has been driven."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from socialzoo.bench.drive_check import DriveReport, RouteDrive, drive_map, pose_pairs
from socialzoo.maps.map_file import Map, MapError, graph_components, validate_map
from socialzoo.maps.repair import Repair
from socialzoo.maps.segments import segments_clear
from socialzoo.nav.graph import NavGraph

# Farthest a pose is moved to a place whose join to the graph the robot can drive, m.
MAX_MOVE = 1.5
# Least wall distance of a moved pose, m (the generated poses' preference is 0.6).
MOVED_POSE_CLEARANCE = 0.5


def _at(p: np.ndarray) -> str:
    return f"({p[0]:.2f}, {p[1]:.2f})"


def repair_by_driving(
    m: Map,
    *,
    report: DriveReport | None = None,
    batch_size: int = 256,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[Map, list[Repair], DriveReport]:
    """Drive every feasible pose pair of a map and repair what fails.

    It drives GoAlone alone over every feasible pair of legal poses (socialzoo.bench.drive_check), then:

    - a pose the robot cannot reach or leave (its join to the graph passes closer to a wall than the
      robot keeps: "goal_unreachable", "start_unleavable") moves to the nearest place within
      `MAX_MOVE` whose join keeps the robot's wall distance; without one it is dropped;
    - a graph edge where routes stop at a gap too narrow for the robot ("blocked_doorway") is
      dropped when the graph stays connected without it;
    - the changed routes are driven again; then, while some route still fails, the pose in most of
      the failed routes is dropped (never below two poses).

    Every change is a Repair (socialzoo.maps.repair) and the map's provenance records the drive
    ("drive": routes driven, completed, failures by cause, the repairs' count), so a map file says
    that its pairs were driven.

    Args:
        m: a valid map.
        report: the drive of `m` if already made (over `pose_pairs(m)`).
        batch_size: rows driven together.
        progress: called with (routes done, routes) as routes finish.

    Returns:
        (repaired map, repairs in the order made, the drive of the map's first version). The
        repaired map passes validate_map and every feasible pair of its poses was completed.

    Raises:
        MapError: fewer than two poses would be left.
    """
    first = report if report is not None else drive_map(m, batch_size=batch_size, progress=progress)
    repairs: list[Repair] = []
    routes = {(r.start, r.goal): r for r in first.routes}
    poses = np.array(m.legal_poses, dtype=np.float64).reshape(-1, 3)
    edges = np.asarray(m.edges, dtype=np.int64).reshape(-1, 2)
    graph = NavGraph(m.nodes, edges, m.wall_index, name=m.where)
    failures = [r for r in routes.values() if not r.reached]
    drop = np.zeros(len(poses), dtype=bool)

    # Poses the robot cannot reach or leave: move them where the join is drivable, else drop.
    moved: list[int] = []
    stuck_at: dict[int, RouteDrive] = {}
    for r in failures:
        if r.cause == "goal_unreachable":
            stuck_at.setdefault(r.goal, r)
        elif r.cause == "start_unleavable":
            stuck_at.setdefault(r.start, r)
    wall_distance = first.wall_distance
    for k, r in sorted(stuck_at.items()):
        what = (
            f"legal_poses[{k}] at {_at(poses[k])}: its join to the graph passes {r.gap:.2f} m from a wall "
            f"at {_at(r.where)} ({r.cause.replace('_', ' ')})"
        )
        new = _drivable_place(m, graph, poses[k, :2], wall_distance)
        if new is None:
            drop[k] = True
            repairs.append(
                Repair("pose_dropped", f"{what}: dropped (no drivable place within {MAX_MOVE:g} m)")
            )
        else:
            repairs.append(
                Repair("pose_moved", f"{what}: moved {np.hypot(*(new - poses[k, :2])):.2f} m to {_at(new)}")
            )
            poses[k, :2] = new
            moved.append(k)

    # Edges where routes stop at a gap too narrow for the robot: drop them if the graph stays whole.
    dropped_edges: list[int] = []
    for r in failures:
        if r.cause != "blocked_doorway" or r.start in stuck_at or r.goal in stuck_at:
            continue
        edge = _nearest_edge(m.nodes, edges, r.where, dropped_edges)
        if edge < 0:
            continue
        keep = np.ones(len(edges), dtype=bool)
        keep[[*dropped_edges, edge]] = False
        if len(np.unique(graph_components(len(m.nodes), edges[keep]))) > 1:
            continue
        dropped_edges.append(edge)
        i, j = (int(v) for v in edges[edge])
        repairs.append(
            Repair(
                "edge_dropped",
                f"graph edge (node {i} - node {j}): routes stop at a gap {2 * r.gap:.2f} m wide at {_at(r.where)} "
                f"(the robot needs {2 * wall_distance:.2f} m): dropped",
            )
        )
    if dropped_edges:
        keep = np.ones(len(edges), dtype=bool)
        keep[dropped_edges] = False
        edges = edges[keep]
    current = dataclasses.replace(m, legal_poses=poses, edges=edges, provenance=m.provenance)
    if moved or dropped_edges:
        # Drive again what the changes touched: every pair after an edge change, else the moved poses'.
        pairs = pose_pairs(current)
        if not dropped_edges:
            pairs = pairs[np.isin(pairs, moved).any(axis=1)]
            routes = {key: r for key, r in routes.items() if key[0] not in moved and key[1] not in moved}
        else:
            routes = {}
        again = drive_map(current, pairs, batch_size=batch_size, progress=progress)
        routes.update({(r.start, r.goal): r for r in again.routes})

    # Drop the pose in most of the failed routes until none is left.
    feasible = {tuple(p) for p in pose_pairs(current).tolist()}
    alive = ~drop
    while True:
        failed = [
            r
            for key, r in routes.items()
            if not r.reached and key in feasible and alive[r.start] and alive[r.goal]
        ]
        if not failed:
            break
        count = np.zeros(len(poses), dtype=np.int64)
        for r in failed:
            count[r.start] += 1
            count[r.goal] += 1
        k = int(np.argmax(count))
        if alive.sum() <= 2:
            raise MapError(
                f"{m.where}: the drive check leaves fewer than two legal poses: "
                + "; ".join(r.describe() for r in failed[:5])
            )
        alive[k] = False
        example = next(r for r in failed if k in (r.start, r.goal))
        repairs.append(
            Repair(
                "pose_dropped",
                f"legal_poses[{k}] at {_at(poses[k])}: {count[k]} of its routes failed ({example.describe()}): dropped",
            )
        )
    drop |= ~alive
    if drop.sum() > len(poses) - 2:
        raise MapError(f"{m.where}: the drive check leaves fewer than two legal poses")
    kept = np.flatnonzero(~drop)
    completed = [
        r for key, r in routes.items() if r.reached and key in feasible and not (drop[key[0]] or drop[key[1]])
    ]
    provenance: dict[str, Any] = dict(m.provenance or {})
    provenance["repairs"] = [*provenance.get("repairs", []), *(r.to_json() for r in repairs)]
    provenance["drive"] = {
        "routes_driven": len(first.routes),
        "routes_completed": len(first.routes) - len(first.failures),
        "failures": first.counts(),
        "repairs": len(repairs),
        "pairs_completed_after_repairs": len(completed),
    }
    out = dataclasses.replace(current, legal_poses=poses[kept], provenance=provenance)
    validate_map(out)
    return out, repairs, first


def _nearest_edge(nodes: np.ndarray, edges: np.ndarray, point: np.ndarray, skip: list[int]) -> int:
    """The edge nearest to point within 1 m (not in skip), or -1."""
    if len(edges) == 0:
        return -1
    a, b = nodes[edges[:, 0]], nodes[edges[:, 1]]
    ab = b - a
    t = np.clip(((point - a) * ab).sum(-1) / np.maximum((ab**2).sum(-1), 1e-12), 0.0, 1.0)
    gap = np.hypot(*(a + t[:, None] * ab - point).T)
    gap[skip] = np.inf
    k = int(np.argmin(gap))
    return k if gap[k] <= 1.0 else -1


def _drivable_place(m: Map, graph: NavGraph, point: np.ndarray, wall_distance: float) -> np.ndarray | None:
    """The nearest place within MAX_MOVE of point with MOVED_POSE_CLEARANCE from walls whose
    straight join to the graph keeps the robot's wall distance (and sees a node), or None."""
    rings = np.arange(0.1, MAX_MOVE + 1e-9, 0.1)
    angles = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
    cand = point + (rings[:, None, None] * np.stack((np.cos(angles), np.sin(angles)), -1)[None]).reshape(
        -1, 2
    )
    index = m.wall_index
    roomy = index.nearest(cand)[1] >= MOVED_POSE_CLEARANCE
    seen = index.crosses(np.repeat(point[None], len(cand), axis=0), cand)
    cand = cand[roomy & ~seen]
    if len(cand) == 0:
        return None
    att = graph.attach(cand, strict=False, clearance=wall_distance + 0.02)
    ok = att.found & segments_clear(index, cand, att.point, wall_distance + 0.02)
    if not ok.any():
        return None
    best = int(np.flatnonzero(ok)[0])  # rings go outwards: the first is the nearest
    return np.asarray(cand[best], dtype=np.float64)
