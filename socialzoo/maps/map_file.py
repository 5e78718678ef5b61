"""Maps: walls, navigation graph and legal poses, stored as one JSON file per map (format "socialzoo-map/1",
described in docs/maps.md); loading, validation and the wall queries the checks use."""

from __future__ import annotations

import functools
import hashlib
import importlib.resources
import json
import logging
import math
import os
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.core import files
from socialzoo.core.files import read_text
from socialzoo.core.geometry import closest_point_on_segment, segments_intersect
from socialzoo.core.validation import is_finite_number
from socialzoo.core.walls import WallIndex

logger = logging.getLogger(__name__)

MAP_FORMAT = "socialzoo-map/1"
# Python package that holds the shipped maps (the repository's top-level maps/ folder).
MAPS_PACKAGE = "socialzoo._maps"

# A legal pose must keep the robot's whole footprint (0.5 m x 0.43 m, half-diagonal 0.33 m) off the
# walls at any heading, since episodes start there and a wall contact ends an episode at once.
POSE_CLEARANCE = 0.35
# Graph nodes are waypoints that people (radius 0.2 m) walk through and the robot steers towards
# with its own clearance checks, so they need less room than a spawn pose.
NODE_CLEARANCE = 0.25
# Problems listed in one MapError message at most; the rest are counted.
MAX_REPORTED = 12


class MapError(ValueError):
    """A map file or map data is malformed; the message names the file and the entry."""


def _no_doors() -> np.ndarray:
    """The doors of a map without any: a read-only (0, 4) array."""
    doors = np.zeros((0, 4), dtype=np.float64)
    doors.setflags(write=False)
    return doors


@dataclass(frozen=True, eq=False)
class Map:
    """A building map.

    Attributes:
        name: short identifier, e.g. "gdc1".
        walls: (W, 4) wall segments x1, y1, x2, y2, m.
        nodes: (N, 2) navigation-graph node positions, m.
        edges: (E, 2) int node index pairs, undirected.
        legal_poses: (P, 3) start/goal poses x, y (m), theta (rad).
        doors: (D, 4) door segments x1, y1, x2, y2 across doorway openings, m (world frame); (0, 4)
            for a map without doors. Not walls: open unless a scenario closes them.
        source: provenance of the data.
        licence: licence and attribution of the data.
        region: optional (xmin, ymin, xmax, ymax) area of interest, m.
        walkable_area: optional floor area the robot can drive in, m^2 (cells at least the
            passable clearance from walls, measured by the importer); scenario generation caps
            the head count at the benchmark's crowd density (socialzoo.scenarios.feasibility). None
            for the shipped maps: the SPEC's head count.
        provenance: optional JSON object saying how the map was made: the importer, its options
            and every repair it made to the source data (socialzoo.maps.repair); None for maps
            written by hand.
        path: file the map was loaded from, if any (used in error messages).
    """

    name: str
    walls: np.ndarray
    nodes: np.ndarray
    edges: np.ndarray
    legal_poses: np.ndarray
    doors: np.ndarray = field(default_factory=_no_doors)
    source: str = ""
    licence: str = ""
    region: tuple[float, float, float, float] | None = None
    walkable_area: float | None = None
    provenance: dict[str, Any] | None = field(default=None, compare=False)
    path: str | None = field(default=None, compare=False)

    @cached_property
    def wall_index(self) -> WallIndex:
        """The spatial index over this map's walls (built once per map object)."""
        return WallIndex(self.walls)

    @property
    def num_walls(self) -> int:
        """W, the number of wall segments."""
        return len(self.walls)

    @property
    def num_nodes(self) -> int:
        """N, the number of navigation graph nodes."""
        return len(self.nodes)

    @property
    def num_doors(self) -> int:
        """D, the number of doors."""
        return len(self.doors)

    @property
    def where(self) -> str:
        """How errors refer to this map: its file if it has one, else its name."""
        return self.path or f"map {self.name!r}"

    def to_json(self) -> dict[str, Any]:
        """The map as a JSON-ready dict in the socialzoo-map/1 format.

        "doors" is written only when there are some, so files without doors round-trip byte for byte.
        """
        data: dict[str, Any] = {
            "format": MAP_FORMAT,
            "name": self.name,
            "source": self.source,
            "licence": self.licence,
        }
        if self.region is not None:
            data["region"] = [float(v) for v in self.region]
        data["walls"] = [[round(float(v), 6) for v in w] for w in self.walls]
        if len(self.doors):
            data["doors"] = [[round(float(v), 6) for v in d] for d in self.doors]
        data["graph"] = {
            "nodes": [[round(float(v), 6) for v in n] for n in self.nodes],
            "edges": [[int(i), int(j)] for i, j in self.edges],
        }
        data["legal_poses"] = [[round(float(v), 6) for v in p] for p in self.legal_poses]
        if self.walkable_area is not None:
            data["walkable_area"] = round(float(self.walkable_area), 3)
        if self.provenance is not None:
            data["provenance"] = self.provenance
        return data

    def to_text(self) -> str:
        """The map file's text (`save` writes it): to_json as compact JSON, one line."""
        return json.dumps(self.to_json(), separators=(",", ":")) + "\n"

    def save(self, path: str | Path) -> Path:
        """Write the map as JSON, whole or not at all (core.files.write_text_atomic); returns the path."""
        return files.write_text_atomic(path, self.to_text())


# ----------------------------------------------------------------------------- reading JSON


def _fail(where: str, what: str) -> MapError:
    return MapError(f"{where}: {what}")


def _is_number(value: Any) -> bool:
    # bool is an int subclass in Python but never a coordinate in a map file.
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number_rows(value: Any, width: int, where: str, field_name: str, names: str) -> np.ndarray:
    """A JSON list of `width`-number rows as a float array (n, width), checked entry by entry."""
    if not isinstance(value, list):
        raise _fail(where, f"{field_name} must be a list of {names}, got {type(value).__name__}")
    for k, row in enumerate(value):
        if not isinstance(row, list) or len(row) != width or not all(_is_number(v) for v in row):
            raise _fail(where, f"{field_name}[{k}]: expected {width} numbers {names}, got {row!r}")
        for v in row:
            if not is_finite_number(v):
                what = "NaN" if v != v else v if isinstance(v, float) else "an int beyond a float's range"
                raise _fail(where, f"{field_name}[{k}]: coordinate is {what}")
    return np.array(value, dtype=np.float64).reshape(len(value), width)


def _edge_rows(value: Any, where: str) -> np.ndarray:
    if not isinstance(value, list):
        raise _fail(where, f"graph.edges must be a list of [i, j] pairs, got {type(value).__name__}")
    for k, row in enumerate(value):
        ok = isinstance(row, list) and len(row) == 2
        if not ok or not all(isinstance(v, int) and not isinstance(v, bool) for v in row):
            raise _fail(where, f"graph.edges[{k}]: expected two integer node indices [i, j], got {row!r}")
    return np.array(value, dtype=np.int64).reshape(len(value), 2)


def _text_field(data: dict[str, Any], key: str, where: str, required: bool) -> str:
    if key not in data:
        if required:
            raise _fail(where, f"missing field {key!r}")
        return ""
    if not isinstance(data[key], str):
        raise _fail(where, f"{key} must be a string, got {data[key]!r}")
    return str(data[key])


def check_map_name(name: str, where: str) -> None:
    """Refuse a map name that is not one file name: it names files (a benchmark's
    DIR/test_sets/<name>-test.json, tables, figures), which must stay inside their folder.

    Raises:
        MapError: a name with '/', a backslash or control characters, or '.' or '..' (naming
            `where`).
    """
    if "/" in name or "\\" in name or name in (".", "..") or not name.isprintable():
        raise _fail(
            where, f"name {name!r} must be usable as a file name (no '/', '\\' or control characters)"
        )


def parse_json(text: str, where: str) -> Any:
    """JSON text parsed; MapError naming `where` (and the line and column) for text that is not JSON
    (socialzoo.core.files.parse_json's, for a map file)."""
    return files.parse_json(text, where, "map file", MapError)


_KNOWN_FIELDS = {
    "format",
    "name",
    "source",
    "licence",
    "region",
    "walls",
    "doors",
    "graph",
    "legal_poses",
    "walkable_area",
    "provenance",
}


def map_from_json(data: dict[str, Any] | str, where: str = "<map>") -> Map:
    """Build a Map from socialzoo-map/1 JSON data, checking its structure (not its geometry).

    Args:
        data: the parsed JSON object, or the JSON text itself.
        where: how error messages name the source, usually the file path.

    Returns:
        The map, with read-only arrays and `path` set to `where`. Zero-length walls are kept: they
        act as points and do no harm (the importers drop them from raw data).

    Raises:
        MapError: text that is not JSON, a wrong or missing format tag, a missing field, or an entry of
            the wrong type or shape or with a NaN or infinite coordinate, or a door of zero length.
            Run `validate_map` for the geometric checks.
    """
    if isinstance(data, str):
        data = parse_json(data, where)
    if not isinstance(data, dict):
        raise _fail(where, f"expected a JSON object at the top level, got {type(data).__name__}")
    if "format" not in data:
        raise _fail(where, f"missing field 'format' (expected {MAP_FORMAT!r})")
    if data["format"] != MAP_FORMAT:
        raise _fail(where, f"format is {data['format']!r}, expected {MAP_FORMAT!r}")
    for key in ("name", "walls", "graph", "legal_poses"):
        if key not in data:
            raise _fail(where, f"missing field {key!r}")
    unknown = sorted(set(data) - _KNOWN_FIELDS)
    if unknown:
        logger.warning("%s: ignoring unknown fields %s", where, unknown)
    name = _text_field(data, "name", where, required=True)
    if not name:
        raise _fail(where, "name is empty")
    check_map_name(name, where)
    region: tuple[float, float, float, float] | None = None
    if data.get("region") is not None:
        box = _number_rows([data["region"]], 4, where, "region", "[xmin, ymin, xmax, ymax]")[0]
        region = (float(box[0]), float(box[1]), float(box[2]), float(box[3]))
    graph = data["graph"]
    if not isinstance(graph, dict):
        raise _fail(where, f"graph must be an object with 'nodes' and 'edges', got {type(graph).__name__}")
    for key in ("nodes", "edges"):
        if key not in graph:
            raise _fail(where, f"missing field 'graph.{key}'")
    walls = _number_rows(data["walls"], 4, where, "walls", "[x1, y1, x2, y2]")
    nodes = _number_rows(graph["nodes"], 2, where, "graph.nodes", "[x, y]")
    edges = _edge_rows(graph["edges"], where)
    poses = _number_rows(data["legal_poses"], 3, where, "legal_poses", "[x, y, theta]")
    doors = _number_rows(data.get("doors", []), 4, where, "doors", "[x1, y1, x2, y2]")
    point_doors = np.flatnonzero((doors[:, :2] == doors[:, 2:]).all(axis=1))
    if len(point_doors):
        k = int(point_doors[0])
        raise _fail(
            where, f"doors[{k}]: zero length, both ends at {doors[k, :2].tolist()} (a door spans an opening)"
        )
    walkable = data.get("walkable_area")
    if walkable is not None and not (is_finite_number(walkable) and walkable > 0):
        raise _fail(where, f"walkable_area must be a positive number of m^2, got {walkable!r}")
    provenance = data.get("provenance")
    if provenance is not None and not isinstance(provenance, dict):
        raise _fail(where, f"provenance must be an object, got {type(provenance).__name__}")
    for arr in (walls, nodes, edges, poses, doors):
        arr.setflags(write=False)
    return Map(
        name=name,
        walls=walls,
        nodes=nodes,
        edges=edges,
        legal_poses=poses,
        doors=doors,
        source=_text_field(data, "source", where, required=False),
        licence=_text_field(data, "licence", where, required=False),
        region=region,
        walkable_area=None if walkable is None else float(walkable),
        provenance=provenance,
        path=where,
    )


def read_map(path: str | os.PathLike[str], validate: bool = True) -> Map:
    """Read a map JSON file (and, by default, validate it: then a file read again with the same text,
    under the same path, gives the same Map object, as load_map does).

    Raises:
        FileNotFoundError: no such file.
        MapError: the file is not a valid map (random bytes, a truncated file or a file of another
            kind included); the message names the file and the entry.
    """
    where = os.fspath(path)
    text = read_text(path, "map file", MapError)
    return _validated_file(text, where) if validate else map_from_json(text, where)


@functools.lru_cache(maxsize=4)
def _validated_file(text: str, where: str) -> Map:
    # A file read again with the same text is the same Map object, as a shipped map is: its wall
    # index, distance field and graph tables (keyed on the object) are built once, not by every env,
    # test set and check that loads it (seconds and 100 MiB each for a building of 5,000 walls).
    m = map_from_json(text, where)
    validate_map(m)
    return m


def map_sha256(m: Map) -> str:
    """sha256 of a map's contents (its JSON form with sorted keys)."""
    return hashlib.sha256(json.dumps(m.to_json(), sort_keys=True).encode()).hexdigest()


def list_maps() -> list[str]:
    """Names of the shipped maps, sorted, e.g. ["doorway", "gdc1", ...]."""
    folder = importlib.resources.files(MAPS_PACKAGE)
    return sorted(
        entry.name.removesuffix(".json") for entry in folder.iterdir() if entry.name.endswith(".json")
    )


@functools.cache
def _load_shipped(name: str) -> Map:
    # One Map object per name and process, so its WallIndex (and graph caches keyed on the map
    # object) are built once; its arrays are read-only, so sharing it is safe.
    resource = importlib.resources.files(MAPS_PACKAGE) / f"{name}.json"
    where = str(resource) if isinstance(resource, Path) else f"maps/{name}.json"
    m = map_from_json(resource.read_text(encoding="utf-8"), where)
    validate_map(m)
    return m


def names_a_file(name_or_path: str) -> bool:
    """Whether a map argument is a file path (it ends in .json or has a folder separator) rather
    than a shipped map's name: load_map's rule, which the CLI follows too."""
    return name_or_path.endswith(".json") or "/" in name_or_path or os.sep in name_or_path


def load_map(name_or_path: str | os.PathLike[str]) -> Map:
    """A shipped map by name (e.g. "gdc1") or a map file by path (anything ending in .json).

    Shipped maps are loaded, validated and cached once per process: repeated calls return the
    same Map object. Files are read on every call; a file whose text is unchanged returns the Map
    object of its latest reads (the last few files' are kept), so its tables are built once.

    Shipped maps live in the top-level maps/ folder, installed as the package socialzoo._maps.

    Raises:
        FileNotFoundError: a path that does not exist.
        MapError: an unknown map name, or an invalid map (the message names the file and entry).
    """
    text = os.fspath(name_or_path)
    if isinstance(name_or_path, os.PathLike) or names_a_file(text):
        return read_map(text)
    names = list_maps()
    if text not in names:
        raise MapError(f"unknown map {text!r}: shipped maps are {', '.join(names)} (or give a .json path)")
    return _load_shipped(text)


# ----------------------------------------------------------------------------- geometry checks


def nearest_walls(index: WallIndex, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance from points to their nearest wall, and that wall's index.

    Args:
        index: the walls.
        points: (N, 2) world points, m.

    Returns:
        (dist, wall): (N,) distances in m, exact up to the index's reach and inf beyond it; (N,)
        wall indices, -1 where no wall is within reach.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    t = index.fine
    query, wall = t.candidates(t.cells(points))
    _, dist = closest_point_on_segment(points[query], index.wall_a[wall], index.wall_b[wall])
    return _nearest_of(len(points), query, wall, dist, t.reach)


def _nearest_of(
    n: int, query: np.ndarray, wall: np.ndarray, dist: np.ndarray, limit: float
) -> tuple[np.ndarray, np.ndarray]:
    """(dist (n,), wall (n,)) of the nearest of the (query, wall, dist) pairs of each of n queries
    within `limit` (inf and -1 where none is)."""
    best = np.full(n, np.inf)
    best_wall = np.full(n, -1, dtype=np.int64)
    if len(query):
        # Sort pairs by (query, dist, wall) and keep the first of each query: the nearest wall,
        # ties broken by the lower wall index so the answer does not depend on the grid.
        order = np.lexsort((wall, dist, query))
        first = order[np.r_[True, query[order][1:] != query[order][:-1]]]
        near = dist[first] <= limit
        best[query[first][near]] = dist[first][near]
        best_wall[query[first][near]] = wall[first][near]
    return best, best_wall


def segment_clearance(index: WallIndex, p0: np.ndarray, p1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Smallest distance between segments [p0, p1] and any wall, and the wall that is that close.

    Args:
        index: the walls.
        p0: (N, 2) segment start points, m.
        p1: (N, 2) segment end points, m.

    Returns:
        (dist, wall): (N,) distances, exact below reach / 2 of the index (0.5 m by default), 0
        where the segment touches a wall and inf where no wall is within reach / 2; (N,) wall
        indices, -1 where none is that close.
    """
    a0 = np.asarray(p0, dtype=np.float64).reshape(-1, 2)
    a1 = np.asarray(p1, dtype=np.float64).reshape(-1, 2)
    if len(a0) == 0:
        return np.full(0, np.inf), np.full(0, -1, dtype=np.int64)
    t = index.fine
    limit = 0.5 * t.reach
    # Samples at most reach/2 apart: every point of a segment is within reach/4 of a sample, so a
    # wall within reach/2 of the segment is within 3/4 reach of a sample and listed in its cell.
    length = np.sqrt(((a1 - a0) ** 2).sum(-1))
    num_samples = max(2, math.ceil(float(length.max(initial=0.0)) / limit) + 1)
    frac = np.linspace(0.0, 1.0, num_samples)
    samples = a0[:, None, :] + frac[:, None] * (a1 - a0)[:, None, :]
    query, wall = t.candidates(t.cells(samples).reshape(-1))
    seg = query // num_samples
    # Several samples of one segment list the same wall: test each (segment, wall) pair once.
    pair = np.unique(seg * index.num_walls + wall)
    seg, wall = pair // index.num_walls, pair % index.num_walls
    wa, wb = index.wall_a[wall], index.wall_b[wall]
    sa, sb = a0[seg], a1[seg]
    dist = np.minimum.reduce(
        [
            closest_point_on_segment(sa, wa, wb)[1],
            closest_point_on_segment(sb, wa, wb)[1],
            closest_point_on_segment(wa, sa, sb)[1],
            closest_point_on_segment(wb, sa, sb)[1],
        ]
    )
    dist = np.where(segments_intersect(sa, sb, wa, wb), 0.0, dist)
    return _nearest_of(len(a0), seg, wall, dist, limit)


def _first_crossed_wall(index: WallIndex, p0: np.ndarray, p1: np.ndarray) -> int:
    """Index of the first wall (lowest index) that segment [p0, p1] touches, or -1."""
    hit = np.flatnonzero(segments_intersect(p0, p1, index.wall_a, index.wall_b))
    return int(hit[0]) if len(hit) else -1


def reaches_graph(index: WallIndex, points: np.ndarray, nodes: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Whether each point sees the graph: a wall-free straight line to some node or edge.

    For an edge the line goes to the edge's closest point, as a planner joins a start or goal to the
    graph; nearer targets are tried first, so the usual case tests a handful of lines.

    Args:
        index: the walls.
        points: (P, 2) world points, m.
        nodes: (N, 2) graph nodes, m.
        edges: (E, 2) node index pairs.

    Returns:
        bool (P,).
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    out = np.zeros(len(points), dtype=bool)
    if len(nodes) == 0:
        return out
    for k, p in enumerate(points):
        targets = [nodes]
        if len(edges):
            targets.append(closest_point_on_segment(p, nodes[edges[:, 0]], nodes[edges[:, 1]])[0])
        target = np.concatenate(targets)
        order = np.argsort(((target - p) ** 2).sum(-1), kind="stable")
        for chunk in (order[:16], order[16:]):
            if len(chunk) == 0:
                continue
            blocked = index.crosses(np.broadcast_to(p, (len(chunk), 2)), target[chunk])
            if not blocked.all():
                out[k] = True
                break
    return out


def graph_components(num_nodes: int, edges: np.ndarray) -> np.ndarray:
    """Connected-component label of each node: the smallest node index in its component.

    Args:
        num_nodes: N.
        edges: (E, 2) valid node index pairs.

    Returns:
        int (N,).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    if num_nodes == 0:
        return np.zeros(0, dtype=np.int64)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(num_nodes, num_nodes))
    label = connected_components(graph, directed=False)[1]
    # Each component's first node in index order is its smallest: name the component by it.
    return np.unique(label, return_index=True)[1][label].astype(np.int64)


def _index_list(indices: np.ndarray, limit: int = 20) -> str:
    shown = ", ".join(str(int(i)) for i in indices[:limit])
    return f"[{shown}{', ...' if len(indices) > limit else ''}] ({len(indices)} in all)"


def _array_problems(m: Map) -> list[str]:
    """Shape, dtype and finiteness problems of a map's arrays (checked before any geometry)."""
    problems: list[str] = []
    shapes = {
        "walls": (m.walls, 4),
        "graph.nodes": (m.nodes, 2),
        "legal_poses": (m.legal_poses, 3),
        "doors": (m.doors, 4),
    }
    for name, (arr, width) in shapes.items():
        a = np.asarray(arr)
        if name == "doors" and a.size == 0 and np.issubdtype(a.dtype, np.number):
            continue
        if a.ndim != 2 or a.shape[1] != width or not np.issubdtype(a.dtype, np.number):
            problems.append(f"{name} must be a numeric array of shape (n, {width}), got shape {a.shape}")
            continue
        bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
        for k in bad[:MAX_REPORTED]:
            problems.append(f"{name}[{k}]: coordinate is {'NaN' if np.isnan(a[k]).any() else 'infinite'}")
        if name == "doors" and not len(bad):
            for k in np.flatnonzero((a[:, :2] == a[:, 2:]).all(axis=1))[:MAX_REPORTED]:
                problems.append(f"doors[{k}]: zero length, both ends at {a[k, :2].tolist()}")
    e = np.asarray(m.edges)
    if e.ndim != 2 or e.shape[1] != 2 or not np.issubdtype(e.dtype, np.integer):
        if not (e.size == 0 and np.issubdtype(e.dtype, np.number)):
            problems.append(f"graph.edges must be an integer array of shape (n, 2), got {e.dtype} {e.shape}")
    if m.region is not None:
        box = np.asarray(m.region, dtype=np.float64)
        if box.shape != (4,) or not np.isfinite(box).all() or box[0] >= box[2] or box[1] >= box[3]:
            problems.append(f"region must be finite [xmin, ymin, xmax, ymax] with min < max, got {m.region}")
    return problems


def validate_map(
    m: Map, pose_clearance: float = POSE_CLEARANCE, node_clearance: float = NODE_CLEARANCE
) -> None:
    """Check a map's geometry; raise MapError naming the file and every offending entry.

    Rules:
        - walls (W, 4), nodes (N, 2), legal poses (P, 3) and doors (D, 4) are finite numbers, the
          walls spread no wider than their wall grid allows (socialzoo.core.walls.MAX_TABLE_CELLS
          cells of 25 cm, a 1.25 km square: coordinates in metres); at least
          one node and two legal poses (a scenario needs a distinct start and goal); no door of zero
          length;
        - edges (E, 2) name existing nodes, never a node to itself;
        - every node is at least `node_clearance` (0.25 m) from every wall, every legal pose at least
          `pose_clearance` (0.35 m: the robot footprint fits at any heading); a point inside a
          closed wall loop thicker than that is caught by the graph-reach rule instead;
        - no edge touches a wall;
        - the graph is connected;
        - every legal pose sees the graph: a wall-free straight line joins it to a node or to the
          closest point of an edge;
        - with a region, every node and pose lies inside it.
        Zero-length walls are allowed (they act as points).

    Raises:
        MapError: one message, one line per problem (at most MAX_REPORTED listed).
    """
    where = m.where
    problems = _array_problems(m)
    if not problems:
        try:
            m.wall_index.table()  # built here, where a refusal can name the file
        except ValueError as err:  # walls spread too wide for the wall grid (core.walls.MAX_TABLE_CELLS)
            problems = [str(err)]
    if not problems:
        problems = _graph_problems(m)
    if not problems:
        problems = _geometry_problems(m, pose_clearance, node_clearance)
    if problems:
        lines = [f"{where}: {p}" for p in problems[:MAX_REPORTED]]
        if len(problems) > MAX_REPORTED:
            lines.append(f"{where}: ... and {len(problems) - MAX_REPORTED} more problems")
        raise MapError("\n".join(lines))


def _graph_problems(m: Map) -> list[str]:
    problems: list[str] = []
    n = len(m.nodes)
    edges = np.asarray(m.edges).reshape(-1, 2)
    if n == 0:
        problems.append("graph.nodes is empty: a map needs a navigation graph")
    if len(m.legal_poses) < 2:
        problems.append(f"legal_poses: needs at least 2 poses (a start and a goal), got {len(m.legal_poses)}")
    for k in np.flatnonzero(((edges < 0) | (edges >= n)).any(axis=1))[:MAX_REPORTED]:
        i, j = edges[k]
        problems.append(f"graph.edges[{k}] ({i}, {j}) names a node outside 0..{n - 1}")
    for k in np.flatnonzero(edges[:, 0] == edges[:, 1])[:MAX_REPORTED]:
        problems.append(f"graph.edges[{k}] joins node {edges[k, 0]} to itself")
    return problems


def _geometry_problems(m: Map, pose_clearance: float, node_clearance: float) -> list[str]:
    problems: list[str] = []
    index = m.wall_index
    nodes = np.asarray(m.nodes, dtype=np.float64)
    poses = np.asarray(m.legal_poses, dtype=np.float64)
    edges = np.asarray(m.edges, dtype=np.int64).reshape(-1, 2)
    if m.region is not None:
        x0, y0, x1, y1 = m.region
        for name, pts in (("graph.nodes", nodes), ("legal_poses", poses[:, :2])):
            outside = ~((pts[:, 0] >= x0) & (pts[:, 0] <= x1) & (pts[:, 1] >= y0) & (pts[:, 1] <= y1))
            for k in np.flatnonzero(outside):
                problems.append(
                    f"{name}[{k}] at ({pts[k, 0]:.2f}, {pts[k, 1]:.2f}) lies outside region {list(m.region)}"
                )
    for name, pts, need in (
        ("graph.nodes", nodes, node_clearance),
        ("legal_poses", poses[:, :2], pose_clearance),
    ):
        if index.num_walls == 0 or len(pts) == 0:
            continue
        dist, wall = nearest_walls(index, pts)
        for k in np.flatnonzero(dist < need):
            where_pt = f"{name}[{k}] at ({pts[k, 0]:.2f}, {pts[k, 1]:.2f})"
            if dist[k] <= 1e-9:
                problems.append(f"{where_pt} lies on wall {wall[k]}")
            else:
                problems.append(f"{where_pt} is {dist[k]:.2f} m from wall {wall[k]} (needs {need:.2f})")
    if len(edges) and index.num_walls:
        a, b = nodes[edges[:, 0]], nodes[edges[:, 1]]
        for k in np.flatnonzero(index.crosses(a, b)):
            w = _first_crossed_wall(index, a[k], b[k])
            pair = f"(node {edges[k, 0]} - node {edges[k, 1]})"
            problems.append(f"graph.edges[{k}] {pair} passes through wall {w}")
    if len(nodes):
        label = graph_components(len(nodes), edges)
        unreached = np.flatnonzero(label != label[0])
        if len(unreached):
            unreached_text = _index_list(unreached)
            problems.append(f"graph is disconnected: nodes {unreached_text} not reachable from node 0")
    if len(nodes) and len(poses):
        for k in np.flatnonzero(~reaches_graph(index, poses[:, :2], nodes, edges)):
            problems.append(
                f"legal_poses[{k}] at ({poses[k, 0]:.2f}, {poses[k, 1]:.2f}) cannot reach the graph "
                "(no wall-free straight line to any node or edge)"
            )
    return problems
