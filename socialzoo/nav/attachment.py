"""How off-graph points (robot and human poses) join the navigation graph: at the nearest edge point or node they
can reach by a wall-free straight line (SPEC section 5), batched over points (`NavGraph.attach` calls `attach`)."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.maps.segments import segments_clear_of, segments_free
from socialzoo.nav.path_table import NoPathError

if TYPE_CHECKING:
    from socialzoo.nav.graph import NavGraph

# Candidate attach points tested per query point before falling back to all of them.
ATTACH_CANDIDATES = 8
# A robot's join to the graph may pass this much closer to a wall than asked (the distance
# field's lookup error, as the navigator's Sight allows), m.
JOIN_TOLERANCE = 0.02
# Upper bound on (points x candidates) pairs held in memory at once by `attach`.
_ATTACH_CHUNK_PAIRS = 1 << 20


class AttachError(NoPathError):
    """An off-graph point reaches no graph edge or node by a wall-free straight line."""


@dataclass(frozen=True)
class Attachment:
    """Where off-graph points join the navigation graph.

    The attach point lies on the edge (node_a, node_b); cost_a and cost_b are the distances along
    that edge from the attach point to its two end nodes. A point joined at a node has
    node_a == node_b and both costs zero.

    Attributes:
        point: (N, 2) attach points, world frame, m.
        dist: (N,) straight-line distance from each query point to its attach point, m.
        edge: (N,) index into NavGraph.edges, or -1 when the point joins at a node.
        node_a, node_b: (N,) end nodes of the attach edge.
        cost_a, cost_b: (N,) distance along the edge from the attach point to node_a, node_b, m.
        found: (N,) False for points that reach nothing (only with strict=False); their point is
            the query point itself, their dist and costs inf, their nodes 0 and edge -1.
    """

    point: np.ndarray
    dist: np.ndarray
    edge: np.ndarray
    node_a: np.ndarray
    node_b: np.ndarray
    cost_a: np.ndarray
    cost_b: np.ndarray
    found: np.ndarray


def attach(
    graph: NavGraph,
    points: np.ndarray,
    k: int = ATTACH_CANDIDATES,
    *,
    strict: bool = True,
    clearance: float = 0.0,
    skip_edges: np.ndarray | None = None,
) -> Attachment:
    """Join off-graph points to the graph at the nearest point they can reach in a straight line.

    Candidates are the closest point of every edge and every node. For each query point the k
    nearest candidates are tested first (one batched wall test for all points); points whose k
    candidates are all blocked test every candidate, nearest first.

    With clearance > 0 (a robot's plans), the nearest candidate whose line keeps
    min(clearance, the point's own wall distance) - JOIN_TOLERANCE from every wall is taken,
    and only a point with no such candidate at all joins by a merely wall-free line: a join
    through a crack between two wall segments or grazing a door frame is a line the robot
    cannot drive.

    Args:
        graph: the navigation graph (its nodes, edges, edge costs and walls).
        points: (N, 2) query points, world frame, m.
        k: candidates per point in the first round.
        strict: raise for a point that reaches nothing; else mark it not found.
        clearance: the clearance a join should keep, m (0: any wall-free line).
        skip_edges: edge indices whose points are no candidates (their end nodes still are).

    Returns:
        The attachment of every point.

    Raises:
        AttachError: with strict, a point reaches no edge and no node by a wall-free line (the
            message names the first such point), or the graph has no nodes.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    num = len(points)
    if graph.num_nodes == 0:
        if strict:
            raise AttachError(f"{graph.name}: the navigation graph has no nodes to attach to")
        return not_found(points)
    if not np.all(np.isfinite(points)):
        raise ValueError(
            f"{graph.name}: attach points must be finite, got {points[~np.isfinite(points).all(1)][0]}"
        )
    num_cand = graph.num_edges + graph.num_nodes
    chosen = np.full(num, -1, dtype=np.intp)
    cand_point = np.empty((num, 2))
    cand_t = np.empty(num)
    chunk = max(1, _ATTACH_CHUNK_PAIRS // num_cand)
    k = min(k, num_cand)
    for lo in range(0, num, chunk):
        rows = np.arange(lo, min(num, lo + chunk))
        pts, ts, ds = _candidates(graph, points[rows])
        if skip_edges is not None and len(skip_edges):
            ds[:, np.asarray(skip_edges, dtype=np.intp)] = np.inf
        order = np.argpartition(ds, k - 1, axis=1)[:, :k] if k < num_cand else np.argsort(ds, axis=1)
        order = np.take_along_axis(order, np.argsort(np.take_along_axis(ds, order, 1), 1, kind="stable"), 1)
        valid = np.isfinite(np.take_along_axis(ds, order, 1))
        pick, clear = _first_free(graph, points[rows], pts, order, clearance, valid)
        missing = np.flatnonzero((pick < 0) | ~clear)
        if len(missing) and k < num_cand:
            full = np.argsort(ds[missing], axis=1, kind="stable")
            more_valid = np.isfinite(np.take_along_axis(ds[missing], full, 1))
            more, more_clear = _first_free(
                graph, points[rows][missing], pts[missing], full, clearance, more_valid
            )
            better = (pick[missing] < 0) | more_clear
            pick[missing] = np.where(better, more, pick[missing])
        if strict and np.any(pick < 0):
            bad = rows[int(np.flatnonzero(pick < 0)[0])]
            raise AttachError(
                f"{graph.name}: point {points[bad].tolist()} reaches no edge or node of the navigation "
                "graph by a wall-free straight line"
            )
        chosen[rows] = pick
        r = np.arange(len(rows))
        cand_point[rows] = np.where((pick >= 0)[:, None], pts[r, pick], points[rows])
        cand_t[rows] = ts[r, pick]
    found = chosen >= 0
    chosen = np.where(found, chosen, graph.num_edges)  # stand-in: node 0, overwritten below
    is_edge = chosen < graph.num_edges
    edge = np.where(is_edge, chosen, -1)
    node = chosen - graph.num_edges
    e = np.where(is_edge, chosen, 0)
    node_a = np.where(is_edge, graph.edges[e, 0] if graph.num_edges else 0, node)
    node_b = np.where(is_edge, graph.edges[e, 1] if graph.num_edges else 0, node)
    length = graph.edge_cost[e] if graph.num_edges else np.zeros(num)
    cost_a = np.where(is_edge, cand_t * length, 0.0)
    cost_b = np.where(is_edge, (1.0 - cand_t) * length, 0.0)
    dist = np.where(found, np.sqrt(((cand_point - points) ** 2).sum(-1)), np.inf)
    return Attachment(
        point=cand_point,
        dist=dist,
        edge=np.where(found, edge, -1),
        node_a=np.where(found, node_a, 0).astype(np.intp),
        node_b=np.where(found, node_b, 0).astype(np.intp),
        cost_a=np.where(found, cost_a, np.inf),
        cost_b=np.where(found, cost_b, np.inf),
        found=found,
    )


def _candidates(graph: NavGraph, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (M, C, 2), edge parameter t (M, C), distance (M, C)) of all C = E + N candidates."""
    a = graph.nodes[graph.edges[:, 0]]
    b = graph.nodes[graph.edges[:, 1]]
    ab = b - a
    denom = np.where(graph.edge_cost > 0, graph.edge_cost**2, 1.0)
    t = np.clip(np.einsum("mei,ei->me", points[:, None, :] - a[None], ab) / denom, 0.0, 1.0)
    # Clamped ends are the node positions exactly, so duplicate waypoints compare equal.
    on_edge = np.where(
        (t <= 0.0)[..., None],
        a[None],
        np.where((t >= 1.0)[..., None], b[None], a[None] + t[..., None] * ab[None]),
    )
    pts = np.concatenate(
        (on_edge, np.broadcast_to(graph.nodes[None], (len(points), graph.num_nodes, 2))), axis=1
    )
    ts = np.concatenate((t, np.zeros((len(points), graph.num_nodes))), axis=1)
    ds = np.sqrt(((pts - points[:, None, :]) ** 2).sum(-1))
    return pts, ts, ds


def _first_free(
    graph: NavGraph,
    points: np.ndarray,
    cand: np.ndarray,
    order: np.ndarray,
    clearance: float = 0.0,
    valid: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(index (M,) of the first candidate in `order` (M, K) reachable from each point, -1 if
    none; (M,) bool, that line keeps the clearance asked for, see `attach`). Candidates where
    `valid` (M, K) is False are skipped."""
    m, kk = order.shape
    targets = np.take_along_axis(cand, order[..., None], axis=1).reshape(-1, 2)  # (M * K, 2)
    starts = np.repeat(points, kk, axis=0)
    free = segments_free(graph.walls, starts, targets)
    if valid is not None:
        free &= valid.reshape(-1)
    use = free.reshape(m, kk)
    clear: np.ndarray = np.ones(m, dtype=bool)
    if clearance > 0 and graph.walls is not None and graph.walls.num_walls and free.any():
        own = graph.walls.nearest(points)[1]
        need = np.repeat(np.minimum(clearance, own) - JOIN_TOLERANCE, kk)
        good = free.copy()
        good[free] = segments_clear_of(graph.walls, starts[free], targets[free], need[free])
        good = good.reshape(m, kk)
        clear = np.asarray(good.any(axis=1))
        use = np.where(clear[:, None], good, use)
    first = np.argmax(use, axis=1)
    found = use[np.arange(m), first]
    return np.where(found, order[np.arange(m), first], -1), clear & found


def not_found(points: np.ndarray) -> Attachment:
    """The attachment of points that reach nothing."""
    num = len(points)
    return Attachment(
        point=points.copy(),
        dist=np.full(num, np.inf),
        edge=np.full(num, -1, dtype=np.intp),
        node_a=np.zeros(num, dtype=np.intp),
        node_b=np.zeros(num, dtype=np.intp),
        cost_a=np.full(num, np.inf),
        cost_b=np.full(num, np.inf),
        found=np.zeros(num, dtype=bool),
    )


def take(att: Attachment, sel: slice) -> Attachment:
    """Rows `sel` of an attachment."""
    return Attachment(**{f.name: getattr(att, f.name)[sel] for f in fields(Attachment)})
