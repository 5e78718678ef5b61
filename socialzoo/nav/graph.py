"""The navigation graph of a map: A*, an all-pairs next-hop table and batched path planning."""

from __future__ import annotations

import heapq
import math
import weakref
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.core.walls import WallIndex
from socialzoo.maps.segments import segments_clear, segments_free
from socialzoo.nav.attachment import attach, take
from socialzoo.nav.path_table import NoPathError, PathTable, floyd_warshall

if TYPE_CHECKING:
    from socialzoo.maps.map_file import Map

# Waypoints closer than this to the previous one are dropped from a plan (metres).
DUPLICATE_EPS = 1e-9


class NavGraph:
    """An undirected navigation graph with Euclidean edge costs, and the walls it lives among.

    Two ways to find shortest paths give the same answers: `astar` (one pair, cached) and the
    all-pairs `table` (built once, lazily, by Floyd-Warshall) that `plan_batch` reads so that
    batched queries need no search per row. Both return shortest paths of equal cost (to float
    rounding); where several paths tie, they may pick different ones.

    Args:
        nodes: (N, 2) node positions, world frame, m.
        edges: (E, 2) node index pairs; duplicates and reversed duplicates are merged.
        walls: the map's wall index, used to check straight joins; None for a map without walls.
        name: used in error messages.

    Raises:
        ValueError: nodes not finite or not (N, 2), edges not (E, 2), an edge index out of range,
            or an edge from a node to itself.
    """

    def __init__(
        self, nodes: np.ndarray, edges: np.ndarray, walls: WallIndex | None = None, name: str = "graph"
    ) -> None:
        nodes = np.asarray(nodes, dtype=np.float64)
        if nodes.ndim != 2 or nodes.shape[1] != 2 or not np.all(np.isfinite(nodes)):
            raise ValueError(f"{name}: nodes must be a finite (N, 2) array, got shape {nodes.shape}")
        edges = np.asarray(edges)
        if edges.size == 0:
            edges = np.zeros((0, 2), dtype=np.intp)
        if edges.ndim != 2 or edges.shape[1] != 2 or not np.issubdtype(edges.dtype, np.integer):
            raise ValueError(
                f"{name}: edges must be an integer (E, 2) array, got {edges.dtype} {edges.shape}"
            )
        edges = edges.astype(np.intp)
        bad = np.flatnonzero((edges < 0).any(1) | (edges >= len(nodes)).any(1))
        if len(bad):
            raise ValueError(
                f"{name}: edge {int(bad[0])} = {edges[bad[0]].tolist()} names a node outside "
                f"0..{len(nodes) - 1}"
            )
        loops = np.flatnonzero(edges[:, 0] == edges[:, 1])
        if len(loops):
            raise ValueError(f"{name}: edge {int(loops[0])} joins node {int(edges[loops[0], 0])} to itself")
        edges = np.unique(np.sort(edges, axis=1), axis=0)
        self.name = name
        self.nodes = nodes
        self.edges = edges
        self.walls = walls
        self.edge_cost = np.sqrt(((nodes[edges[:, 0]] - nodes[edges[:, 1]]) ** 2).sum(-1))
        self._neighbours: list[list[tuple[int, float]]] = [[] for _ in range(len(nodes))]
        for (i, j), c in zip(edges.tolist(), self.edge_cost.tolist(), strict=True):
            self._neighbours[i].append((j, c))
            self._neighbours[j].append((i, c))
        self._astar_cache: dict[tuple[int, int], tuple[int, ...]] = {}

    @classmethod
    def from_map(cls, m: Map) -> NavGraph:
        """The graph of a map, with the map's wall index (a new object; see `graph_of`)."""
        return cls(m.nodes, m.edges, m.wall_index, name=m.where)

    @property
    def num_nodes(self) -> int:
        """N, the number of nodes."""
        return len(self.nodes)

    @property
    def num_edges(self) -> int:
        """E, the number of undirected edges."""
        return len(self.edges)

    def _check_node(self, node: int, what: str) -> int:
        if not 0 <= int(node) < self.num_nodes:
            raise ValueError(f"{self.name}: {what} node {node} is outside 0..{self.num_nodes - 1}")
        return int(node)

    # ---------------------------------------------------------------- single-pair search
    def astar(self, start_node: int, goal_node: int) -> list[int]:
        """Shortest node path by A* with the (admissible, consistent) Euclidean heuristic.

        Results are cached per (start, goal).

        Returns:
            Node indices from start_node to goal_node inclusive.

        Raises:
            NoPathError: the goal is not reachable from the start.
        """
        start = self._check_node(start_node, "start")
        goal = self._check_node(goal_node, "goal")
        key = (start, goal)
        if key not in self._astar_cache:
            self._astar_cache[key] = self._astar(start, goal)
        return list(self._astar_cache[key])

    def _astar(self, start: int, goal: int) -> tuple[int, ...]:
        gx, gy = self.nodes[goal].tolist()
        pos = self.nodes.tolist()
        best = {start: 0.0}
        parent = {start: -1}
        heap = [(math.hypot(pos[start][0] - gx, pos[start][1] - gy), 0.0, start)]
        closed = set()
        while heap:
            _, cost, node = heapq.heappop(heap)
            if node in closed:
                continue
            if node == goal:
                path = [node]
                while parent[path[-1]] >= 0:
                    path.append(parent[path[-1]])
                return tuple(reversed(path))
            closed.add(node)
            for nb, edge_cost in self._neighbours[node]:
                new = cost + edge_cost
                if nb not in closed and new < best.get(nb, math.inf):
                    best[nb] = new
                    parent[nb] = node
                    heapq.heappush(heap, (new + math.hypot(pos[nb][0] - gx, pos[nb][1] - gy), new, nb))
        raise NoPathError(
            f"{self.name}: no path from node {start} {self.nodes[start].tolist()} "
            f"to node {goal} {self.nodes[goal].tolist()}: they are not connected"
        )

    def plan_avoiding(
        self, start: np.ndarray, goal: np.ndarray, avoid: np.ndarray, *, clearance: float = 0.0
    ) -> np.ndarray | None:
        """Waypoints (L, 2) from start to goal (2,) over the graph without the edges `avoid`
        (edge indices; -1 entries ignored), or None when no such path exists.

        A recovering robot's plan (socialzoo.nav.navigator): start and goal join the graph as in
        `plan_batch` (keeping `clearance` where they can) but never on an avoided edge, then
        Dijkstra from the start's attach edge ends to the goal's, skipping the avoided edges; a
        straight start-goal line is not used (the robot came back from where it was stuck).
        """
        avoided = {int(e) for e in np.asarray(avoid).reshape(-1) if e >= 0}
        skip = np.array(sorted(avoided), dtype=np.intp)
        att = self.attach(np.stack((start, goal)), strict=False, clearance=clearance, skip_edges=skip)
        if not att.found.all():
            return None
        best: dict[int, float] = {}
        parent: dict[int, int] = {}
        heap: list[tuple[float, int]] = []
        for node, cost in (
            (int(att.node_a[0]), float(att.cost_a[0])),
            (int(att.node_b[0]), float(att.cost_b[0])),
        ):
            if cost < best.get(node, math.inf):
                best[node], parent[node] = cost, -1
                heapq.heappush(heap, (cost, node))
        edge_of = {(int(i), int(j)): k for k, (i, j) in enumerate(self.edges.tolist())}
        done: set[int] = set()
        while heap:
            cost, node = heapq.heappop(heap)
            if node in done:
                continue
            done.add(node)
            for nb, edge_cost in self._neighbours[node]:
                if edge_of[(min(node, nb), max(node, nb))] in avoided or nb in done:
                    continue
                if cost + edge_cost < best.get(nb, math.inf):
                    best[nb], parent[nb] = cost + edge_cost, node
                    heapq.heappush(heap, (cost + edge_cost, nb))
        ends = ((int(att.node_a[1]), float(att.cost_a[1])), (int(att.node_b[1]), float(att.cost_b[1])))
        total, last = min((best.get(n, math.inf) + c, n) for n, c in ends)
        if not math.isfinite(total):
            return None
        chain = [last]
        while parent[chain[-1]] >= 0:
            chain.append(parent[chain[-1]])
        points = [start, att.point[0], *self.nodes[chain[::-1]], att.point[1], goal]
        out = [np.asarray(points[0], dtype=np.float64)]
        for q in points[1:]:
            if np.hypot(*(np.asarray(q) - out[-1])) > DUPLICATE_EPS:
                out.append(np.asarray(q, dtype=np.float64))
        out[-1] = np.asarray(goal, dtype=np.float64)  # the goal exactly, as plan_batch keeps it
        return np.array(out)

    # ---------------------------------------------------------------- all-pairs table
    @cached_property
    def table(self) -> PathTable:
        """All-pairs shortest-path costs, next hops and hop counts, computed on first use.

        The table holds shortest paths of the same cost as `astar` for every pair (the tests
        check it on the shipped maps and on random graphs).
        """
        return floyd_warshall(self.nodes, self.edges)

    # ---------------------------------------------------------------- joining off-graph points
    # socialzoo.nav.attachment.attach, with this graph as its first argument.
    attach = attach

    # ---------------------------------------------------------------- planning
    def plan(self, start: np.ndarray, goal: np.ndarray, *, direct: bool = True) -> np.ndarray:
        """Waypoints from an off-graph start to an off-graph goal.

        The path is: start, its attach point, the graph nodes of the shortest path between the
        best pair of end nodes of the two attach edges, the goal's attach point, goal; consecutive
        duplicates are dropped. Start and goal on the same edge go along it without visiting a
        node; with `direct`, a wall-free straight line start-goal is used whenever it exists (it is
        then the shortest path). This is `plan_batch` on one row.

        Args:
            start: (2,) start position, world frame, m.
            goal: (2,) goal position, world frame, m.
            direct: allow the straight line.

        Returns:
            (L, 2) waypoints, L >= 1, first == start, last == goal.

        Raises:
            AttachError: start or goal reaches no edge of the graph.
            NoPathError: their attach edges are not connected.
        """
        paths, lengths = self.plan_batch(
            np.asarray(start, dtype=np.float64).reshape(1, 2),
            np.asarray(goal, dtype=np.float64).reshape(1, 2),
            direct=direct,
        )
        return paths[0, : lengths[0]]

    def plan_batch(
        self,
        starts: np.ndarray,
        goals: np.ndarray,
        *,
        direct: bool = True,
        clearance: float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Plan N start/goal pairs at once, as `plan` does for one.

        Vectorised over rows: one `attach` call for all starts and goals, one batched wall test
        for the direct lines, node sequences read from the all-pairs table with a loop over path
        length (never over rows). Safe to call every step; see `plan_batch_status` for a version
        that reports unreachable rows instead of raising.

        Args:
            starts: (N, 2) start positions, world frame, m.
            goals: (N, 2) goal positions, world frame, m.
            direct: allow straight start-goal lines where wall-free.
            clearance: with clearance > 0 (a robot's plans), the straight start-goal line is used
                only where it keeps this from every wall (m), and start and goal join the graph
                by lines that keep it where they can (see `attach`); a line grazing a door frame
                would lead the robot into it. 0: any wall-free line, as humans' routes are planned.

        Returns:
            (paths, lengths): paths (N, L, 2) m, each padded to the longest by repeating its last
            waypoint; lengths (N,) int number of valid waypoints.

        Raises:
            AttachError: a start or goal reaches no edge (the message names the point).
            NoPathError: a row's attach edges are not connected (the message names the row).
        """
        return self.plan_batch_status(starts, goals, direct=direct, clearance=clearance, strict=True)[:2]

    def plan_batch_status(
        self,
        starts: np.ndarray,
        goals: np.ndarray,
        *,
        direct: bool = True,
        clearance: float = 0.0,
        strict: bool = False,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`plan_batch` that never raises for an unreachable row, for batched envs (`strict`: raise
        as `plan_batch` does).

        Returns:
            (paths, lengths, ok): as `plan_batch`, plus ok (N,) bool; a row that is not ok (its
            start or goal reaches no edge, or they are not connected) gets the straight line
            [start, goal], which may cross walls.
        """
        starts = np.asarray(starts, dtype=np.float64).reshape(-1, 2)
        goals = np.asarray(goals, dtype=np.float64).reshape(-1, 2)
        if starts.shape != goals.shape:
            raise ValueError(f"{self.name}: starts {starts.shape} and goals {goals.shape} differ in shape")
        n = len(starts)
        if n == 0:
            return np.zeros((0, 1, 2)), np.zeros(0, dtype=np.intp), np.zeros(0, dtype=bool)
        direct_ok = segments_free(self.walls, starts, goals) if direct else np.zeros(n, dtype=bool)
        if clearance > 0 and direct_ok.any():
            direct_ok[direct_ok] = segments_clear(self.walls, starts[direct_ok], goals[direct_ok], clearance)
        need = ~direct_ok
        # Rows that go straight need no attach: they may even lie where no edge is reachable.
        rows = np.flatnonzero(need)
        node_s = np.zeros(n, dtype=np.intp)
        node_g = np.zeros(n, dtype=np.intp)
        point_s = starts.copy()
        point_g = goals.copy()
        mode = np.zeros(n, dtype=np.intp)  # 0 straight line, 1 via nodes, 2 along one edge
        ok = np.ones(n, dtype=bool)
        if len(rows):
            att = self.attach(np.concatenate((starts[rows], goals[rows])), strict=strict, clearance=clearance)
            m = len(rows)
            sa = take(att, slice(0, m))
            ga = take(att, slice(m, 2 * m))
            dist = self.table.dist
            ends_s = np.stack((sa.node_a, sa.node_b), 1)  # (m, 2)
            ends_g = np.stack((ga.node_a, ga.node_b), 1)
            cost_s = np.stack((sa.cost_a, sa.cost_b), 1)
            cost_g = np.stack((ga.cost_a, ga.cost_b), 1)
            via = cost_s[:, :, None] + dist[ends_s[:, :, None], ends_g[:, None, :]] + cost_g[:, None, :]
            via = via.reshape(m, 4)
            same_edge = (sa.edge >= 0) & (sa.edge == ga.edge)
            along = np.where(same_edge, np.sqrt(((sa.point - ga.point) ** 2).sum(-1)), np.inf)
            choice = np.argmin(via, axis=1)
            best = via[np.arange(m), choice]
            unreachable = ~np.isfinite(best) & ~np.isfinite(along)
            if strict and unreachable.any():
                bad = rows[int(np.flatnonzero(unreachable)[0])]
                raise NoPathError(
                    f"{self.name}: row {bad}: no path from {starts[bad].tolist()} to {goals[bad].tolist()}: "
                    "they join parts of the navigation graph that are not connected"
                )
            use_along = along <= best
            mode[rows] = np.where(unreachable, 0, np.where(use_along, 2, 1))
            ok[rows] = ~unreachable
            node_s[rows] = ends_s[np.arange(m), choice // 2]
            node_g[rows] = ends_g[np.arange(m), choice % 2]
            point_s[rows] = sa.point
            point_g[rows] = ga.point
        # Rows not via nodes repeat their start attach point (the start itself for direct rows)
        # in place of nodes; the duplicates are dropped below.
        via_nodes = np.flatnonzero(mode == 1)
        is_direct = mode == 0
        point_s = np.where(is_direct[:, None], starts, point_s)
        point_g = np.where(is_direct[:, None], starts, point_g)
        seq = self.table.node_paths(node_s[via_nodes], node_g[via_nodes])  # (len(via_nodes), K)
        node_pts = np.repeat(point_s[:, None, :], seq.shape[1], axis=1)
        node_pts[via_nodes] = self.nodes[seq]
        raw = np.concatenate(
            (starts[:, None], point_s[:, None], node_pts, point_g[:, None], goals[:, None]), axis=1
        )  # (n, K + 4, 2)
        step = np.sqrt(((raw[:, 1:] - raw[:, :-1]) ** 2).sum(-1))
        keep = np.concatenate((np.ones((n, 1), dtype=bool), step > DUPLICATE_EPS), axis=1)
        # Keep the goal exactly: if it duplicates the previous point, drop that one instead.
        last_dup = ~keep[:, -1]
        lengths = keep.sum(1)
        order = np.argsort(~keep, axis=1, kind="stable")
        compact = np.take_along_axis(raw, order[..., None], axis=1)
        idx = np.arange(n)
        compact[idx[last_dup], lengths[last_dup] - 1] = goals[last_dup]
        width = int(lengths.max())
        compact = compact[:, :width]
        pad = np.arange(width)[None, :] >= lengths[:, None]
        last = compact[idx, lengths - 1]
        paths = np.where(pad[..., None], last[:, None, :], compact)
        return paths, lengths.astype(np.intp), ok


_GRAPHS: weakref.WeakKeyDictionary[Map, NavGraph] = weakref.WeakKeyDictionary()


def graph_of(m: Map) -> NavGraph:
    """The navigation graph of a map, built once per map object and shared (with its caches)."""
    graph = _GRAPHS.get(m)
    if graph is None:
        graph = NavGraph.from_map(m)
        _GRAPHS[m] = graph
    return graph
