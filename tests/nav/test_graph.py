"""NavGraph: A* against networkx, the all-pairs table against A*, attach and wall-free plans."""

from __future__ import annotations

import dataclasses
import itertools

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from socialzoo.core.walls import WallIndex
from socialzoo.maps import map_file as maps
from socialzoo.maps.map_file import Map, segment_clearance
from socialzoo.maps.segments import segments_free
from socialzoo.nav.attachment import AttachError
from socialzoo.nav.graph import NavGraph, NoPathError, graph_of


def gdc1() -> Map:
    return maps.load_map("gdc1")


def to_networkx(g: NavGraph) -> nx.Graph:
    out = nx.Graph()
    out.add_nodes_from(range(g.num_nodes))
    for (i, j), c in zip(g.edges.tolist(), g.edge_cost.tolist(), strict=True):
        out.add_edge(i, j, weight=c)
    return out


def path_cost(g: NavGraph, path: list[int]) -> float:
    p = g.nodes[np.asarray(path, dtype=np.intp)]
    return float(np.sqrt(((p[1:] - p[:-1]) ** 2).sum(-1)).sum())


def check_graph_against_networkx(g: NavGraph) -> None:
    ref = dict(nx.all_pairs_dijkstra_path_length(to_networkx(g)))
    table = g.table
    edge_set = {frozenset(e) for e in g.edges.tolist()}
    for s, t in itertools.product(range(g.num_nodes), repeat=2):
        if t in ref[s]:
            path = g.astar(s, t)
            assert path[0] == s and path[-1] == t
            assert all(frozenset(e) in edge_set for e in itertools.pairwise(path))
            assert path_cost(g, path) == pytest.approx(ref[s][t], rel=1e-9, abs=1e-9)
            assert table.dist[s, t] == pytest.approx(ref[s][t], rel=1e-9, abs=1e-9)
            via_table = table.node_paths(np.array([s]), np.array([t]))[0][: table.hops[s, t] + 1].tolist()
            assert via_table[0] == s and via_table[-1] == t
            assert len(via_table) == table.hops[s, t] + 1
            assert all(frozenset(e) in edge_set for e in itertools.pairwise(via_table))
            assert path_cost(g, via_table) == pytest.approx(ref[s][t], rel=1e-9, abs=1e-9)
        else:
            with pytest.raises(NoPathError, match=f"node {s}"):
                g.astar(s, t)
            assert np.isinf(table.dist[s, t])
            assert table.hops[s, t] == -1


@st.composite
def random_graphs(draw: st.DrawFn) -> NavGraph:
    n = draw(st.integers(1, 14))
    coords = draw(st.lists(st.tuples(st.integers(-50, 50), st.integers(-50, 50)), min_size=n, max_size=n))
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
    edges = draw(st.lists(st.sampled_from(pairs), max_size=3 * n)) if pairs else []
    nodes = np.array(coords, dtype=np.float64) * 0.37
    nodes += np.arange(n)[:, None] * 1e-3  # no two nodes on the same spot
    return NavGraph(nodes, np.array(edges, dtype=np.int64).reshape(-1, 2))


@settings(max_examples=60, deadline=None)
@given(random_graphs())
def test_astar_and_table_equal_networkx_on_random_graphs(g: NavGraph) -> None:
    check_graph_against_networkx(g)


def test_astar_and_table_equal_networkx_on_gdc1() -> None:
    check_graph_against_networkx(graph_of(gdc1()))


def test_astar_is_cached_and_returns_copies() -> None:
    g = NavGraph.from_map(gdc1())
    path = g.astar(0, 5)
    path.append(-7)
    assert g.astar(0, 5)[-1] == 5
    assert (0, 5) in g._astar_cache


def gdc1_pose_pairs() -> tuple[np.ndarray, np.ndarray]:
    poses = gdc1().legal_poses[:, :2]
    i, j = np.nonzero(~np.eye(len(poses), dtype=bool))
    return poses[i], poses[j]


@pytest.mark.parametrize("direct", [True, False])
def test_plans_between_all_gdc1_poses_never_cross_walls(direct: bool) -> None:
    m = gdc1()
    g = graph_of(m)
    starts, goals = gdc1_pose_pairs()
    assert len(starts) == 26 * 25
    paths, lengths = g.plan_batch(starts, goals, direct=direct)
    assert paths.shape == (len(starts), int(lengths.max()), 2)
    np.testing.assert_array_equal(paths[:, 0], starts)
    np.testing.assert_array_equal(paths[np.arange(len(starts)), lengths - 1], goals)
    # Every consecutive pair, padding included (padding repeats the goal: a zero-length segment).
    crossed = m.wall_index.crosses(paths[:, :-1], paths[:, 1:])
    assert not crossed.any(), np.argwhere(crossed)[:5]
    pad = np.arange(paths.shape[1])[None] >= lengths[:, None]
    np.testing.assert_array_equal(np.where(pad[..., None], goals[:, None], paths), paths)
    # Never shorter than the straight line; a single plan equals its batch row.
    length = np.where(~pad[:, 1:], np.linalg.norm(np.diff(paths, axis=1), axis=-1), 0.0).sum(1)
    assert np.all(length >= np.linalg.norm(goals - starts, axis=1) - 1e-9)
    for row in (0, 17, 333, 649):
        np.testing.assert_array_equal(
            g.plan(starts[row], goals[row], direct=direct), paths[row, : lengths[row]]
        )


def test_plan_uses_the_graph_optimally() -> None:
    """Without the direct line, a plan costs the attach legs plus the table distance, minimised."""
    g = graph_of(gdc1())
    starts, goals = gdc1_pose_pairs()
    paths, _ = g.plan_batch(starts, goals, direct=False)
    sa, ga = g.attach(starts), g.attach(goals)
    ends_s = np.stack((sa.node_a, sa.node_b), 1)
    ends_g = np.stack((ga.node_a, ga.node_b), 1)
    cost_s = np.stack((sa.cost_a, sa.cost_b), 1)
    cost_g = np.stack((ga.cost_a, ga.cost_b), 1)
    best = (cost_s[:, :, None] + g.table.dist[ends_s[:, :, None], ends_g[:, None, :]] + cost_g[:, None]).min(
        (1, 2)
    )
    same = (sa.edge >= 0) & (sa.edge == ga.edge)
    best = np.where(same, np.minimum(best, np.linalg.norm(sa.point - ga.point, axis=1)), best)
    expected = sa.dist + best + ga.dist
    length = np.linalg.norm(np.diff(paths, axis=1), axis=-1).sum(1)
    np.testing.assert_allclose(length, expected, rtol=1e-9, atol=1e-9)


def test_attach_picks_the_nearest_reachable_point() -> None:
    m = gdc1()
    g = graph_of(m)
    rng = np.random.default_rng(0)
    points = np.concatenate((m.legal_poses[:, :2], m.legal_poses[:, :2] + rng.uniform(-0.4, 0.4, (26, 2))))
    att = g.attach(points)
    assert segments_free(m.wall_index, points, att.point).all()
    np.testing.assert_allclose(np.linalg.norm(att.point - points, axis=1), att.dist)
    # The point lies on its edge, at the stated distances from the edge's ends.
    on_edge = att.edge >= 0
    a, b = g.nodes[att.node_a], g.nodes[att.node_b]
    np.testing.assert_allclose(np.linalg.norm(att.point - a, axis=1), att.cost_a, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(att.point - b, axis=1), att.cost_b, atol=1e-9)
    np.testing.assert_allclose((att.cost_a + att.cost_b)[on_edge], np.linalg.norm(a - b, axis=1)[on_edge])
    # Brute force: no reachable candidate (closest point of an edge, or a node) is nearer.
    for p, d in zip(points, att.dist, strict=True):
        ea, eb = g.nodes[g.edges[:, 0]], g.nodes[g.edges[:, 1]]
        t = np.clip(((p - ea) * (eb - ea)).sum(1) / ((eb - ea) ** 2).sum(1), 0, 1)
        cand = np.concatenate((ea + t[:, None] * (eb - ea), g.nodes))
        free = segments_free(m.wall_index, np.broadcast_to(p, cand.shape), cand)
        assert d <= np.linalg.norm(cand - p, axis=1)[free].min() + 1e-9


def box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


def corridor_graph() -> NavGraph:
    """Two parallel corridors y=0 and y=4 joined at x=10, a wall y=2 from x=-1 to x=9."""
    nodes = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 4.0], [0.0, 4.0]])
    edges = np.array([[0, 1], [1, 2], [2, 3]])
    walls = np.array([[-1.0, 2.0, 9.0, 2.0], [-1.0, -1.0, 11.0, -1.0], [-1.0, 5.0, 11.0, 5.0]])
    return NavGraph(nodes, edges, WallIndex(walls), name="corridors")


def test_attach_skips_an_edge_behind_a_wall() -> None:
    g = corridor_graph()
    att = g.attach(np.array([[3.0, 2.2], [3.0, 1.8]]))
    np.testing.assert_allclose(att.point, [[3.0, 4.0], [3.0, 0.0]])
    np.testing.assert_array_equal(att.edge, [2, 0])


def test_attach_falls_back_beyond_k_candidates() -> None:
    g = corridor_graph()
    att = g.attach(np.array([[3.0, 2.2]]), k=1)
    np.testing.assert_allclose(att.point, [[3.0, 4.0]])


def test_plan_around_a_wall_and_along_one_edge() -> None:
    g = corridor_graph()
    path = g.plan(np.array([2.0, 0.5]), np.array([2.0, 3.5]))
    np.testing.assert_allclose(path, [[2, 0.5], [2, 0], [10, 0], [10, 4], [2, 4], [2, 3.5]])
    same = g.plan(np.array([2.0, 0.5]), np.array([7.0, -0.5]), direct=False)
    np.testing.assert_allclose(same, [[2, 0.5], [2, 0], [7, 0], [7, -0.5]])
    assert len(g.plan(np.array([2.0, 0.5]), np.array([7.0, -0.5]))) == 2


def test_plan_from_a_node_and_to_the_same_point() -> None:
    g = corridor_graph()
    np.testing.assert_allclose(
        g.plan(np.array([0.0, 0.0]), np.array([0.0, 4.0])), [[0, 0], [10, 0], [10, 4], [0, 4]]
    )
    np.testing.assert_allclose(g.plan(np.array([1.0, 1.0]), np.array([1.0, 1.0])), [[1, 1]])


def test_plan_batch_pads_to_the_longest_path() -> None:
    g = corridor_graph()
    starts = np.array([[2.0, 0.5], [2.0, 0.5]])
    goals = np.array([[2.0, 3.5], [3.0, 0.5]])
    paths, lengths = g.plan_batch(starts, goals)
    assert paths.shape == (2, 6, 2)
    np.testing.assert_array_equal(lengths, [6, 2])
    np.testing.assert_array_equal(paths[1, 2:], np.broadcast_to(goals[1], (4, 2)))
    empty, lens = g.plan_batch(np.zeros((0, 2)), np.zeros((0, 2)))
    assert empty.shape == (0, 1, 2) and lens.shape == (0,)


def test_unreachable_goal_and_enclosed_point_raise_clear_errors() -> None:
    g = corridor_graph()
    boxed = np.array(
        [
            [20.0, 20.0, 22.0, 20.0],
            [22.0, 20.0, 22.0, 22.0],
            [22.0, 22.0, 20.0, 22.0],
            [20.0, 22.0, 20.0, 20.0],
        ]
    )
    walls = WallIndex(np.concatenate((g.walls.walls, boxed)))  # type: ignore[union-attr]
    g = NavGraph(g.nodes, g.edges, walls, name="corridors")
    with pytest.raises(AttachError, match=r"point \[21.0, 21.0\] reaches no edge"):
        g.plan(np.array([2.0, 0.5]), np.array([21.0, 21.0]))
    # A graph in two pieces: node 4 alone in the box.
    split = NavGraph(np.concatenate((g.nodes, [[21.5, 21.5]])), g.edges, walls, name="split")
    with pytest.raises(NoPathError, match="not connected"):
        split.plan(np.array([2.0, 0.5]), np.array([21.0, 21.0]))
    with pytest.raises(NoPathError, match="no path from node 0"):
        split.astar(0, 4)
    with pytest.raises(ValueError, match=r"outside 0\.\.4"):
        split.astar(0, 5)


def test_empty_map_and_bad_graphs_raise() -> None:
    empty = Map(
        name="empty",
        walls=np.zeros((0, 4)),
        nodes=np.zeros((0, 2)),
        edges=np.zeros((0, 2), int),
        legal_poses=np.zeros((0, 3)),
    )
    g = NavGraph.from_map(empty)
    with pytest.raises(AttachError, match="no nodes"):
        g.plan(np.zeros(2), np.ones(2), direct=False)
    # With no walls the straight line needs no graph at all.
    np.testing.assert_array_equal(g.plan(np.zeros(2), np.ones(2)), [[0, 0], [1, 1]])
    with pytest.raises(ValueError, match=r"edge 1 = \[0, 3\] names a node outside 0..2"):
        NavGraph(np.zeros((3, 2)), np.array([[0, 1], [0, 3]]))
    with pytest.raises(ValueError, match="joins node 2 to itself"):
        NavGraph(np.zeros((3, 2)), np.array([[2, 2]]))
    with pytest.raises(ValueError, match="nodes must be a finite"):
        NavGraph(np.full((3, 2), np.nan), np.zeros((0, 2), int))


def test_duplicate_edges_are_merged() -> None:
    g = NavGraph(np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([[0, 1], [1, 0], [0, 1]]))
    assert g.num_edges == 1


def test_graph_of_is_shared_per_map() -> None:
    m = gdc1()
    assert graph_of(m) is graph_of(m)
    assert graph_of(dataclasses.replace(m)) is not graph_of(m)


def test_plan_batch_status_reports_unreachable_rows_without_raising() -> None:
    g = corridor_graph()
    boxed = np.array(box(20.0, 20.0, 22.0, 22.0) + box(29.0, 29.0, 31.0, 31.0))
    walls = WallIndex(np.concatenate((g.walls.walls, boxed)))  # type: ignore[union-attr]
    split = NavGraph(np.concatenate((g.nodes, [[21.5, 21.5]])), g.edges, walls, name="split")
    starts = np.array([[2.0, 0.5], [2.0, 0.5], [21.0, 21.0], [2.0, 0.5]])
    goals = np.array([[2.0, 3.5], [21.0, 21.0], [21.2, 21.2], [30.0, 30.0]])
    paths, lengths, ok = split.plan_batch_status(starts, goals)
    np.testing.assert_array_equal(ok, [True, False, True, False])
    np.testing.assert_array_equal(lengths, [6, 2, 2, 2])
    np.testing.assert_array_equal(paths[1, :2], [starts[1], goals[1]])
    att = split.attach(np.array([[2.0, 0.5], [30.0, 30.0]]), strict=False)
    np.testing.assert_array_equal(att.found, [True, False])
    assert att.edge[1] == -1 and np.isinf(att.dist[1])
    with pytest.raises(AttachError, match=r"point \[30.0, 30.0\]"):
        split.attach(np.array([[30.0, 30.0]]))
    empty = NavGraph(np.zeros((0, 2)), np.zeros((0, 2), int))
    assert not empty.attach(np.zeros((2, 2)), strict=False).found.any()


def test_robot_plans_keep_clearance_where_they_can() -> None:
    # Two rooms, a 0.9 m door at y 3.55..4.45; a graph node on each side, in line with the door.
    walls = np.array([*box(0, 0, 16, 8), [8, 0, 8, 3.55], [8, 4.45, 8, 8]], dtype=np.float64)
    g = NavGraph(np.array([[4.0, 4.0], [12.0, 4.0]]), np.array([[0, 1]]), WallIndex(walls))
    start, goal = np.array([[9.0, 4.0]]), np.array([[1.0, 7.0]])
    # The straight start-goal line passes the door 0.05 m from its upper jamb: humans take it ...
    grazing, _ = g.plan_batch(start, goal)
    assert len(grazing[0]) == 2
    # ... a robot keeping 0.37 m goes along the graph, through the middle of the door.
    paths, lengths = g.plan_batch(start, goal, clearance=0.37)
    path = paths[0, : lengths[0]]
    assert len(path) > 2
    assert segment_clearance(g.walls, path[:-1], path[1:])[0].min() >= 0.37
