"""Seeded synthetic floor plans (offices along corridors, atria with pillars, long and winding corridors) as wall
segments (W, 4) with a point inside, for testing importers and navigation on buildings nobody has tuned for."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

Point = tuple[float, float]


@dataclass(frozen=True)
class FloorPlan:
    """A synthetic building.

    Walls are drawn as real plans draw them: solid pieces between door gaps, either thin (one line)
    or `thickness` thick (a closed outline of four lines). Every plan is a pure function of its seed
    and options.

    Attributes:
        name: plan name (kind and seed).
        walls: (W, 4) wall segments x1, y1, x2, y2, m.
        inside: (2,) a point in the free space of the building, m.
    """

    name: str
    walls: np.ndarray
    inside: Point


class _Drawing:
    """Collects wall pieces; axis-aligned walls with door gaps."""

    def __init__(self, thickness: float) -> None:
        self.thickness = thickness
        self.segments: list[list[float]] = []

    def piece(self, a: Point, b: Point, extend: tuple[bool, bool] = (True, True)) -> None:
        """A solid wall from a to b: a line, or a thick outline around it, grown by half the
        thickness past each end that `extend` marks (so that walls meeting at a corner close it;
        a door jamb is not grown, so the door keeps its width)."""
        (x0, y0), (x1, y1) = a, b
        if abs(x1 - x0) + abs(y1 - y0) < 1e-9:
            return
        t = 0.5 * self.thickness
        if t <= 0:
            self.segments.append([x0, y0, x1, y1])
            return
        d = np.array([x1 - x0, y1 - y0]) / np.hypot(x1 - x0, y1 - y0)
        n = np.array([-d[1], d[0]]) * t
        p0, p1 = np.array(a) - d * t * extend[0], np.array(b) + d * t * extend[1]
        corners = [p0 + n, p1 + n, p1 - n, p0 - n]
        for k in range(4):
            c, e = corners[k], corners[(k + 1) % 4]
            self.segments.append([float(c[0]), float(c[1]), float(e[0]), float(e[1])])

    def wall(self, a: Point, b: Point, doors: Sequence[tuple[float, float]] = ()) -> None:
        """A straight wall from a to b with door gaps (distance of the gap's centre from a, width)."""
        length = float(np.hypot(b[0] - a[0], b[1] - a[1]))
        d = ((b[0] - a[0]) / length, (b[1] - a[1]) / length)
        at = 0.0
        for centre, width in sorted(doors):
            lo, hi = max(centre - 0.5 * width, 0.0), min(centre + 0.5 * width, length)
            if lo > at:
                start = (a[0] + d[0] * at, a[1] + d[1] * at)
                self.piece(start, (a[0] + d[0] * lo, a[1] + d[1] * lo), (at == 0.0, False))
            at = max(at, hi)
        if at < length:
            self.piece((a[0] + d[0] * at, a[1] + d[1] * at), b, (at == 0.0, True))

    def box(self, x0: float, y0: float, x1: float, y1: float) -> None:
        for a, b in (((x0, y0), (x1, y0)), ((x1, y0), (x1, y1)), ((x1, y1), (x0, y1)), ((x0, y1), (x0, y0))):
            self.wall(a, b)

    def result(self) -> np.ndarray:
        return np.array(self.segments, dtype=np.float64).reshape(-1, 4)


def _door_at(rng: np.random.Generator, length: float, width: float) -> float:
    """A door centre along a wall of `length`, at least 0.3 m from either end."""
    return float(rng.uniform(0.3 + 0.5 * width, max(length - 0.3 - 0.5 * width, 0.3 + 0.5 * width)))


def office_corridor(
    seed: int = 0,
    *,
    num_offices: int = 8,
    corridor_width: float = 2.0,
    office_width: tuple[float, float] = (3.0, 4.5),
    office_depth: tuple[float, float] = (4.0, 6.0),
    door_width: float = 0.9,
    thickness: float = 0.15,
) -> FloorPlan:
    """Offices on both sides of a straight corridor, one door each, and an open end room."""
    rng = np.random.default_rng(seed)
    draw = _Drawing(thickness)
    widths = rng.uniform(*office_width, size=(2, num_offices))
    depth = rng.uniform(*office_depth, size=2)
    length = float(max(widths.sum(axis=1)))
    h = 0.5 * corridor_width
    for side, sign in ((0, 1.0), (1, -1.0)):
        x = 0.0
        outer = sign * (h + depth[side])
        doors = []
        for w in widths[side]:
            doors.append((x + _door_at(rng, w, door_width), door_width))
            if x + w < length - 1e-6:
                draw.wall((x + w, sign * h), (x + w, outer))
            x += w
        draw.wall((0.0, sign * h), (length, sign * h), doors)
        draw.wall((0.0, outer), (length, outer))
        draw.wall((0.0, sign * h), (0.0, outer))
    # An end room twice the corridor's width beyond the offices, open to the corridor.
    room = float(rng.uniform(5.0, 8.0))
    top, bottom = h + depth[0], -(h + depth[1])
    draw.wall((length, top), (length + room, top))
    draw.wall((length + room, top), (length + room, bottom))
    draw.wall((length + room, bottom), (length, bottom))
    draw.wall((length, h), (length, top))
    draw.wall((length, -h), (length, bottom))
    draw.wall((0.0, -h), (0.0, h), [(h, 1.2)])
    draw.wall((-3.0, -h), (-3.0, h))
    draw.wall((-3.0, h), (0.0, h))
    draw.wall((-3.0, -h), (0.0, -h))
    return FloorPlan(f"office_corridor_{seed}", draw.result(), (length * 0.5, 0.0))


def atrium(
    seed: int = 0,
    *,
    size: tuple[float, float] = (18.0, 24.0),
    pillar: float = 0.6,
    pillar_spacing: float = 6.0,
    ring_width: float = 2.2,
    num_rooms: int = 4,
    door_width: float = 1.0,
    thickness: float = 0.2,
) -> FloorPlan:
    """A large open hall with a grid of pillars, a corridor around it and rooms off the corridor."""
    rng = np.random.default_rng(seed)
    draw = _Drawing(thickness)
    w, h = (float(v) for v in rng.uniform(*size, size=2))
    # The hall: open on each side through two wide openings.
    openings = [(0.25 * w, 3.0), (0.75 * w, 3.0)]
    draw.wall((0, 0), (w, 0), openings)
    draw.wall((0, h), (w, h), openings)
    draw.wall((0, 0), (0, h), [(0.5 * h, 3.0)])
    draw.wall((w, 0), (w, h), [(0.5 * h, 3.0)])
    for x in np.arange(pillar_spacing, w - 1.0, pillar_spacing):
        for y in np.arange(pillar_spacing, h - 1.0, pillar_spacing):
            half = 0.5 * pillar
            draw.box(x - half, y - half, x + half, y + half)
    r = ring_width
    # The outer wall of the corridor ring, with doors into rooms on the south and north sides.
    room_depth = float(rng.uniform(4.0, 6.0))
    spans = np.linspace(-r, w + r, num_rooms + 1)
    for y in (-r, h + r):
        doors = [
            (float(a + _door_at(rng, b - a, door_width) + r), door_width)
            for a, b in itertools.pairwise(spans.tolist())
        ]
        draw.wall((-r, y), (w + r, y), doors)
    draw.wall((-r, -r), (-r, h + r))
    draw.wall((w + r, -r), (w + r, h + r))
    for y0, y1 in ((-r, -r - room_depth), (h + r, h + r + room_depth)):
        draw.wall((-r, y1), (w + r, y1))
        for x in spans:
            draw.wall((float(x), y0), (float(x), y1))
    return FloorPlan(f"atrium_{seed}", draw.result(), (0.5 * w + 0.5 * pillar_spacing, 0.5 * h))


def winding_corridor(
    seed: int = 0,
    *,
    num_legs: int = 6,
    width: tuple[float, float] = (1.5, 2.2),
    leg_length: tuple[float, float] = (6.0, 14.0),
    thickness: float = 0.0,
) -> FloorPlan:
    """A corridor of straight legs joined by sharp (90 degree) corners, turning left or right."""
    rng = np.random.default_rng(seed)
    draw = _Drawing(thickness)
    cw = float(rng.uniform(*width))
    h = 0.5 * cw
    heading = 0
    directions = ((1, 0), (0, 1), (-1, 0), (0, -1))
    pos = np.zeros(2)
    centre = [pos.copy()]
    for _ in range(num_legs):
        d = np.array(directions[heading])
        pos = pos + d * float(rng.uniform(*leg_length))
        centre.append(pos.copy())
        heading = (heading + (1 if rng.random() < 0.5 else 3)) % 4
    pts = np.array(centre)
    # Offset the polyline both ways (mitred corners) to get the two walls.
    for side in (1.0, -1.0):
        offset = []
        for k, p in enumerate(pts):
            normals = []
            if k > 0:
                d = (p - pts[k - 1]) / np.linalg.norm(p - pts[k - 1])
                normals.append(np.array([-d[1], d[0]]))
            if k < len(pts) - 1:
                d = (pts[k + 1] - p) / np.linalg.norm(pts[k + 1] - p)
                normals.append(np.array([-d[1], d[0]]))
            n = np.sum(normals, axis=0)
            n = n / max(float(np.dot(n, normals[0])), 1e-9)
            offset.append(p + side * h * n)
        for a, b in itertools.pairwise(offset):
            draw.wall((float(a[0]), float(a[1])), (float(b[0]), float(b[1])))
    for end in (0, -1):
        d = pts[1] - pts[0] if end == 0 else pts[-1] - pts[-2]
        d = d / np.linalg.norm(d)
        n = np.array([-d[1], d[0]]) * h
        p = pts[end]
        draw.wall((float((p + n)[0]), float((p + n)[1])), (float((p - n)[0]), float((p - n)[1])))
    mid = 0.5 * (pts[0] + pts[1])
    return FloorPlan(f"winding_corridor_{seed}", draw.result(), (float(mid[0]), float(mid[1])))


def room_grid(
    seed: int = 0,
    *,
    rows: int = 3,
    cols: int = 4,
    room: tuple[float, float] = (4.0, 7.0),
    door_width: tuple[float, float] = (0.9, 1.2),
    thickness: float = 0.12,
) -> FloorPlan:
    """A grid of rooms joined by doors between neighbours (a random spanning tree plus a few more)."""
    rng = np.random.default_rng(seed)
    draw = _Drawing(thickness)
    xs = np.concatenate(([0.0], np.cumsum(rng.uniform(*room, size=cols))))
    ys = np.concatenate(([0.0], np.cumsum(rng.uniform(*room, size=rows))))
    # Doors: a spanning tree of the room grid (random order), plus 30% of the other walls.
    walls_between = [("v", i, j) for i in range(1, cols) for j in range(rows)]
    walls_between += [("h", i, j) for i in range(cols) for j in range(1, rows)]
    order = rng.permutation(len(walls_between))
    parent = list(range(rows * cols))

    def root(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    door = set()
    for k in order.tolist():
        kind, i, j = walls_between[k]
        a, b = (i - 1) * rows + j, i * rows + j
        if kind == "h":
            a, b = i * rows + j - 1, i * rows + j
        if root(a) != root(b):
            parent[root(a)] = root(b)
            door.add(k)
        elif rng.random() < 0.3:
            door.add(k)
    for k, (kind, i, j) in enumerate(walls_between):
        dw = float(rng.uniform(*door_width))
        if kind == "v":
            a, b = (float(xs[i]), float(ys[j])), (float(xs[i]), float(ys[j + 1]))
        else:
            a, b = (float(xs[i]), float(ys[j])), (float(xs[i + 1]), float(ys[j]))
        length = float(np.hypot(b[0] - a[0], b[1] - a[1]))
        draw.wall(a, b, [(_door_at(rng, length, dw), dw)] if k in door else [])
    draw.box(0.0, 0.0, float(xs[-1]), float(ys[-1]))
    return FloorPlan(f"room_grid_{seed}", draw.result(), (0.5 * float(xs[1]), 0.5 * float(ys[1])))


def two_rooms(
    door_width: float = 0.9,
    *,
    room: tuple[float, float] = (5.0, 4.0),
    door_offset: float = 0.0,
    thickness: float = 0.15,
) -> FloorPlan:
    """Two rooms side by side (each room[0] x room[1] m, the first from x = 0) joined by one door
    in the wall between them at x = room[0], its centre door_offset m off the middle: the plan for
    doorways, from a door too narrow for the robot (0.6 m) to real ones (0.8 to 1.0 m)."""
    draw = _Drawing(thickness)
    w, h = room
    draw.box(0.0, 0.0, 2.0 * w, h)
    draw.wall((w, 0.0), (w, h), [(0.5 * h + door_offset, door_width)])
    return FloorPlan(f"two_rooms_{door_width:g}", draw.result(), (0.5 * w, 0.5 * h))


def long_corridor(length: float = 150.0, width: float = 2.0) -> FloorPlan:
    """One straight corridor, closed at both ends (longer than the robot drives in 80 s)."""
    draw = _Drawing(0.0)
    draw.box(0.0, 0.0, length, width)
    return FloorPlan(f"long_corridor_{length:g}", draw.result(), (1.0, 0.5 * width))


PLANS: dict[str, Callable[..., FloorPlan]] = {
    "office_corridor": office_corridor,
    "atrium": atrium,
    "winding_corridor": winding_corridor,
    "room_grid": room_grid,
}
