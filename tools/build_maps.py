"""Rebuild every shipped map in maps/ from the reference data and the hand-drawn small maps.

    python tools/build_maps.py [--reference maps/reference/socialgym]

gdc1: the reference walls of the benchmark area (the second floor plan drawn below y = -5 is
dropped), its 77 nodes and 26 legal poses; edges joined by socialzoo.maps.roadmap.build_edges.
ghc3: all 2082 reference walls; graph and legal poses generated inside the building, keeping only
poses whose routes to every other pose fit in the benchmark's time limit (at most 90 m).
Small maps (open_room, hallway, doorway, intersection): hand-drawn walls, generated graph and poses.
Every map is validated before it is written.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from socialzoo.maps.importers import drop_zero_length, read_table
from socialzoo.maps.map_completion import complete_map
from socialzoo.maps.map_file import Map
from socialzoo.maps.roadmap import RoadmapConfig
from socialzoo.nav.graph import graph_of

ROOT = Path(__file__).resolve().parents[1]
SOCIAL_GYM = (
    "MIT. Map data from social_gym 1.0, Copyright (c) 2021 Autonomous Mobile Robotics Laboratory, "
    "UT Austin (see NOTICE)"
)
OURS = "CC0-1.0 (part of socialzoo)"
# The roadmap settings the shipped maps were built with (before keep_clearance and
# join_clearance existed): the benchmark's test sets depend on their graphs and poses, so a
# rebuild must reproduce them.
SHIPPED = RoadmapConfig(
    resolution=0.1, free_clearance=0.35, edge_clearance=0.3, keep_clearance=0.0, join_clearance=0.0
)


def box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


# name -> (walls, region, a point inside)
SMALL_MAPS = {
    "open_room": (box(0, 0, 10, 10), (-1.0, -1.0, 11.0, 11.0), (5.0, 5.0)),
    "hallway": (
        # two 8 x 9 m rooms joined by a 2 m wide, 14 m long corridor
        [
            [0, 0, 8, 0],
            [8, 0, 8, 3.5],
            [8, 5.5, 8, 9],
            [8, 9, 0, 9],
            [0, 9, 0, 0],
            [8, 3.5, 22, 3.5],
            [8, 5.5, 22, 5.5],
            [22, 0, 30, 0],
            [30, 0, 30, 9],
            [30, 9, 22, 9],
            [22, 9, 22, 5.5],
            [22, 3.5, 22, 0],
        ],
        (-1.0, -1.0, 31.0, 10.0),
        (4.0, 4.5),
    ),
    "doorway": (
        # two rooms split by a wall with a 1.2 m door
        [[0, 0, 16, 0], [16, 0, 16, 8], [16, 8, 0, 8], [0, 8, 0, 0], [8, 0, 8, 3.4], [8, 4.6, 8, 8]],
        (-1.0, -1.0, 17.0, 9.0),
        (4.0, 4.0),
    ),
    "intersection": (
        # two 2 m wide, 20 m long corridors crossing at the origin
        [
            [-10, -1, -1, -1],
            [-1, -1, -1, -10],
            [1, -10, 1, -1],
            [1, -1, 10, -1],
            [10, 1, 1, 1],
            [1, 1, 1, 10],
            [-1, 10, -1, 1],
            [-1, 1, -10, 1],
            [-10, -1, -10, 1],
            [10, -1, 10, 1],
            [-1, -10, 1, -10],
            [-1, 10, 1, 10],
        ],
        (-11.0, -11.0, 11.0, 11.0),
        (0.0, 0.0),
    ),
}


def build_gdc1(reference: Path, out_dir: Path) -> None:
    walls = read_table(reference / "gdc1_walls.txt", 4, "x1 y1 x2 y2")
    walls = drop_zero_length(walls[(walls[:, 1] > -5.0) & (walls[:, 3] > -5.0)], "gdc1_walls.txt")
    m = complete_map(
        "gdc1",
        walls,
        nodes=read_table(reference / "gdc1_nav_nodes.txt", 2, "x y"),
        legal_poses=read_table(reference / "gdc1_legal_poses.txt", 3, "x y theta"),
        region=(-43.0, -1.0, 45.0, 35.0),
        config=SHIPPED,
        source=(
            "social_gym 1.0: UT Gates Dell Complex floor 1 (gdc1_walls.txt, gdc1_nav_nodes.txt, "
            "gdc1_legal_poses.txt); edges built by socialzoo"
        ),
        licence=SOCIAL_GYM,
    )
    m.save(out_dir / "gdc1.json")
    print(f"gdc1: {m.num_walls} walls, {m.num_nodes} nodes, {len(m.edges)} edges, {len(m.legal_poses)} poses")


# A legal pose pair whose route is longer than this cannot be driven within the benchmark's 80 s
# (60 s at GoAlone's 1.5 m/s, leaving 20 s for doors, turns and people), m.
MAX_ROUTE = 90.0


def drop_far_poses(m: Map, max_route: float = MAX_ROUTE) -> Map:
    """The map without the legal poses that make some route longer than max_route.

    Repeatedly drops the pose with the most over-long routes to the others (ties: the lowest index).
    """
    graph = graph_of(m)
    poses = m.legal_poses[:, :2]
    n = len(poses)
    first, second = np.nonzero(~np.eye(n, dtype=bool))
    paths, _ = graph.plan_batch(poses[first], poses[second])
    length = np.zeros((n, n))
    length[first, second] = np.linalg.norm(np.diff(paths, axis=1), axis=-1).sum(-1)
    keep = list(range(n))
    while True:
        too_long = (length[np.ix_(keep, keep)] > max_route).sum(axis=1)
        if too_long.max() == 0:
            break
        keep.pop(int(np.argmax(too_long)))
    return dataclasses.replace(m, legal_poses=m.legal_poses[keep])


def build_ghc3(reference: Path, out_dir: Path) -> None:
    m = complete_map(
        "ghc3",
        read_table(reference / "ghc3_walls.txt", 4, "x1 y1 x2 y2"),
        region=(-25.0, -37.0, 40.0, 27.0),
        seed_point=(-5.0, -10.0),
        config=SHIPPED,
        source=(
            "social_gym 1.0: CMU Gates Hillman Center floor 3 (ghc3_walls.txt); navigation graph and "
            "legal poses generated by socialzoo.maps.roadmap inside the building"
        ),
        licence=SOCIAL_GYM,
    )
    m = drop_far_poses(m)
    m.save(out_dir / "ghc3.json")
    print(f"ghc3: {m.num_walls} walls, {m.num_nodes} nodes, {len(m.edges)} edges, {len(m.legal_poses)} poses")


def build_small(out_dir: Path) -> None:
    for name, (walls, region, inside) in SMALL_MAPS.items():
        m = complete_map(
            name,
            np.array(walls, dtype=np.float64),
            region=region,
            seed_point=inside,
            config=SHIPPED,
            source="socialzoo: hand-drawn test map (tools/build_maps.py)",
            licence=OURS,
        )
        m.save(out_dir / f"{name}.json")
        print(
            f"{name}: {m.num_walls} walls, {m.num_nodes} nodes, {len(m.edges)} edges, {len(m.legal_poses)} poses"
        )


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--reference", type=Path, default=ROOT / "maps" / "reference" / "socialgym")
    parser.add_argument("--out-dir", type=Path, default=ROOT / "maps", help="where to write (default maps/)")
    args = parser.parse_args()
    build_gdc1(args.reference, args.out_dir)
    build_ghc3(args.reference, args.out_dir)
    build_small(args.out_dir)


if __name__ == "__main__":
    main()
