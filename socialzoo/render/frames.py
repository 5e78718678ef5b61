"""Fast RGB frames of one world row, for render_mode="rgb_array" and "human"."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from socialzoo.core.config import HumanConfig, LaserConfig, RobotConfig
from socialzoo.core.laser import ray_angles
from socialzoo.core.state import WorldState
from socialzoo.core.validation import check_int, check_number
from socialzoo.maps.map_file import Map

if TYPE_CHECKING:
    from PIL import Image, ImageDraw, ImageFont

BACKGROUND = (255, 255, 255)
WALL = (45, 45, 55)
GRAPH_EDGE = (200, 212, 232)
GRAPH_NODE = (160, 178, 210)
HUMAN = (70, 120, 205)
HUMAN_EDGE = (25, 55, 125)
HIGHLIGHT = (215, 25, 60)
ROBOT = (245, 140, 30)
ROBOT_EDGE = (130, 65, 0)
ROBOT_MARK = (80, 35, 0)
OTHER_ROBOT = (250, 200, 150)
GOAL = (35, 165, 65)
CARROT = (215, 0, 200)
PATH = (160, 160, 160)
LASER = (225, 45, 45)
TEXT = (20, 20, 20)
TEXT_BOX = (255, 255, 255)
TEXT_BOX_EDGE = (200, 200, 200)

View = Literal["follow", "map"]

_TILE = 512  # side of a cached background tile in the follow view, pixels
_SUPERSAMPLE = 3  # the static background is drawn this many times larger, then box-filtered
_TRAIL_FADE = 0.85  # the oldest trail point is this close to white
_MIN_HUMAN_PX = 3.0  # smallest drawn human radius, output pixels
_MIN_ROBOT_PX = 10.0  # smallest drawn robot length, output pixels


@dataclass(frozen=True, kw_only=True)
class Overlay:
    """Optional extras drawn over a frame; every field may be left out.

    Attributes:
        path: (L, 2) global path polyline in the world frame, m.
        carrot: (2,) carrot (lookahead) point, m.
        goal: (2,) or (3,) goal position (and heading, rad); defaults to the state's robot goal.
        laser_ranges: (M,) ranges of the robot's scan, m; needs `laser`.
        laser: the LaserConfig that produced `laser_ranges` (ray angles and max range).
        action: name of the chosen sub-policy, e.g. "GoAlone", "Halt", "Follow", "Pass".
        highlight: index of the human being followed or passed, or None.
        info: extra text lines shown under the action and time.
    """

    path: np.ndarray | None = None
    carrot: np.ndarray | None = None
    goal: np.ndarray | None = None
    laser_ranges: np.ndarray | None = None
    laser: LaserConfig | None = None
    action: str | None = None
    highlight: int | None = None
    info: tuple[str, ...] = ()


def map_bounds(world_map: Map, margin: float = 0.5) -> tuple[float, float, float, float]:
    """(xmin, ymin, xmax, ymax) of the map's region, else of its walls, nodes and poses, in m."""
    if world_map.region is not None:
        return tuple(float(v) for v in world_map.region)  # type: ignore[return-value]
    points = [
        np.asarray(world_map.walls, float).reshape(-1, 2),
        np.asarray(world_map.nodes, float).reshape(-1, 2),
        np.asarray(world_map.legal_poses, float).reshape(-1, 3)[:, :2],
    ]
    pts = np.concatenate(points)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if len(pts) == 0:
        return (-5.0, -5.0, 5.0, 5.0)
    lo = pts.min(axis=0) - margin
    hi = pts.max(axis=0) + margin
    return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))


@lru_cache(maxsize=8)
def _font(size: int) -> ImageFont.ImageFont | ImageFont.FreeTypeFont:
    """Pillow's built-in font at `size` pixels (a bitmap font where FreeType is missing)."""
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1 has only the fixed-size bitmap font
        return ImageFont.load_default()


def _fade(color: tuple[int, int, int], amount: float) -> tuple[int, int, int]:
    """`color` mixed with white: amount 0 keeps it, 1 gives white."""
    return tuple(round(c + (255 - c) * amount) for c in color)  # type: ignore[return-value]


class FrameRenderer:
    """Draws one row of a WorldState as an (height, width, 3) uint8 RGB image.

    World y points up in the image. The renderer keeps each human's recent positions (a trail of
    up to `trail_length` points, one every `trail_spacing` metres walked); call reset() at the start
    of an episode. The trails also restart by themselves when the row's step count goes backwards,
    the row changes or a human jumps (respawns). In zoomed-out views humans and the robot are drawn
    at least a few pixels wide. The follow view caches the static layer in 512-pixel tiles, made
    as the robot first comes near them (at most about 90 MiB for a 100 m x 60 m map at the default
    640x480, antialias=2, once the robot has been everywhere).

    The walls (and optionally the navigation graph) are drawn once, antialiased, into cached images; each
    frame copies the visible part and draws the moving parts on it with Pillow.

    Args:
        map: the map whose walls are drawn.
        width: frame width, pixels.
        height: frame height, pixels.
        view: "follow" centres on the robot and shows +-view_radius metres along the shorter side;
            "map" shows the whole map region (map.region, else the walls' bounding box).
        view_radius: half the shorter side of the follow window, m.
        show_graph: draw the navigation graph under the walls.
        robot_config: robot footprint (length, width); defaults to RobotConfig().
        human_radius: radius of the human discs, m.
        dt: physics step, s, to show the time; None shows the step count only.
        trail_length: number of past positions kept per human.
        trail_spacing: distance walked between two kept positions, m.
        antialias: the moving parts are drawn this many times larger and box-filtered down
            (1 turns antialiasing off: about twice as fast, visibly jagged discs).
    """

    def __init__(
        self,
        map: Map,
        *,
        width: int = 640,
        height: int = 480,
        view: View = "follow",
        view_radius: float = 8.0,
        show_graph: bool = False,
        robot_config: RobotConfig | None = None,
        human_radius: float = HumanConfig().radius,
        dt: float | None = 0.025,
        trail_length: int = 20,
        trail_spacing: float = 0.1,
        antialias: int = 2,
    ) -> None:
        if view not in ("follow", "map"):
            raise ValueError(f"FrameRenderer.view must be 'follow' or 'map', got {view!r}")
        check_int("FrameRenderer", "width", width, low=16)
        check_int("FrameRenderer", "height", height, low=16)
        check_number("FrameRenderer", "view_radius", view_radius, low=0, low_open=True)
        check_int("FrameRenderer", "antialias", antialias, low=1, high=4)
        check_int("FrameRenderer", "trail_length", trail_length, low=0)
        self.map = map
        self.width = width
        self.height = height
        self.view = view
        self.view_radius = float(view_radius)
        self.show_graph = show_graph
        self.robot_config = robot_config or RobotConfig()
        self.human_radius = float(human_radius)
        self.dt = dt
        self.trail_length = trail_length
        self.trail_spacing = float(trail_spacing)

        self.antialias = antialias

        self._walls = np.asarray(map.walls, float).reshape(-1, 4)
        self._nodes = np.asarray(map.nodes, float).reshape(-1, 2)
        self._edges = np.asarray(map.edges, int).reshape(-1, 2)
        if view == "follow":
            self.scale = min(width, height) / (2.0 * self.view_radius)
        else:
            xmin, ymin, xmax, ymax = map_bounds(map)
            pad = 8
            span_x = max(xmax - xmin, 1e-6)
            span_y = max(ymax - ymin, 1e-6)
            self.scale = min((width - 2 * pad) / span_x, (height - 2 * pad) / span_y)
        # Drawing happens at `antialias` times the output size: internal pixels per metre and
        # frame size. Global internal pixel coordinates are u = x * _s, v = -y * _s.
        self._s = self.scale * antialias
        self._w = width * antialias
        self._h = height * antialias
        if view == "map":
            # The internal pixel at the frame's top-left corner, centring the region.
            self._origin = (
                xmin * self._s - (self._w - span_x * self._s) / 2.0,
                -ymax * self._s - (self._h - span_y * self._s) / 2.0,
            )
        else:
            self._origin = (0.0, 0.0)
        self._tiles: dict[tuple[int, int], Image.Image] = {}
        self._map_background: Image.Image | None = None
        self._font_size = max(10, round(height / 34))
        self.reset()

    # ------------------------------------------------------------------ episode state

    def reset(self) -> None:
        """Forget the human trails (call at the start of every episode)."""
        self._trail = np.zeros((0, self.trail_length, 2))
        self._trail_count = np.zeros(0, dtype=np.intp)
        self._last_step: int | None = None
        self._last_row: int | None = None

    def _update_trails(self, pos: np.ndarray, mask: np.ndarray, row: int, step: int) -> None:
        """Push each present human's position onto its trail once it has walked trail_spacing."""
        num_humans = len(pos)
        restart = (
            self._trail.shape[0] != num_humans
            or self._last_row != row
            or (self._last_step is not None and step < self._last_step)
        )
        if restart:
            self._trail = np.zeros((num_humans, self.trail_length, 2))
            self._trail_count = np.zeros(num_humans, dtype=np.intp)
        self._last_row = row
        self._last_step = step
        if self.trail_length == 0 or num_humans == 0:
            return
        has = self._trail_count > 0
        dist = np.linalg.norm(pos - self._trail[:, 0], axis=-1)
        jumped = has & (dist > max(1.0, 10.0 * self.trail_spacing))
        self._trail_count[jumped | ~mask] = 0
        push = mask & ((self._trail_count == 0) | (dist >= self.trail_spacing))
        if push.any():
            self._trail[push, 1:] = self._trail[push, :-1]
            self._trail[push, 0] = pos[push]
            self._trail_count[push] = np.minimum(self._trail_count[push] + 1, self.trail_length)

    # ------------------------------------------------------------------ static background

    def _draw_static(self, x0: float, y0: float, w: int, h: int) -> Image.Image:
        """Walls (and graph) in the internal pixel window [x0, x0 + w) x [y0, y0 + h), antialiased."""
        from PIL import Image, ImageDraw

        ss = max(1, round(_SUPERSAMPLE / self.antialias))
        s = self._s
        img = Image.new("RGB", (w * ss, h * ss), BACKGROUND)
        draw = ImageDraw.Draw(img)
        # The window in metres, grown so that thick lines just outside it are drawn too.
        margin = 4.0 * self.antialias / s
        wx0, wx1 = x0 / s - margin, (x0 + w) / s + margin
        wy0, wy1 = -(y0 + h) / s - margin, -y0 / s + margin

        def to_px(xy: np.ndarray) -> np.ndarray:
            u = (xy[..., 0] * s - x0) * ss + (ss - 1) / 2.0
            v = (-xy[..., 1] * s - y0) * ss + (ss - 1) / 2.0
            return np.stack((u, v), axis=-1)

        def visible(seg: np.ndarray) -> np.ndarray:
            xs, ys = seg[:, [0, 2]], seg[:, [1, 3]]
            inside_x = (xs.max(axis=1) >= wx0) & (xs.min(axis=1) <= wx1)
            return inside_x & (ys.max(axis=1) >= wy0) & (ys.min(axis=1) <= wy1)

        out_px = self.antialias * ss  # drawing pixels per output pixel
        if self.show_graph and len(self._edges):
            seg = np.concatenate((self._nodes[self._edges[:, 0]], self._nodes[self._edges[:, 1]]), axis=1)
            seg = seg[visible(seg)]
            for a, b in zip(to_px(seg[:, :2]).tolist(), to_px(seg[:, 2:]).tolist(), strict=True):
                draw.line((*a, *b), fill=GRAPH_EDGE, width=out_px)
            node_r = 2.5 * out_px
            for u, v in to_px(self._nodes).tolist():
                draw.ellipse((u - node_r, v - node_r, u + node_r, v + node_r), fill=GRAPH_NODE)

        if len(self._walls):
            seg = self._walls[visible(self._walls)]
            wall_px = max(1.3, 0.08 * self.scale) * out_px
            cap = wall_px / 2.0
            a_px, b_px = to_px(seg[:, :2]).tolist(), to_px(seg[:, 2:]).tolist()
            for a, b in zip(a_px, b_px, strict=True):
                draw.line((*a, *b), fill=WALL, width=max(1, round(wall_px)))
            # Round caps close the notches where thick segments meet at an angle.
            if cap >= 1.5:
                for u, v in a_px + b_px:
                    draw.ellipse((u - cap, v - cap, u + cap, v + cap), fill=WALL)
        return img.reduce(ss) if ss > 1 else img

    def _tile(self, i: int, j: int) -> Image.Image:
        if (i, j) not in self._tiles:
            self._tiles[(i, j)] = self._draw_static(i * _TILE, j * _TILE, _TILE, _TILE)
        return self._tiles[(i, j)]

    def _background(self, x0: int, y0: int) -> Image.Image:
        """The static layer (internal size) of the frame whose top-left is internal pixel (x0, y0)."""
        from PIL import Image

        if self.view == "map":
            if self._map_background is None:
                ox, oy = self._origin
                self._map_background = self._draw_static(ox, oy, self._w, self._h)
            return self._map_background.copy()
        frame = Image.new("RGB", (self._w, self._h))
        for j in range(math.floor(y0 / _TILE), math.floor((y0 + self._h - 1) / _TILE) + 1):
            for i in range(math.floor(x0 / _TILE), math.floor((x0 + self._w - 1) / _TILE) + 1):
                frame.paste(self._tile(i, j), (i * _TILE - x0, j * _TILE - y0))
        return frame

    # ------------------------------------------------------------------ frame

    def render(
        self, state: WorldState, row: int = 0, robot: int = 0, overlay: Overlay | None = None
    ) -> np.ndarray:
        """Draw row `row` of `state`, centred on robot `robot` in the follow view.

        Args:
            state: the batched world state.
            row: batch row to draw.
            robot: index of the robot the view follows and the overlay belongs to; other robots
                are drawn paler.
            overlay: optional path, carrot, goal, laser scan, action label and highlighted human.

        Returns:
            (height, width, 3) uint8 RGB image.
        """
        from PIL import ImageDraw

        if not 0 <= row < state.batch_size:
            raise IndexError(f"row {row} out of range for a batch of {state.batch_size}")
        if not 0 <= robot < state.num_robots:
            raise IndexError(f"robot {robot} out of range for {state.num_robots} robots")
        overlay = overlay or Overlay()
        poses = np.asarray(state.robot_pose[row], float)
        pose = poses[robot]
        human_pos = np.asarray(state.human_pos[row], float)
        human_mask = np.asarray(state.human_mask[row], bool) & np.isfinite(human_pos).all(axis=1)
        step = int(state.step_count[row])
        self._update_trails(human_pos, human_mask, row, step)

        s, aa = self._s, self.antialias
        if self.view == "follow":
            centre = pose[:2] if np.isfinite(pose[:2]).all() else np.zeros(2)
            x0 = round(centre[0] * s - self._w / 2.0)
            y0 = round(-centre[1] * s - self._h / 2.0)
            ox, oy = float(x0), float(y0)
            img = self._background(x0, y0)
        else:
            ox, oy = self._origin
            img = self._background(0, 0)
        draw = ImageDraw.Draw(img)

        def px(xy: np.ndarray) -> np.ndarray:
            xy = np.asarray(xy, float)
            return np.stack((xy[..., 0] * s - ox, -xy[..., 1] * s - oy), axis=-1)

        if overlay.path is not None and len(overlay.path) >= 2:
            pts = px(np.asarray(overlay.path, float).reshape(-1, 2))
            pts = pts[np.isfinite(pts).all(axis=1)]
            if len(pts) >= 2:
                draw.line([tuple(p) for p in pts.tolist()], fill=PATH, width=2 * aa, joint="curve")

        self._draw_trails(draw, px, human_pos, human_mask)

        # The scan and the link to the highlighted human go under the discs they end on.
        if overlay.laser_ranges is not None and overlay.laser is not None:
            self._draw_laser(draw, px, pose, np.asarray(overlay.laser_ranges, float), overlay.laser)
        # Zoomed-out views keep humans and the robot at least a few pixels wide.
        r = max(self.human_radius * s, _MIN_HUMAN_PX * aa)
        centres = px(human_pos)
        highlight = overlay.highlight
        highlighted = (
            highlight is not None and 0 <= highlight < len(human_pos) and bool(human_mask[highlight])
        )
        if highlighted and np.isfinite(pose[:2]).all():
            draw.line((*px(pose[:2]), *centres[highlight]), fill=HIGHLIGHT, width=aa)

        goal = overlay.goal if overlay.goal is not None else state.robot_goal[row, robot]
        self._draw_goal(draw, px, np.asarray(goal, float))

        for h in np.flatnonzero(human_mask).tolist():
            u, v = centres[h]
            draw.ellipse((u - r, v - r, u + r, v + r), fill=HUMAN, outline=HUMAN_EDGE, width=aa)

        for k in range(len(poses)):
            if k != robot:
                self._draw_robot(draw, px, poses[k], OTHER_ROBOT)
        self._draw_robot(draw, px, pose, ROBOT)

        if highlighted:
            u, v = centres[highlight]
            ring = r + 3 * aa
            draw.ellipse((u - ring, v - ring, u + ring, v + ring), outline=HIGHLIGHT, width=2 * aa)

        if overlay.carrot is not None:
            u, v = px(np.asarray(overlay.carrot, float)[:2])
            if math.isfinite(u) and math.isfinite(v):
                c = max(3.5 * aa, 0.1 * s)
                draw.ellipse((u - c, v - c, u + c, v + c), fill=CARROT, outline=(110, 0, 100), width=aa)

        if aa > 1:
            img = img.reduce(aa)
        self._draw_text(ImageDraw.Draw(img), overlay, step)
        return np.array(img)

    def _draw_trails(self, draw: ImageDraw.ImageDraw, px: Any, pos: np.ndarray, mask: np.ndarray) -> None:
        """Fading polylines from each human back through its kept positions."""
        if self.trail_length == 0 or not mask.any():
            return
        trail_px = px(self._trail)  # (H, T, 2)
        now_px = px(pos)
        width = max(2 * self.antialias, round(0.08 * self._s))
        n = self.trail_length
        colors = [_fade(HUMAN, 0.3 + (_TRAIL_FADE - 0.3) * k / max(n - 1, 1)) for k in range(n)]
        for h in np.flatnonzero(mask & (self._trail_count > 0)).tolist():
            points = [tuple(now_px[h]), *(tuple(p) for p in trail_px[h, : self._trail_count[h]].tolist())]
            for k in range(len(points) - 1):
                draw.line((*points[k], *points[k + 1]), fill=colors[k], width=width)

    def _draw_goal(self, draw: ImageDraw.ImageDraw, px: Any, goal: np.ndarray) -> None:
        """A green ring with a dot, and a tick along the goal heading when there is one."""
        if goal.shape[-1] < 2 or not np.isfinite(goal[:2]).all():
            return
        aa = self.antialias
        u, v = px(goal[:2])
        r = max(5.0 * aa, 0.3 * self._s)
        draw.ellipse((u - r, v - r, u + r, v + r), outline=GOAL, width=2 * aa)
        c = max(2.0 * aa, 0.08 * self._s)
        draw.ellipse((u - c, v - c, u + c, v + c), fill=GOAL)
        if goal.shape[-1] >= 3 and math.isfinite(goal[2]):
            cos, sin = math.cos(goal[2]), math.sin(goal[2])
            draw.line(
                (u + r * cos, v - r * sin, u + 1.7 * r * cos, v - 1.7 * r * sin), fill=GOAL, width=2 * aa
            )

    def _draw_robot(
        self, draw: ImageDraw.ImageDraw, px: Any, pose: np.ndarray, color: tuple[int, int, int]
    ) -> None:
        """Its footprint, an oriented box or a disc (RobotConfig.radius), with a chevron pointing
        along the heading."""
        if not np.isfinite(pose).all():
            return
        disc = self.robot_config.radius
        hl, hw = (
            (disc, disc)
            if disc is not None
            else (self.robot_config.half_length, self.robot_config.half_width)
        )
        grow = max(1.0, _MIN_ROBOT_PX * self.antialias / (2.0 * hl * self._s))
        hl, hw = hl * grow, hw * grow
        c, sn = math.cos(pose[2]), math.sin(pose[2])
        box = [[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]]
        chevron = [[0.85 * hl, 0.0], [-0.35 * hl, 0.6 * hw], [-0.1 * hl, 0.0], [-0.35 * hl, -0.6 * hw]]
        world = pose[:2] + np.array(box + chevron) @ np.array([[c, sn], [-sn, c]])
        pts = [tuple(p) for p in px(world).tolist()]
        main = color == ROBOT
        edge = ROBOT_EDGE if main else _fade(ROBOT_EDGE, 0.45)
        mark = ROBOT_MARK if main else _fade(ROBOT_MARK, 0.45)
        outline = max(self.antialias, round(0.03 * self._s))
        if disc is not None:
            (cx, cy), r = px(pose[None, :2])[0], hl * self._s
            draw.ellipse([cx - r, cy - r, cx + r, cy + r], fill=color, outline=edge, width=outline)
        else:
            draw.polygon(pts[:4], fill=color, outline=edge, width=outline)
        draw.polygon(pts[4:], fill=mark)

    def _draw_laser(
        self, draw: ImageDraw.ImageDraw, px: Any, pose: np.ndarray, ranges: np.ndarray, cfg: LaserConfig
    ) -> None:
        """Scan end points that hit something (range below max_range) as small dots."""
        angles = ray_angles(cfg)
        if len(ranges) != len(angles):
            raise ValueError(
                f"Overlay.laser_ranges has {len(ranges)} rays but its LaserConfig has {len(angles)}"
            )
        hit = np.isfinite(ranges) & (ranges < cfg.max_range - 1e-6)
        theta = pose[2] + angles[hit]
        ends = pose[:2] + ranges[hit, None] * np.stack((np.cos(theta), np.sin(theta)), axis=-1)
        d = self.antialias * min(1.2, max(0.7, 0.05 * self.scale))
        for u, v in px(ends).tolist():
            draw.ellipse((u - d, v - d, u + d, v + d), fill=LASER)

    def _draw_text(self, draw: ImageDraw.ImageDraw, overlay: Overlay, step: int) -> None:
        """Action label, time and info lines in a white box at the top-left corner (output pixels)."""
        lines = [str(overlay.action)] if overlay.action else []
        lines.append(f"step {step}" if self.dt is None else f"t = {step * self.dt:.2f} s   step {step}")
        lines.extend(str(line) for line in overlay.info)
        font = _font(self._font_size)
        big = _font(round(self._font_size * 1.3))
        fonts = [big if (k == 0 and overlay.action) else font for k in range(len(lines))]
        heights = [f.size + 4 if hasattr(f, "size") else 14 for f in fonts]
        pad = 4
        text_w = max(draw.textlength(line, font=f) for line, f in zip(lines, fonts, strict=True))
        draw.rectangle(
            (pad, pad, 3 * pad + text_w, 2 * pad + sum(heights) + pad), fill=TEXT_BOX, outline=TEXT_BOX_EDGE
        )
        y: float = 2 * pad - 1
        for k, (line, f) in enumerate(zip(lines, fonts, strict=True)):
            color = ROBOT_MARK if (k == 0 and overlay.action) else TEXT
            draw.text((2 * pad, y), line, fill=color, font=f)
            y += heights[k]


class HumanWindow:
    """A matplotlib window that shows frames as they come (render_mode="human").

    matplotlib is imported here, when the first window is made, never at module import.

    Args:
        title: window title (several windows may share one: each has its own figure).
        fps: frames per second to pace the display at; None draws as fast as it can.
    """

    def __init__(self, title: str = "socialzoo", fps: float | None = None) -> None:
        import matplotlib.pyplot as plt

        self._plt = plt
        plt.ion()
        self.fig: Any
        # A figure of its own, titled after it is made: plt.subplots(num=title) would reuse (or, in
        # matplotlib 3.11, refuse) the figure of another window with the same title, so a second
        # env rendering to a window in the same process raised.
        self.fig, self.ax = plt.subplots()
        if self.fig.canvas.manager is not None:
            self.fig.canvas.manager.set_window_title(title)
        self.ax.set_axis_off()
        self.fig.subplots_adjust(left=0, right=1, bottom=0, top=1)
        self._image: Any = None
        self.fps = fps
        # Non-interactive backends (Agg, in tests and on servers) have no event loop to run.
        self._interactive = getattr(type(self.fig.canvas), "required_interactive_framework", None) is not None

    @property
    def is_open(self) -> bool:
        """False once the window was closed (by close() or by the user)."""
        return self.fig is not None and self._plt.fignum_exists(self.fig.number)

    def show(self, frame: np.ndarray) -> None:
        """Display an (H, W, 3) uint8 frame, replacing the previous one."""
        if self.fig is None:
            raise RuntimeError("HumanWindow.show called after close()")
        if self._image is None or self._image.get_array().shape != frame.shape:
            self.ax.clear()
            self.ax.set_axis_off()
            self._image = self.ax.imshow(frame, interpolation="nearest")
            h, w = frame.shape[:2]
            self.fig.set_size_inches(w / self.fig.dpi, h / self.fig.dpi)
        else:
            self._image.set_data(frame)
        if self._interactive:
            self._plt.pause(1.0 / self.fps if self.fps else 1e-3)
        else:
            self.fig.canvas.draw_idle()

    def close(self) -> None:
        """Close the window; further show() calls raise."""
        if self.fig is not None:
            self._plt.close(self.fig)
            self.fig = None
