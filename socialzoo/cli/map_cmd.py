"""`socialzoo map list|show|import|validate`: see, check and import building maps."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np


def register(subparsers: Any) -> None:
    """Add `map` and its subcommands."""
    parser = subparsers.add_parser("map", help="list, show, validate and import maps")
    sub = parser.add_subparsers(dest="map_command", required=True, metavar="ACTION")

    listing = sub.add_parser("list", help="the shipped maps with their sizes")
    listing.set_defaults(func=run_list)

    show = sub.add_parser("show", help="draw a map (walls, graph, legal poses) to a PNG")
    show.add_argument("map", help="shipped map name or path to a map JSON file")
    show.add_argument("--out", type=Path, default=None, help="PNG file (default NAME.png)")
    show.add_argument("--no-graph", action="store_true", help="leave out the navigation graph")
    show.set_defaults(func=run_show)

    validate = sub.add_parser("validate", help="check a map file; exit 2 and name every problem")
    validate.add_argument("map", help="shipped map name or path to a map JSON file")
    validate.set_defaults(func=run_validate)

    imp = sub.add_parser(
        "import",
        help="turn a building's walls into a socialzoo map",
        description=(
            "Read walls from an AMRL vector map (one 'x1, y1, x2, y2' segment per line) or a pedsim "
            "scene XML, take the navigation graph from --nav (AMRL navigation JSON) or the scene's "
            "waypoints, or build one inside the building (from --seed-point, within --region), "
            "generate legal poses, validate, and write a socialzoo map JSON."
        ),
    )
    source = imp.add_mutually_exclusive_group(required=True)
    source.add_argument("--walls", type=Path, help="AMRL vector map text file")
    source.add_argument("--pedsim", type=Path, help="pedsim scene XML file")
    imp.add_argument("--nav", type=Path, default=None, help="AMRL navigation graph JSON")
    imp.add_argument("--name", required=True, help="map name")
    imp.add_argument("--region", type=float, nargs=4, metavar=("XMIN", "YMIN", "XMAX", "YMAX"), default=None)
    imp.add_argument(
        "--seed-point",
        type=float,
        nargs=2,
        metavar=("X", "Y"),
        default=None,
        help="a point inside the building: the graph covers what is reachable from it",
    )
    imp.add_argument("--source", default="", help="provenance text stored in the map")
    imp.add_argument("--licence", default="", help="licence text stored in the map")
    imp.add_argument("--out", type=Path, default=None, help="output JSON (default NAME.json)")
    imp.set_defaults(func=run_import)


def _fail(err: Exception) -> int:
    print(f"socialzoo map: error: {err}", file=sys.stderr)
    return 2


def run_list(args: argparse.Namespace) -> int:
    from socialzoo.nav.maps import list_maps, load_map

    for name in list_maps():
        m = load_map(name)
        print(
            f"{name:<14} {m.num_walls:5d} walls {m.num_nodes:4d} nodes {len(m.edges):4d} edges "
            f"{len(m.legal_poses):3d} poses  {m.source[:60]}"
        )
    return 0


def run_show(args: argparse.Namespace) -> int:
    from socialzoo.nav.maps import MapError, load_map
    from socialzoo.render.map_plot import save_map_png

    try:
        m = load_map(args.map)
    except (MapError, FileNotFoundError, KeyError) as err:
        return _fail(err)
    out = args.out or Path(f"{m.name}.png")
    save_map_png(m, out, show_graph=not args.no_graph)
    print(f"{out}: {m.name}, {m.num_walls} walls, {m.num_nodes} nodes, {len(m.legal_poses)} legal poses")
    return 0


def run_validate(args: argparse.Namespace) -> int:
    from socialzoo.nav.maps import MapError, load_map, validate_map

    try:
        validate_map(load_map(args.map))
    except (MapError, FileNotFoundError, KeyError) as err:
        return _fail(err)
    print(f"{args.map}: valid")
    return 0


def run_import(args: argparse.Namespace) -> int:
    from socialzoo.nav.importers import (
        drop_zero_length,
        read_amrl_nav_graph,
        read_pedsim_scene,
        read_vector_map,
    )
    from socialzoo.nav.maps import MapError
    from socialzoo.nav.roadmap import complete_map

    nodes = edges = None
    try:
        if args.walls is not None:
            walls = read_vector_map(args.walls)
        else:
            scene = read_pedsim_scene(args.pedsim)
            walls = scene.walls
            if len(scene.nodes):
                nodes = scene.nodes
        if args.nav is not None:
            nodes, edges = read_amrl_nav_graph(args.nav)
        walls = drop_zero_length(np.asarray(walls, dtype=np.float64), str(args.walls or args.pedsim))
        m = complete_map(
            args.name,
            walls,
            nodes=nodes,
            edges=edges,
            region=tuple(args.region) if args.region else None,
            seed_point=tuple(args.seed_point) if args.seed_point else None,
            source=args.source or f"imported from {args.walls or args.pedsim}",
            licence=args.licence,
        )
    except (MapError, FileNotFoundError, ValueError) as err:
        return _fail(err)
    out = m.save(args.out or Path(f"{args.name}.json"))
    print(
        f"{out}: {m.num_walls} walls, {m.num_nodes} nodes, {len(m.edges)} edges, {len(m.legal_poses)} poses"
    )
    return 0
