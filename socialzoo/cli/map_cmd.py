"""`socialzoo map list|show|validate|check|import|drive`: see, check, import and drive building maps."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import count, out_dir, out_file, out_path, positive_float, positive_int

# A building of `map drive`'s folder: NAME.vectormap.txt, with NAME.navigation.json beside it.
VECTOR_MAP, NAVIGATION = ".vectormap.txt", ".navigation.json"
# Steps of an import that generate what the source lacks (the others repair what it has).
GENERATED = ("graph_generated", "edges_built", "poses_generated")


def register(subparsers: Any) -> None:
    """Add `map` and its subcommands.

    `show` and `check` draw a picture only where asked (--picture PATH) or beside a map file, never
    into the current directory or the package's maps folder, and always say where it went.
    """
    parser = subparsers.add_parser("map", help=command_help("map"))
    sub = parser.add_subparsers(dest="map_command", required=True, metavar="ACTION")

    listing = sub.add_parser("list", help="the shipped maps with their sizes")
    listing.set_defaults(func=run_list)

    show = sub.add_parser(
        "show",
        help="draw a map (walls, graph, legal poses) to a PNG",
        description=(
            "Draw a map's walls, navigation graph and legal poses to a PNG: to --picture PATH, or "
            "beside a map file (FILE-map.png). A shipped map name writes nothing unless --picture "
            "is given (the package's maps folder may be read-only). Prints where the picture went."
        ),
    )
    show.add_argument("map", help="shipped map name or path to a map JSON file")
    _add_picture_options(show, "map", no_picture=False)
    show.add_argument("--no-graph", action="store_true", help="leave out the navigation graph")
    show.set_defaults(func=run_show)

    validate = sub.add_parser("validate", help="check a map file; exit 2 and name every problem")
    validate.add_argument("map", help="shipped map name or path to a map JSON file")
    validate.set_defaults(func=run_validate)

    check = sub.add_parser(
        "check",
        help="judge a map before training on it: clearance, connectivity, feasible routes, a picture",
        description=(
            "Validate a map and report the wall clearance of its nodes, edges and legal poses, its "
            "graph components, the edges closer to a wall than the robot keeps (it leaves its path "
            "there), and the feasible-route statistics of its legal poses (a route is feasible when "
            "it is at most --max-route metres: 75% of the 80 s time limit at 1.5 m/s). Draws the "
            "walls, the graph (tight edges in red) and the poses (stranded ones in red) to "
            "--picture PATH, or beside a map file (FILE-check.png); a shipped map name gets no "
            "picture unless --picture is given. Prints where the picture went. With --drive the "
            "map checks itself by driving: the robot alone (GoAlone, no people, one batched world) "
            "drives every feasible pose pair (or a seeded sample of N) within 80 s, and every route "
            "it cannot complete is reported with where it stopped and why (blocked doorway, goal "
            "unreachable, start cannot be left, oscillation, stuck, wall collision, timeout) and "
            "marked on the picture. Exit status 0 for a valid map (whose driven routes were all "
            "completed), 1 when a driven route failed, 2 for an invalid map."
        ),
    )
    check.add_argument("map", help="shipped map name or path to a map JSON file")
    check.add_argument(
        "--max-route", type=positive_float, default=None, help="feasible route length, m (default 90)"
    )
    check.add_argument(
        "--drive", nargs="?", type=count, const=0, default=None, metavar="N",
        help="drive every feasible pose pair (or a seeded sample of N pairs) and report the failed routes",
    )  # fmt: skip
    check.add_argument("--seed", type=count, default=0, help="seed of the --drive N sample (default 0)")
    _add_picture_options(check, "check", no_picture=True)
    check.set_defaults(func=run_check)

    imp = sub.add_parser(
        "import",
        help="turn a building's walls (vector map, pedsim scene or floor-plan image) into a socialzoo map",
        description=(
            "Read walls from an AMRL vector map (one 'x1, y1, x2, y2' segment per line), a pedsim "
            "scene XML or a floor-plan image (PNG occupancy grid: dark pixels are walls, --scale "
            "metres per pixel; or a ROS map_server map YAML, which gives the image, scale, origin "
            "and threshold), take the navigation graph from --nav (AMRL navigation JSON) or the "
            "scene's waypoints, or build one inside the building (from --seed-point, within "
            "--region; default the largest enclosed area; openings of the outline to space the plan "
            "does not map, such as doorways to nowhere wider than 3 m, are closed by virtual walls "
            "where nothing else is enclosed, and reported), generate legal poses, and write a "
            "socialzoo map JSON. What the source gets wrong is repaired and reported: nodes on or "
            "in walls are moved to the nearest clear point (or dropped), edges through walls are "
            "rerouted along walking paths (or dropped), stray graph components are joined where the "
            "free space joins them and dropped otherwise, legal poses are moved clear of walls (or "
            "dropped, and generated when fewer than two are left). Then the map checks itself by "
            "driving (as map check --drive): a pose the robot cannot reach or leave is moved where "
            "it can (or dropped), an edge through a gap too narrow for the robot is dropped, and "
            "while a route still fails the pose in most failed routes is dropped, so that scenarios "
            "draw only pairs the robot has driven (--no-drive skips this). Every repair is printed "
            "and stored in the map's provenance. --strict refuses the source instead (exit 2)."
        ),
    )
    _add_import_arguments(imp)
    imp.set_defaults(func=run_import)

    drive = sub.add_parser(
        "drive",
        help="import buildings as `map import` does and report GoAlone's success among people on each",
        description=(
            "Import every NAME.vectormap.txt of DIR (with its navigation graph NAME.navigation.json "
            "when there is one) as `socialzoo map import --walls NAME.vectormap.txt [--nav "
            "NAME.navigation.json] --name NAME` does (repairs and the drive check included), to "
            "OUT/NAME.json (what the import said: OUT/NAME.import.txt); without DIR, the built-in "
            "buildings (the second floor plan in the social_gym GDC1 data and the raw GHC3 walls, "
            "shipped with the package, and seeded synthetic plans), written to OUT/buildings/ first. "
            "GoAlone then runs on the first --episodes scenarios of the test set `socialzoo "
            "benchmark --maps OUT/NAME.json` generates (base seed 20220100, stored in "
            "OUT/test_sets), and a Markdown table gives, per building, the import, GoAlone's "
            "success and every failure by cause (wall collision, human collision, stuck, timeout), "
            "the episodes whose metric stuck is set and those in which the robot never moved 1 m. "
            "--pictures draws every failure to OUT/NAME-fail-K.png. Floor plans without a licence "
            "stay outside the repository: pass their folder. Exit status 1 when an import was "
            "refused or a building's success is below 90%, 2 for bad arguments."
        ),
    )
    drive.add_argument(
        "buildings", type=Path, nargs="?", default=None, metavar="DIR",
        help="folder of NAME.vectormap.txt [+ NAME.navigation.json] (default: the built-in buildings)",
    )  # fmt: skip
    drive.add_argument(
        "--out", type=out_dir, required=True, help="folder of the imported maps, test sets, pictures"
    )
    drive.add_argument("--episodes", type=positive_int, default=30, help="episodes per building (default 30)")
    drive.add_argument("--batch-size", type=positive_int, default=30, help="episodes stepped together")
    drive.add_argument("--only", default=None, metavar="NAME,...", help="comma-separated building names")
    drive.add_argument("--pictures", action="store_true", help="draw every failure to OUT/NAME-fail-K.png")
    drive.add_argument(
        "--spec-crowd",
        action="store_true",
        help="5 to 25 people on every building (drop the walkable area: no crowd-density cap)",
    )
    drive.set_defaults(func=run_drive)


def _add_import_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of `map import` (its source, graph, repairs and output)."""
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--walls", type=Path, help="AMRL vector map text file")
    source.add_argument("--pedsim", type=Path, help="pedsim scene XML file")
    source.add_argument(
        "--png", type=Path,
        help="floor-plan image: dark pixels are walls (needs --scale), or a ROS map_server map YAML",
    )  # fmt: skip
    parser.add_argument("--scale", type=float, default=None, help="metres per pixel of --png")
    parser.add_argument(
        "--origin", type=float, nargs=2, metavar=("X", "Y"), default=None,
        help="world position of the image's lower-left corner, m (default 0 0)",
    )  # fmt: skip
    parser.add_argument(
        "--threshold", type=float, default=None,
        help="pixels darker than this (0 black .. 1 white) are walls (default 0.5; from a map YAML: "
        "1 - occupied_thresh)",
    )  # fmt: skip
    parser.add_argument(
        "--min-wall-area", type=float, default=0.0, help="drop wall specks smaller than this, m^2"
    )
    parser.add_argument("--nav", type=Path, default=None, help="AMRL navigation graph JSON")
    parser.add_argument("--name", required=True, help="map name")
    parser.add_argument(
        "--region", type=float, nargs=4, metavar=("XMIN", "YMIN", "XMAX", "YMAX"), default=None
    )
    parser.add_argument(
        "--seed-point",
        type=float,
        nargs=2,
        metavar=("X", "Y"),
        default=None,
        help="a point inside the building: the graph covers what is reachable from it",
    )
    parser.add_argument(
        "--strict",
        action="store_true",
        help="repair nothing: refuse a source that breaks a rule or a route the robot cannot drive",
    )
    parser.add_argument(
        "--no-drive",
        action="store_true",
        help="skip the drive check (the robot alone over every feasible pose pair) and its repairs",
    )
    parser.add_argument("--source", default="", help="provenance text stored in the map")
    parser.add_argument("--licence", default="", help="licence text stored in the map")
    parser.add_argument("--out", type=out_file, default=None, help="output JSON (default NAME.json)")


def _add_picture_options(parser: argparse.ArgumentParser, suffix: str, *, no_picture: bool) -> None:
    """Add --picture PATH (and --no-picture), and the old --out as a hidden alias of --picture."""
    parser.add_argument(
        "--picture",
        type=Path,
        default=None,
        metavar="PATH",
        help=f"PNG to write (default: beside a map file, FILE-{suffix}.png; none for a shipped map name)",
    )
    # The old name, kept so existing command lines still work; hidden so new ones use --picture.
    parser.add_argument("--out", type=out_path, default=None, help=argparse.SUPPRESS)
    if no_picture:
        parser.add_argument(
            "--no-picture", action="store_true", help="skip the picture (no matplotlib needed)"
        )
    parser.set_defaults(picture_suffix=suffix)


def _map_file(name_or_path: str) -> Path | None:
    """MAP's file when it is a path (socialzoo.maps.map_file.load_map's rule), None for a shipped name."""
    from socialzoo.maps.map_file import names_a_file

    return Path(name_or_path) if names_a_file(name_or_path) else None


def _picture_path(args: argparse.Namespace) -> tuple[Path | None, str]:
    """Where the picture goes, or None and why none is written.

    --picture PATH when given; else beside a map file (FILE-SUFFIX.png in the map's folder); else
    nowhere: a shipped map's folder is inside the installed package (maybe read-only) and the
    current directory is not a place the user chose.

    Raises:
        ValueError: --picture and its old name --out both given, or either with --no-picture.
    """
    picture = args.picture
    if args.out is not None:
        if picture is not None:
            raise ValueError("give --picture only (--out is its old name)")
        print("socialzoo map: --out is deprecated: use --picture", file=sys.stderr)
        picture = args.out
    if getattr(args, "no_picture", False):
        if picture is not None:
            raise ValueError("--picture (or --out) and --no-picture contradict each other")
        return None, "none (--no-picture)"
    if picture is not None:
        return picture, ""
    suffix = args.picture_suffix
    file = _map_file(str(args.map))
    if file is None:
        return None, f"none ({args.map} is a shipped map: ask for one with --picture {args.map}-{suffix}.png)"
    return file.with_name(f"{file.stem}-{suffix}.png"), ""


def _save_picture(save: Any, out: Path | None, why_none: str) -> int:
    """Call save(out), creating out's folder, and say where the picture went (nowhere: `why_none`);
    returns 0, or 2 when it cannot be written (the error names out)."""
    if out is not None:
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            save(out)
        except OSError as err:
            return fail(
                "map",
                f"cannot write the picture {out} ({err.strerror or err}): choose another with --picture PATH",
            )
    print(f"  picture: {out or why_none}")
    return 0


def run_list(args: argparse.Namespace) -> int:
    """Run `socialzoo map list`; returns the exit status."""
    from socialzoo.maps.map_file import list_maps, load_map

    for name in list_maps():
        m = load_map(name)
        print(
            f"{name:<14} {m.num_walls:5d} walls {m.num_nodes:4d} nodes {len(m.edges):4d} edges "
            f"{len(m.legal_poses):3d} poses  {m.source[:60]}"
        )
    return 0


def run_show(args: argparse.Namespace) -> int:
    """Run `socialzoo map show`; returns the exit status."""
    from socialzoo.maps.map_file import MapError, load_map
    from socialzoo.render.map_plot import save_map_png

    try:
        out, why_none = _picture_path(args)
        m = load_map(args.map)
    except (MapError, FileNotFoundError, KeyError, ValueError) as err:
        return fail("map", err)
    print(f"{args.map}: {m.name}, {m.num_walls} walls, {m.num_nodes} nodes, {len(m.legal_poses)} legal poses")
    return _save_picture(lambda path: save_map_png(m, path, show_graph=not args.no_graph), out, why_none)


def run_validate(args: argparse.Namespace) -> int:
    """Run `socialzoo map validate`; returns the exit status."""
    from socialzoo.maps.map_file import MapError, load_map, validate_map

    try:
        validate_map(load_map(args.map))
    except (MapError, FileNotFoundError, KeyError) as err:
        return fail("map", err)
    print(f"{args.map}: valid")
    return 0


def run_check(args: argparse.Namespace) -> int:
    """Run `socialzoo map check`; returns the exit status."""
    from socialzoo.maps.map_file import MapError, load_map, read_map
    from socialzoo.render.map_plot import save_map_check_png
    from socialzoo.scenarios.feasibility import MAX_ROUTE_LENGTH
    from socialzoo.scenarios.map_check import check_map

    try:
        out, why_none = _picture_path(args)
        file = _map_file(str(args.map))
        # A file is read unvalidated: the check lists its problems instead.
        m = read_map(file, validate=False) if file is not None else load_map(args.map)
        max_route = MAX_ROUTE_LENGTH if args.max_route is None else args.max_route
        report = check_map(m, max_route)
    except (MapError, FileNotFoundError, KeyError, ValueError) as err:
        return fail("map", err)
    print(f"{args.map}: {m.name}, {m.num_walls} walls, {m.num_nodes} nodes, {len(m.edges)} edges, "
          f"{len(m.legal_poses)} legal poses")  # fmt: skip
    for line in report.lines():
        print(f"  {line}")
    drive = None
    if args.drive is not None and report.valid:
        from socialzoo.bench.drive_check import drive_map, pose_pairs

        pairs = pose_pairs(m, args.drive or None, args.seed, max_route)
        drive = drive_map(m, pairs, progress=_drive_progress(len(pairs)))
        for line in drive.lines(limit=None):
            print(f"  {line}")
    elif args.drive is not None:
        print("  drive: skipped (the map is invalid)")
    if (
        _save_picture(lambda path: save_map_check_png(m, report, path, drive), out, why_none)
        or not report.valid
    ):
        return 2
    return 1 if drive is not None and not drive.complete else 0


def _drive_progress(total: int) -> Any:
    """A progress callback for drive_map: a line on stderr every 10% of the routes."""
    marks = {max(1, round(total * k / 10)) for k in range(1, 11)}

    def report(done: int, _: int) -> None:
        if done in marks:
            marks.discard(done)
            print(f"socialzoo map: drove {done} of {total} routes", file=sys.stderr, flush=True)

    return report


def _read_source(
    args: argparse.Namespace,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, dict, int]:
    """Walls, nodes and edges of the import's source, its provenance inputs, and how many of its
    walls were merged into others (repeated pieces, `merge_duplicate_walls`)."""
    from socialzoo.maps.importers import (
        drop_zero_length,
        merge_duplicate_walls,
        read_amrl_nav_graph,
        read_pedsim_scene,
        read_vector_map,
    )

    nodes = edges = None
    inputs: dict[str, Any] = {}
    if args.png is None:
        # The image's options would be ignored: a plan in feet given --scale 0.3048 imported in feet.
        unset = {"scale": None, "origin": None, "threshold": None, "min_wall_area": 0.0}
        given = [f"--{k.replace('_', '-')}" for k, v in unset.items() if getattr(args, k) != v]
        if given:
            raise ValueError(
                f"only --png takes {', '.join(given)}: --walls and --pedsim coordinates are read as "
                "metres (a plan in feet: multiply every coordinate by 0.3048 first)"
            )
    if args.walls is not None:
        walls = read_vector_map(args.walls)
        inputs["walls"] = args.walls.name
    elif args.pedsim is not None:
        scene = read_pedsim_scene(args.pedsim)
        walls = scene.walls
        if len(scene.nodes):
            nodes = scene.nodes
        inputs["pedsim"] = args.pedsim.name
    else:
        walls, png_inputs = _png_walls(args)
        inputs.update(png_inputs)
    if args.nav is not None:
        nodes, edges = read_amrl_nav_graph(args.nav)
        inputs["nav"] = args.nav.name
    walls = drop_zero_length(np.asarray(walls, dtype=np.float64), str(args.walls or args.pedsim or args.png))
    walls, merged = merge_duplicate_walls(walls)
    return walls, nodes, edges, inputs, merged


def _drive_and_repair(m: Any, *, strict: bool) -> tuple[Any, list[tuple[str, str]]]:
    """The import's drive check: the map repaired by driving, and its repairs as (kind, message).

    Raises:
        MapError: with strict, a route failed (the message lists the failed routes).
    """
    from socialzoo.bench.drive_check import drive_map, pose_pairs
    from socialzoo.bench.map_repair import repair_by_driving
    from socialzoo.maps.map_file import MapError

    pairs = pose_pairs(m)
    print(f"driving: the robot alone over {len(pairs)} pose pairs", flush=True)
    drive = drive_map(m, pairs, progress=_drive_progress(len(pairs)))
    print(drive.lines(limit=0)[0])
    if strict:
        if not drive.complete:
            raise MapError(f"{m.name}: --strict: " + "\n".join(drive.lines(limit=None)[1:]))
        done = len(drive.routes)
        record = {"routes_driven": done, "routes_completed": done, "failures": {}, "repairs": 0}
        record["pairs_completed_after_repairs"] = done
        return dataclasses.replace(m, provenance={**(m.provenance or {}), "drive": record}), []
    m, repairs, _ = repair_by_driving(m, report=drive)
    return m, [(r.kind, r.message) for r in repairs]


def _png_walls(args: argparse.Namespace) -> tuple[np.ndarray, dict[str, Any]]:
    """Walls of --png (an image, or a ROS map_server YAML naming one) and their provenance inputs."""
    from socialzoo.maps.importers import is_map_server_yaml, read_floor_plan

    if is_map_server_yaml(args.png):
        if args.scale is not None or args.origin is not None:
            raise ValueError(
                f"--png {args.png}: a map YAML gives the scale and origin: drop --scale and --origin"
            )
    elif args.scale is None:
        raise ValueError("--png needs --scale (metres per pixel), or give a ROS map_server map YAML")
    origin = (0.0, 0.0) if args.origin is None else tuple(args.origin)
    return read_floor_plan(
        args.png, scale=args.scale, origin=origin, threshold=args.threshold, min_area=args.min_wall_area
    )


def run_import(args: argparse.Namespace) -> int:
    """Run `socialzoo map import`; returns the exit status."""
    from socialzoo import __version__
    from socialzoo.maps.map_completion import complete_map
    from socialzoo.maps.map_file import MapError, check_map_name
    from socialzoo.maps.repair import repair_map
    from socialzoo.maps.roadmap import describe_closures

    try:
        check_map_name(args.name, "--name")  # before any reading: the file would not load
        walls, nodes, edges, inputs, merged = _read_source(args)
        common: dict[str, Any] = {
            "nodes": nodes,
            "edges": edges,
            "region": tuple(args.region) if args.region else None,
            "seed_point": tuple(args.seed_point) if args.seed_point else None,
            "source": args.source or f"imported from {', '.join(str(v) for v in inputs.values())}",
            "licence": args.licence,
        }
        provenance = {
            "importer": "socialzoo map import",
            "socialzoo_version": __version__,
            "inputs": inputs,
            "options": {
                "region": args.region,
                "seed_point": args.seed_point,
                "strict": bool(args.strict),
            },
            **({"walls_merged": merged} if merged else {}),
        }
        if args.strict:
            m = complete_map(args.name, walls, **common)
            # Openings of the outline closed by virtual walls are no repair of the source, but
            # how its open outline was read: kept and said.
            closed = {k: v for k, v in (m.provenance or {}).items() if k == "outline_closed"}
            m = dataclasses.replace(m, provenance={**provenance, **closed, "repairs": []})
            steps: list[tuple[str, str]] = []
            if closed:
                print(f"closed: {describe_closures(np.array(closed['outline_closed']))}")
        else:
            m, report = repair_map(args.name, walls, provenance=provenance, **common)
            steps = [(r.kind, r.message) for r in report.repairs]
        if not args.no_drive:
            m, drive_steps = _drive_and_repair(m, strict=args.strict)
            steps += drive_steps
    except (MapError, FileNotFoundError, ValueError) as err:
        return fail("map", err)
    out = m.save(args.out or Path(f"{args.name}.json"))
    num_repairs = 0
    for kind, message in steps:
        generated = kind in GENERATED
        num_repairs += not generated
        print(f"{'generated' if generated else 'repaired'}: {message}")
    walls_merged = f" ({merged} repeated pieces merged)" if merged else ""
    print(
        f"{out}: {m.num_walls} walls{walls_merged}, {m.num_nodes} nodes, {len(m.edges)} edges, "
        f"{len(m.legal_poses)} poses ({num_repairs} repairs)"
    )
    return 0


def run_drive(args: argparse.Namespace) -> int:
    """Run `socialzoo map drive`; returns the exit status."""
    import time

    from socialzoo.bench.drive_check import building_row, building_table_head, drive_building

    args.out.mkdir(parents=True, exist_ok=True)
    try:
        files = _building_files(args)
    except (FileNotFoundError, ValueError) as err:
        return fail("map", err)
    for line in building_table_head():
        print(line)
    worst = 100.0
    for name, walls_file in files.items():
        nav = walls_file.with_name(f"{name}{NAVIGATION}")
        nav_file = nav if nav.is_file() else None
        start = time.perf_counter()
        m, status = _import_building(walls_file, nav_file, name, args.out, spec_crowd=args.spec_crowd)
        drive = None
        if m is not None:
            drive = drive_building(
                args.out / f"{name}.json", args.out, args.episodes, batch_size=args.batch_size,
                pictures=args.pictures,
            )  # fmt: skip
        worst = min(worst, 100.0 * drive.success_rate if drive else 0.0)
        print(
            building_row(name, nav_file is not None, status, m, drive, time.perf_counter() - start),
            flush=True,
        )
    return 0 if worst >= 90.0 else 1


def _building_files(args: argparse.Namespace) -> dict[str, Path]:
    """`map drive`'s buildings: name -> NAME.vectormap.txt of DIR (or of the built-in buildings,
    written to OUT/buildings/), those of --only when given.

    Raises:
        FileNotFoundError: DIR is not a folder.
        ValueError: DIR holds no building, or --only names one it does not hold.
    """
    folder = args.buildings
    if folder is None:
        from socialzoo.bench.drive_check import builtin_buildings
        from socialzoo.maps.importers import write_vector_map

        folder = args.out / "buildings"
        folder.mkdir(exist_ok=True)
        for name, walls in builtin_buildings().items():
            write_vector_map(folder / f"{name}{VECTOR_MAP}", walls)
    elif not folder.is_dir():
        raise FileNotFoundError(f"{folder}: no such folder")
    files = {f.name[: -len(VECTOR_MAP)]: f for f in sorted(folder.glob(f"*{VECTOR_MAP}"))}
    if not files:
        raise ValueError(f"{folder}: no NAME{VECTOR_MAP} file")
    if args.only is None:
        return files
    wanted = args.only.split(",")
    unknown = [name for name in wanted if name not in files]
    if unknown:
        raise ValueError(
            f"--only: no building {', '.join(unknown)} in {folder} (buildings: {', '.join(files)})"
        )
    return {name: files[name] for name in files if name in wanted}


def _import_building(
    walls_file: Path, nav_file: Path | None, name: str, out: Path, *, spec_crowd: bool = False
) -> tuple[Any, str]:
    """(the map or None, "ok" or why the import refused it) of one building imported as `map
    import --walls FILE [--nav FILE] --name NAME --out OUT/NAME.json` does; what the import said
    goes to OUT/NAME.import.txt. With spec_crowd the map loses its walkable area."""
    import contextlib
    import io

    from socialzoo.maps.map_file import read_map

    words = ["--walls", str(walls_file), "--name", name, "--out", str(out / f"{name}.json")]
    if nav_file is not None:
        words += ["--nav", str(nav_file)]
    parser = argparse.ArgumentParser(prog="socialzoo map import")
    _add_import_arguments(parser)
    said = io.StringIO()
    with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
        status = run_import(parser.parse_args(words))
    text = said.getvalue()
    (out / f"{name}.import.txt").write_text(text)
    if status != 0:
        return None, text.strip().splitlines()[-1] if text.strip() else f"refused ({status})"
    m = read_map(out / f"{name}.json")
    if spec_crowd:
        m = dataclasses.replace(m, walkable_area=None)
        m.save(out / f"{name}.json")
    return m, "ok"
