"""Importers for wall maps from other tools: AMRL vector maps (with their navigation graphs), pedsim scene XML
files and ROS map_server YAML files, read into plain arrays (walls (W, 4), nodes (N, 2), edges (E, 2))."""

from __future__ import annotations

import logging
import math
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.core.files import read_json, read_text, write_text_atomic
from socialzoo.core.validation import check_number
from socialzoo.maps.map_file import MapError, graph_components

logger = logging.getLogger(__name__)

# A vector-map line: numbers separated by commas and/or white space.
_SEPARATORS = re.compile(r"[,\s]+")
# Walls whose ends lie this close to another wall's line, and overlap it by more, repeat it: merged
# on import (merge_duplicate_walls), m. Plans are drawn to the millimetre or finer.
MERGE_TOLERANCE = 1e-3


def _read_text(path: str | os.PathLike[str]) -> str:
    return read_text(path, "building file", MapError)


def read_table(path: str | os.PathLike[str], width: int, names: str) -> np.ndarray:
    """Read a text table of `width` numbers per line.

    Numbers are separated by commas and/or white space; text after "#" and blank lines are skipped.

    Args:
        path: the text file.
        width: numbers per line.
        names: what the numbers are, for error messages, e.g. "x1, y1, x2, y2".

    Returns:
        float array (n, width), in file order.

    Raises:
        FileNotFoundError: no such file.
        MapError: a file that is not UTF-8 text, a line with the wrong count of numbers, a word that
            is not a number, or a NaN or infinite value; the message names the file and line.
    """
    where = os.fspath(path)
    rows: list[list[float]] = []
    for line_no, line in enumerate(_read_text(path).splitlines(), start=1):
        body = line.split("#", 1)[0].strip().strip(",")
        if not body:
            continue
        words = [w for w in _SEPARATORS.split(body) if w]
        if len(words) != width:
            raise MapError(f"{where}:{line_no}: expected {width} numbers ({names}), got {line.strip()!r}")
        try:
            values = [float(w) for w in words]
        except ValueError:
            raise MapError(f"{where}:{line_no}: not a number in {line.strip()!r}") from None
        if not all(math.isfinite(v) for v in values):
            raise MapError(f"{where}:{line_no}: NaN or infinite value in {line.strip()!r}")
        rows.append(values)
    return np.array(rows, dtype=np.float64).reshape(len(rows), width)


def drop_zero_length(walls: np.ndarray, where: str = "walls") -> np.ndarray:
    """Walls (W, 4) without the segments whose two end points coincide.

    The importers drop them on import: they block nothing and only cost time in every wall query.
    """
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    keep = (walls[:, 0] != walls[:, 2]) | (walls[:, 1] != walls[:, 3])
    if not keep.all():
        logger.info("%s: dropped %d zero-length wall segments", where, int((~keep).sum()))
    return walls[keep]


def merge_duplicate_walls(walls: np.ndarray, tolerance: float = MERGE_TOLERANCE) -> tuple[np.ndarray, int]:
    """Walls (W, 4) with repeated pieces merged: segments on one line (every end within `tolerance`,
    m, of the longer one's line) that overlap by more than `tolerance` become their union; so exact
    duplicates, reversed ones and pieces lying inside a longer wall go. Collinear segments that only
    touch end to end (overlapping by at most `tolerance`) are kept apart: they draw no point twice,
    and the plan's own segments stay as drawn; segments farther apart than `tolerance` (a wall's
    two faces) are kept.

    A merged wall keeps the place in the list of its first piece and the direction of its longest
    one, whose ends it keeps unless another piece reaches more than `tolerance` beyond them; walls
    that repeat nothing are returned unchanged, in order.

    Returns:
        (walls (W', 4), the number of walls merged away, W - W').
    """
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    n = len(walls)
    start, end = walls[:, :2], walls[:, 2:]
    lo, hi = np.minimum(start, end) - tolerance, np.maximum(start, end) + tolerance
    # Candidate pairs: boxes that overlap along x (a sweep over the sorted left edges), then along y.
    order = np.argsort(lo[:, 0], kind="stable")
    last = np.searchsorted(lo[order, 0], hi[order, 0], side="right")
    count = last - np.arange(n) - 1
    first = np.repeat(np.arange(n), count)
    second = first + 1 + np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    a, b = order[first], order[second]
    near = (lo[a, 1] <= hi[b, 1]) & (lo[b, 1] <= hi[a, 1])
    a, b = a[near], b[near]
    length = np.hypot(*(end - start).T)
    # a: the longer of the two; b's ends must lie on its line and overlap it.
    a, b = np.where(length[a] >= length[b], a, b), np.where(length[a] >= length[b], b, a)
    u = (end[a] - start[a]) / length[a, None]
    off0, off1 = start[b] - start[a], end[b] - start[a]
    on_line = (np.abs(u[:, 0] * off0[:, 1] - u[:, 1] * off0[:, 0]) <= tolerance) & (
        np.abs(u[:, 0] * off1[:, 1] - u[:, 1] * off1[:, 0]) <= tolerance
    )
    t0, t1 = (u * off0).sum(1), (u * off1).sum(1)
    overlap = np.minimum(length[a], np.maximum(t0, t1)) - np.maximum(0.0, np.minimum(t0, t1))
    a, b = a[on_line & (overlap > tolerance)], b[on_line & (overlap > tolerance)]
    if len(a) == 0:
        return walls, 0
    label = graph_components(n, np.stack((a, b), axis=1))
    out = walls.copy()
    keep = np.ones(n, dtype=bool)
    for group in np.split(np.argsort(label, kind="stable"), np.flatnonzero(np.diff(np.sort(label))) + 1):
        if len(group) < 2:
            continue
        ref = group[np.argmax(length[group])]
        u = (end[ref] - start[ref]) / length[ref]
        ends = walls[group].reshape(-1, 2)
        t = (ends - start[ref]) @ u
        new_start = ends[np.argmin(t)] if t.min() < -tolerance else start[ref]
        new_end = ends[np.argmax(t)] if t.max() > length[ref] + tolerance else end[ref]
        out[group[0]] = np.concatenate((new_start, new_end))
        keep[group[1:]] = False
    return out[keep], int(n - keep.sum())


def read_vector_map(path: str | os.PathLike[str]) -> np.ndarray:
    """Read an AMRL vector map: one wall segment "x1, y1, x2, y2" per line, metres.

    Commas and/or spaces separate the numbers, so the SocialGym reference files ("x1 y1 x2 y2" with
    "#" comments) read too. Zero-length segments are dropped.

    Returns:
        walls (W, 4).

    Raises:
        FileNotFoundError: no such file.
        MapError: a file that is not UTF-8 text, a malformed line (the message names the file and
            line), or a file without any segment (an empty file: a wall map has walls).
    """
    walls = read_table(path, 4, "x1, y1, x2, y2")
    if len(walls) == 0:
        raise MapError(f"{os.fspath(path)}: no wall segments; not a vector map (x1, y1, x2, y2 per line)")
    return drop_zero_length(walls, os.fspath(path))


def read_amrl_nav_graph(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """Read an AMRL navigation-graph JSON file.

    The format is {"nodes": [{"id": 3, "loc": {"x": 1.0, "y": 2.0}, ...}, ...],
    "edges": [{"s0_id": 3, "s1_id": 4, ...}, ...]}; other keys are ignored. Node ids need not be
    contiguous: nodes are renumbered 0..N-1 in file order. Repeated edges are kept once.

    Returns:
        (nodes, edges): (N, 2) positions, m, and (E, 2) node index pairs.

    Raises:
        FileNotFoundError: no such file.
        MapError: not UTF-8 text, not JSON (with its line and column), a missing key, a node id
            that is not a string or an integer, a repeated node id, an edge naming an unknown node
            or joining a node to itself; the message names the file.
    """
    where = os.fspath(path)
    data = read_json(path, "building file", MapError)
    if not isinstance(data, dict) or not isinstance(data.get("nodes"), list):
        raise MapError(f"{where}: expected an object with a 'nodes' list (and an 'edges' list)")
    raw_edges = data.get("edges", [])
    if not isinstance(raw_edges, list):
        raise MapError(f"{where}: 'edges' must be a list, got {type(raw_edges).__name__}")
    index_of: dict[Any, int] = {}
    nodes: list[tuple[float, float]] = []
    for k, node in enumerate(data["nodes"]):
        entry = f"{where}: nodes[{k}]"
        if not isinstance(node, dict) or "id" not in node or not isinstance(node.get("loc"), dict):
            raise MapError(f"{entry}: expected {{'id': .., 'loc': {{'x': .., 'y': ..}}}}, got {node!r}")
        if not isinstance(node["id"], (str, int)):
            raise MapError(f"{entry}: a node id is a string or an integer, got {node['id']!r}")
        if node["id"] in index_of:
            raise MapError(f"{entry}: node id {node['id']!r} repeats nodes[{index_of[node['id']]}]")
        loc = node["loc"]
        index_of[node["id"]] = len(nodes)
        x = check_number(f"{entry}: loc", "x", loc.get("x"), error=MapError)
        y = check_number(f"{entry}: loc", "y", loc.get("y"), error=MapError)
        nodes.append((float(x), float(y)))
    edges: set[tuple[int, int]] = set()
    for k, edge in enumerate(raw_edges):
        entry = f"{where}: edges[{k}]"
        if not isinstance(edge, dict) or "s0_id" not in edge or "s1_id" not in edge:
            raise MapError(f"{entry}: expected {{'s0_id': .., 's1_id': ..}}, got {edge!r}")
        ends = []
        for key in ("s0_id", "s1_id"):
            if not isinstance(edge[key], (str, int)) or edge[key] not in index_of:
                raise MapError(f"{entry}: {key} {edge[key]!r} is not a node id")
            ends.append(index_of[edge[key]])
        if ends[0] == ends[1]:
            raise MapError(f"{entry}: joins node {edge['s0_id']!r} to itself")
        edges.add((min(ends), max(ends)))
    node_arr = np.array(nodes, dtype=np.float64).reshape(len(nodes), 2)
    edge_arr = np.array(sorted(edges), dtype=np.int64).reshape(len(edges), 2)
    return node_arr, edge_arr


@dataclass(frozen=True)
class PedsimScene:
    """The static parts of a pedsim scene.

    Attributes:
        walls: (W, 4) obstacle segments x1, y1, x2, y2, m.
        nodes: (N, 2) waypoint positions, m, in file order.
        node_ids: (N,) waypoint ids as written in the file.
        node_radius: (N,) waypoint radii, m (0 where the file gives none).
    """

    walls: np.ndarray
    nodes: np.ndarray
    node_ids: tuple[str, ...]
    node_radius: np.ndarray


class _LineTracker(ET.TreeBuilder):
    """ElementTree tree builder that records the source line of every element it sees.

    The file is fed one line at a time, so when expat reports an element start the line last fed is
    the one holding the end of its start tag.
    """

    def __init__(self) -> None:
        super().__init__()
        self.line = 0
        self.lines: dict[int, int] = {}

    def start(self, tag: str, attrib: dict[str, str]) -> ET.Element:
        element = super().start(tag, attrib)
        self.lines[id(element)] = self.line
        return element


def read_pedsim_scene(path: str | os.PathLike[str]) -> PedsimScene:
    """Read the obstacles and waypoints of a pedsim scene XML file.

    `<obstacle x1=".." y1=".." x2=".." y2=".."/>` elements become walls (zero-length ones dropped);
    `<waypoint id=".." x=".." y=".." r=".."/>` elements become graph nodes. Both are found at any
    depth; agents and other elements are ignored.

    Raises:
        FileNotFoundError: no such file.
        MapError: not UTF-8 text, malformed XML (an empty or truncated file included), an XML file
            without any obstacle or waypoint, or an obstacle or waypoint with a missing or
            non-numeric attribute; the message names the file and line.
    """
    where = os.fspath(path)
    tracker = _LineTracker()
    parser = ET.XMLParser(target=tracker)
    try:
        for line_no, line in enumerate(_read_text(path).splitlines(keepends=True), start=1):
            tracker.line = line_no
            parser.feed(line)
        root = parser.close()
    except ET.ParseError as err:
        line_no, column = err.position
        raise MapError(f"{where}:{line_no}: malformed XML (column {column + 1}): {err}") from None

    def number(element: ET.Element, key: str, default: float | None = None) -> float:
        text = element.get(key)
        entry = f"{where}:{tracker.lines.get(id(element), '?')}: <{element.tag}>"
        if text is None:
            if default is not None:
                return default
            raise MapError(f"{entry}: missing attribute {key!r}")
        try:
            value = float(text)
        except ValueError:
            raise MapError(f"{entry}: attribute {key}={text!r} is not a number") from None
        if not math.isfinite(value):
            raise MapError(f"{entry}: attribute {key}={text!r} is not finite")
        return value

    walls = [[number(o, k) for k in ("x1", "y1", "x2", "y2")] for o in root.iter("obstacle")]
    waypoints = list(root.iter("waypoint"))
    if not walls and not waypoints:
        raise MapError(
            f"{where}: no <obstacle> or <waypoint> elements; not a pedsim scene (root <{root.tag}>)"
        )
    nodes = [[number(w, "x"), number(w, "y")] for w in waypoints]
    return PedsimScene(
        walls=drop_zero_length(np.array(walls, dtype=np.float64).reshape(len(walls), 4), where),
        nodes=np.array(nodes, dtype=np.float64).reshape(len(nodes), 2),
        node_ids=tuple(w.get("id", str(k)) for k, w in enumerate(waypoints)),
        node_radius=np.array([number(w, "r", 0.0) for w in waypoints], dtype=np.float64),
    )


@dataclass(frozen=True)
class MapServerYaml:
    """What a ROS map_server YAML file says about its occupancy image.

    Attributes:
        image: the image file (relative paths resolved against the YAML file's folder).
        resolution: metres per pixel.
        origin: (x, y, yaw) of the image's lower-left corner: m, m, rad (counter-clockwise).
        negate: whether white means occupied.
        occupied_thresh: a pixel is occupied where its occupancy (1 - brightness, or the
            brightness when negated) exceeds this.
    """

    image: Path
    resolution: float
    origin: tuple[float, float, float]
    negate: bool
    occupied_thresh: float


def read_map_server_yaml(path: str | os.PathLike[str]) -> MapServerYaml:
    """Read a ROS map_server map YAML file (image, resolution, origin, negate, occupied_thresh).

    origin is a list [x, y, yaw]; occupied_thresh defaults to map_saver's 0.65, negate to 0;
    free_thresh and other keys are ignored (free and unknown pixels both count as free space: only
    occupied ones are walls).

    Raises:
        FileNotFoundError: no such file.
        MapError: not UTF-8 text, not YAML, not a mapping, a missing or malformed image, resolution
            or origin, a threshold outside (0, 1), or mode "raw" (its pixels are occupancy values,
            not shades); the message names the file and the key.
    """
    import yaml

    where = os.fspath(path)
    try:
        values = yaml.safe_load(_read_text(path))
    except yaml.YAMLError as err:
        raise MapError(f"{where}: not YAML ({err})".replace("\n", " ")) from None
    if not isinstance(values, dict) or not {"image", "resolution", "origin"} <= values.keys():
        raise MapError(f"{where}: not a map_server map YAML (needs image, resolution and origin)")

    def number(key: str, value: object) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise MapError(f"{where}: {key}: {value!r} is not a finite number")
        return float(value)

    image = values["image"]
    if not isinstance(image, str) or not image:
        raise MapError(f"{where}: image: expected a file name, got {image!r}")
    resolution = number("resolution", values["resolution"])
    if resolution <= 0:
        raise MapError(f"{where}: resolution: metres per pixel must be positive, got {resolution}")
    origin = values["origin"]
    if not isinstance(origin, list) or len(origin) != 3:
        raise MapError(f"{where}: origin: expected [x, y, yaw], got {origin!r}")
    x, y, yaw = (number("origin", v) for v in origin)
    occupied = number("occupied_thresh", values.get("occupied_thresh", 0.65))
    if not 0.0 < occupied < 1.0:
        raise MapError(f"{where}: occupied_thresh: must be in (0, 1), got {occupied}")
    negate = values.get("negate", 0)
    if negate not in (0, 1):  # True and False are 1 and 0 here
        raise MapError(f"{where}: negate: expected 0 or 1, got {negate!r}")
    if str(values.get("mode", "")).lower() == "raw":
        raise MapError(f"{where}: mode: 'raw' images hold occupancy values, not shades; not supported")
    image_path = Path(image)
    if not image_path.is_absolute():
        image_path = Path(where).parent / image_path
    return MapServerYaml(image_path, resolution, (x, y, yaw), bool(negate), occupied)


def is_map_server_yaml(path: str | os.PathLike[str]) -> bool:
    """Whether `path` names a ROS map_server map YAML (by its suffix) rather than an image."""
    return Path(path).suffix.lower() in (".yaml", ".yml")


def read_floor_plan(
    path: str | os.PathLike[str],
    *,
    scale: float | None = None,
    origin: tuple[float, float] = (0.0, 0.0),
    threshold: float | None = None,
    min_area: float = 0.0,
) -> tuple[np.ndarray, dict[str, Any]]:
    """Walls (W, 4) of a floor-plan image (an occupancy grid: pixels darker than `threshold`, 0 black
    .. 1 white, default 0.5, are walls; `scale` metres per pixel; `origin` the world position of its
    lower-left corner, m) or of a ROS map_server map YAML, which gives the image, the scale, the
    origin with its yaw, negate and the threshold (1 - occupied_thresh, unless `threshold` is
    given); and the inputs that made them, for the map's provenance.

    Raises:
        FileNotFoundError: no such image (or none where the YAML says).
        ValueError: an image without a scale, one that cannot be decoded or without wall pixels, a
            malformed YAML (MapError), or imageio missing.
    """
    from socialzoo.maps.occupancy import wall_pixels, walls_from_occupancy

    path = Path(path)
    image_file, yaw, negate = path, 0.0, False
    inputs: dict[str, Any] = {"png": path.name}
    if is_map_server_yaml(path):
        meta = read_map_server_yaml(path)
        x, y, yaw = meta.origin
        image_file, scale, origin, negate = meta.image, meta.resolution, (x, y), meta.negate
        # map_server: occupied where 1 - brightness (brightness when negated) > occupied_thresh.
        threshold = 1.0 - meta.occupied_thresh if threshold is None else threshold
        inputs.update(image=image_file.name, negate=negate, yaw=yaw)
    elif scale is None:
        raise ValueError(f"{path}: a floor-plan image needs its scale (metres per pixel)")
    threshold = 0.5 if threshold is None else threshold
    inputs.update(scale=scale, origin=list(origin), threshold=threshold)
    try:
        import imageio.v3 as iio
    except ImportError:  # pragma: no cover - the plot extra is missing
        raise ValueError("reading a floor-plan image needs imageio: pip install 'socialzoo[plot]'") from None
    if not image_file.is_file():
        named = f" (the image named by {path})" if image_file != path else ""
        raise FileNotFoundError(f"{image_file}: no such file{named}")
    try:
        image = iio.imread(image_file)
    except Exception as err:  # imageio raises many kinds for a file it cannot decode
        raise ValueError(f"{image_file}: not a readable image ({err})") from None
    if negate:
        image = (np.iinfo(image.dtype).max if np.issubdtype(image.dtype, np.integer) else 1.0) - image
    # map_server's origin is the pose of the image's lower-left corner: turned by yaw about it.
    walls = walls_from_occupancy(
        wall_pixels(image, threshold), scale, (0.0, 0.0) if yaw else origin, min_area=min_area
    )
    if len(walls) == 0:
        raise ValueError(f"{image_file}: no wall pixels darker than threshold {threshold}")
    if yaw:
        c, s = np.cos(yaw), np.sin(yaw)
        walls = (walls.reshape(-1, 2) @ np.array([[c, s], [-s, c]]) + np.array(origin)).reshape(-1, 4)
    return walls, inputs


def write_vector_map(path: str | os.PathLike[str], walls: np.ndarray) -> Path:
    """Write walls (W, 4) as an AMRL vector map ("x1, y1, x2, y2" per line); returns the path."""
    lines = [", ".join(f"{v:.6f}" for v in w) for w in np.asarray(walls, dtype=np.float64).reshape(-1, 4)]
    return write_text_atomic(path, "".join(line + "\n" for line in lines))
