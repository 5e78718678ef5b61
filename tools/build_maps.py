"""Rebuild every shipped map in maps/ from the reference data and the hand-drawn small maps.

    python tools/build_maps.py [--reference maps/reference/socialgym]

gdc1: the reference walls of the benchmark area (the second floor plan drawn below y = -5 is
dropped), its 77 nodes and 26 legal poses; edges joined by socialzoo.maps.roadmap.build_edges.
ghc3: all 2082 reference walls; graph and legal poses generated inside the building, keeping only
poses whose routes to every other pose fit in the benchmark's time limit (at most 90 m).
Small maps (open_room, hallway, doorway, intersection): hand-drawn walls, generated graph and poses.
Scenario-suite maps (corner, narrow_hallway, room, elevator, plaza): likewise, with today's roadmap
settings pinned (SUITE). Doors (openings a scenario may close) are drawn by hand beside the walls.
Every map is validated before it is written.
"""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass
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
# The settings the scenario-suite maps are built with: RoadmapConfig's defaults when they were
# drawn, written out so that a later change of the defaults leaves these maps as they are.
SUITE = RoadmapConfig(
    resolution=0.05,
    margin=2.0,
    free_clearance=0.39,
    closing_radius=1.5,
    node_clearance=0.45,
    min_spacing=1.5,
    max_spacing=5.0,
    spacing_per_clearance=3.0,
    edge_clearance=0.4,
    keep_clearance=0.45,
    max_edge_length=15.0,
    detour_tolerance=1.15,
    num_poses=25,
    pose_clearance=0.6,
    join_clearance=0.39,
    pose_separation=2.0,
    good_clearance=1.0,
)
# The elevator car (2.4 x 2.2 m) is smaller than SUITE's spacing: nodes at most 3 m apart give it a
# node of its own (the lobby's node covers it otherwise), and poses 1 m apart, all as good as any
# other from 0.6 m clearance on, put two in it (1.4 m apart, in opposite corners).
ELEVATOR = dataclasses.replace(SUITE, max_spacing=3.0, pose_separation=1.0, good_clearance=0.6)


def box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


@dataclass(frozen=True)
class SmallMap:
    """A hand-drawn map: walls, the area of interest, a point inside, doors and roadmap settings."""

    walls: list[list[float]]
    region: tuple[float, float, float, float]
    inside: tuple[float, float]
    doors: list[list[float]] = dataclasses.field(default_factory=list)
    config: RoadmapConfig = SHIPPED
    source: str = "socialzoo: hand-drawn test map (tools/build_maps.py)"


SUITE_SOURCE = "socialzoo: hand-drawn map of the scenario suite (tools/build_maps.py)"

SMALL_MAPS = {
    "open_room": SmallMap(box(0, 0, 10, 10), (-1.0, -1.0, 11.0, 11.0), (5.0, 5.0)),
    "hallway": SmallMap(
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
    "doorway": SmallMap(
        # two rooms split by a wall with a 1.2 m door
        [[0, 0, 16, 0], [16, 0, 16, 8], [16, 8, 0, 8], [0, 8, 0, 0], [8, 0, 8, 3.4], [8, 4.6, 8, 8]],
        (-1.0, -1.0, 17.0, 9.0),
        (4.0, 4.0),
        doors=[[8, 3.4, 8, 4.6]],
    ),
    "intersection": SmallMap(
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
    "corner": SmallMap(
        # an L-shaped corridor 2 m wide: one leg along x (y in [0, 2]), one along y (x in [0, 2]),
        # each 11 m long on its centre line from the corner (1, 1); closed ends at x = 12 and
        # y = 12. The inner corner (2, 2) is solid: neither leg sees into the other.
        [[0, 0, 12, 0], [12, 0, 12, 2], [12, 2, 2, 2], [2, 2, 2, 12], [2, 12, 0, 12], [0, 12, 0, 0]],
        (-1.0, -1.0, 13.0, 13.0),
        (1.0, 1.0),
        config=SUITE,
        source=SUITE_SOURCE,
    ),
    "narrow_hallway": SmallMap(
        # two 6 x 6 m rooms, x in [0, 6] and [16, 22], joined by a corridor 1.4 m wide and 10 m long
        # (x in [6, 16], y in [2.3, 3.7], its axis y = 3)
        [
            [0, 0, 6, 0],
            [6, 0, 6, 2.3],
            [6, 2.3, 16, 2.3],
            [16, 2.3, 16, 0],
            [16, 0, 22, 0],
            [22, 0, 22, 6],
            [22, 6, 16, 6],
            [16, 6, 16, 3.7],
            [16, 3.7, 6, 3.7],
            [6, 3.7, 6, 6],
            [6, 6, 0, 6],
            [0, 6, 0, 0],
        ],
        (-1.0, -1.0, 23.0, 7.0),
        (3.0, 3.0),
        config=SUITE,
        source=SUITE_SOURCE,
    ),
    "room": SmallMap(
        # a corridor 3 m wide and 16 m long, closed at both ends (x in [0, 16], y in [0, 3], its axis
        # y = 1.5), and a 6 x 5 m room beside it (x in [5, 11], y in [3, 8]) behind a 1.2 m door in
        # the corridor's wall at its middle (x in [7.4, 8.6])
        [
            [0, 0, 16, 0],
            [16, 0, 16, 3],
            [16, 3, 8.6, 3],
            [7.4, 3, 0, 3],
            [0, 3, 0, 0],
            [5, 3, 5, 8],
            [5, 8, 11, 8],
            [11, 8, 11, 3],
        ],
        (-1.0, -1.0, 17.0, 9.0),
        (2.0, 1.5),
        doors=[[7.4, 3, 8.6, 3]],
        config=SUITE,
        source=SUITE_SOURCE,
    ),
    "elevator": SmallMap(
        # a 12 x 5 m lobby (x in [0, 12], y in [0, 5]) and an elevator car on its long side, interior
        # 2.4 x 2.2 m (x in [4.8, 7.2], y in [5, 7.2]), behind a 1.2 m opening (x in [5.4, 6.6])
        [
            [0, 0, 12, 0],
            [12, 0, 12, 5],
            [12, 5, 6.6, 5],
            [5.4, 5, 0, 5],
            [0, 5, 0, 0],
            [4.8, 5, 4.8, 7.2],
            [4.8, 7.2, 7.2, 7.2],
            [7.2, 7.2, 7.2, 5],
        ],
        (-1.0, -1.0, 13.0, 8.2),
        (2.0, 2.5),
        doors=[[5.4, 5, 6.6, 5]],
        config=ELEVATOR,
        source=SUITE_SOURCE,
    ),
    "plaza": SmallMap(
        # an open 20 x 14 m area with walls round it
        box(0, 0, 20, 14),
        (-1.0, -1.0, 21.0, 15.0),
        (10.0, 7.0),
        config=SUITE,
        source=SUITE_SOURCE,
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
    for name, spec in SMALL_MAPS.items():
        m = complete_map(
            name,
            np.array(spec.walls, dtype=np.float64),
            region=spec.region,
            seed_point=spec.inside,
            config=spec.config,
            source=spec.source,
            licence=OURS,
        )
        if spec.doors:
            m = dataclasses.replace(m, doors=np.array(spec.doors, dtype=np.float64).reshape(-1, 4))
        m.save(out_dir / f"{name}.json")
        print(
            f"{name}: {m.num_walls} walls, {m.num_nodes} nodes, {len(m.edges)} edges, "
            f"{len(m.legal_poses)} poses, {m.num_doors} doors"
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
