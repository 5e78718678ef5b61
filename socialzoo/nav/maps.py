"""Maps: walls, navigation graph and legal poses, stored as one JSON file per map.

File format ("socialzoo-map/1"), all coordinates in metres, world frame:

    {
      "format": "socialzoo-map/1",
      "name": "gdc1",
      "source": "where the data comes from",
      "licence": "licence and attribution of the data",
      "region": [xmin, ymin, xmax, ymax],          # optional area of interest
      "walls": [[x1, y1, x2, y2], ...],
      "graph": {"nodes": [[x, y], ...], "edges": [[i, j], ...]},   # undirected, node indices
      "legal_poses": [[x, y, theta], ...]         # robot and human start/goal poses, theta in rad
    }
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.core.walls import WallIndex

MAP_FORMAT = "socialzoo-map/1"


class MapError(ValueError):
    """A map file or map data is malformed; the message names the file and the entry."""


@dataclass(frozen=True, eq=False)
class Map:
    """A building map.

    Attributes:
        name: short identifier, e.g. "gdc1".
        walls: (W, 4) wall segments x1, y1, x2, y2, m.
        nodes: (N, 2) navigation-graph node positions, m.
        edges: (E, 2) int node index pairs, undirected.
        legal_poses: (P, 3) start/goal poses x, y (m), theta (rad).
        source: provenance of the data.
        licence: licence and attribution of the data.
        region: optional (xmin, ymin, xmax, ymax) area of interest, m.
        path: file the map was loaded from, if any (used in error messages).
    """

    name: str
    walls: np.ndarray
    nodes: np.ndarray
    edges: np.ndarray
    legal_poses: np.ndarray
    source: str = ""
    licence: str = ""
    region: tuple[float, float, float, float] | None = None
    path: str | None = field(default=None, compare=False)

    @cached_property
    def wall_index(self) -> WallIndex:
        """The spatial index over this map's walls (built once per map object)."""
        return WallIndex(self.walls)

    @property
    def num_walls(self) -> int:
        return len(self.walls)

    @property
    def num_nodes(self) -> int:
        return len(self.nodes)

    @property
    def where(self) -> str:
        """How errors refer to this map: its file if it has one, else its name."""
        return self.path or f"map {self.name!r}"

    def to_json(self) -> dict[str, Any]:
        """The map as a JSON-ready dict in the socialzoo-map/1 format."""
        data: dict[str, Any] = {
            "format": MAP_FORMAT,
            "name": self.name,
            "source": self.source,
            "licence": self.licence,
        }
        if self.region is not None:
            data["region"] = [float(v) for v in self.region]
        data["walls"] = [[round(float(v), 6) for v in w] for w in self.walls]
        data["graph"] = {
            "nodes": [[round(float(v), 6) for v in n] for n in self.nodes],
            "edges": [[int(i), int(j)] for i, j in self.edges],
        }
        data["legal_poses"] = [[round(float(v), 6) for v in p] for p in self.legal_poses]
        return data

    def save(self, path: str | Path) -> Path:
        """Write the map as JSON; returns the path."""
        path = Path(path)
        path.write_text(json.dumps(self.to_json(), indent=None, separators=(",", ":")) + "\n")
        return path
