"""FrameRenderer draws walls, humans, robot and overlays where the state puts them."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from socialzoo.core.config import LaserConfig
from socialzoo.core.state import WorldState
from socialzoo.maps.map_file import Map
from socialzoo.render import frames
from socialzoo.render.frames import FrameRenderer, HumanWindow, Overlay, map_bounds

WIDTH, HEIGHT = 320, 240


def room() -> Map:
    """A 10 m x 8 m room with one interior wall."""
    walls = np.array([[0, 0, 10, 0], [10, 0, 10, 8], [10, 8, 0, 8], [0, 8, 0, 0], [5, 0, 5, 3]], float)
    return Map(
        name="room",
        walls=walls,
        nodes=np.zeros((0, 2)),
        edges=np.zeros((0, 2), int),
        legal_poses=np.zeros((0, 3)),
    )


def make_state(
    robot=(3.0, 5.0, 0.0), humans=((7.0, 5.0), (2.0, 2.0), (8.0, 2.0)), mask=(True, True, False), step=0
):
    num_humans = len(humans)
    return WorldState(
        robot_pose=np.array([[robot]], float),
        robot_vel=np.zeros((1, 1, 2)),
        robot_goal=np.array([[[9.0, 7.0, 0.0]]]),
        human_pos=np.array([humans], float),
        human_vel=np.zeros((1, num_humans, 2)),
        human_pref_speed=np.ones((1, num_humans)),
        human_mask=np.array([mask], bool),
        human_route=np.zeros((1, num_humans, 1, 2)),
        human_route_len=np.ones((1, num_humans), int),
        human_waypoint=np.zeros((1, num_humans), int),
        human_direction=np.ones((1, num_humans), int),
        step_count=np.array([step]),
        noise_key=np.zeros(1, np.uint64),
    )


def pixel(renderer: FrameRenderer, xy, robot_xy=None) -> tuple[int, int]:
    """(column, row) of world point xy in the frame."""
    s = renderer.scale
    if renderer.view == "follow":
        u = renderer.width / 2 + (xy[0] - robot_xy[0]) * s
        v = renderer.height / 2 - (xy[1] - robot_xy[1]) * s
    else:
        ox, oy = renderer._origin
        u = (xy[0] * renderer._s - ox) / renderer.antialias
        v = (-xy[1] * renderer._s - oy) / renderer.antialias
    return int(u), int(v)


def robot_body(x: float, y: float, theta: float) -> tuple[float, float]:
    """A point in the robot's box behind the heading chevron."""
    return x - 0.18 * np.cos(theta), y - 0.18 * np.sin(theta)


def color_at(frame: np.ndarray, uv: tuple[int, int]) -> np.ndarray:
    return frame[uv[1], uv[0]].astype(int)


def close_to(a: np.ndarray, b, tol: int = 40) -> bool:
    return bool(np.abs(a - np.asarray(b)).max() <= tol)


@pytest.mark.parametrize("view", ["follow", "map"])
@pytest.mark.parametrize("antialias", [1, 2])
def test_frame_shape_and_content(view, antialias):
    renderer = FrameRenderer(
        room(), width=WIDTH, height=HEIGHT, view=view, view_radius=6.0, antialias=antialias
    )
    frame = renderer.render(make_state())
    assert frame.shape == (HEIGHT, WIDTH, 3)
    assert frame.dtype == np.uint8
    robot_xy = (3.0, 5.0)
    assert close_to(color_at(frame, pixel(renderer, robot_body(3.0, 5.0, 0.0), robot_xy)), frames.ROBOT)
    assert close_to(color_at(frame, pixel(renderer, (3.08, 5.0), robot_xy)), frames.ROBOT_MARK)
    assert close_to(color_at(frame, pixel(renderer, (7.0, 5.0), robot_xy)), frames.HUMAN)
    assert close_to(color_at(frame, pixel(renderer, (2.0, 2.0), robot_xy)), frames.HUMAN)
    # Human 2 is absent: its spot stays background.
    assert close_to(color_at(frame, pixel(renderer, (8.0, 2.0), robot_xy)), frames.BACKGROUND, tol=5)
    # Points along the right-hand wall and the interior wall.
    for y in (1.0, 4.0, 6.5):
        assert close_to(color_at(frame, pixel(renderer, (10.0, y), robot_xy)), frames.WALL, tol=60)
    assert close_to(color_at(frame, pixel(renderer, (5.0, 1.5), robot_xy)), frames.WALL, tol=60)
    # The state's goal is drawn in green (its centre dot).
    assert close_to(color_at(frame, pixel(renderer, (9.0, 7.0), robot_xy)), frames.GOAL, tol=60)


def test_follow_and_map_views_differ():
    state = make_state()
    follow = FrameRenderer(room(), width=WIDTH, height=HEIGHT, view="follow", view_radius=3.0).render(state)
    whole = FrameRenderer(room(), width=WIDTH, height=HEIGHT, view="map").render(state)
    assert not np.array_equal(follow, whole)


def test_follow_view_moves_with_robot():
    renderer = FrameRenderer(room(), width=WIDTH, height=HEIGHT, view="follow", view_radius=4.0)
    a = renderer.render(make_state(robot=(3.0, 5.0, 0.0)))
    b = renderer.render(make_state(robot=(6.0, 4.0, 1.0)))
    assert not np.array_equal(a, b)
    assert close_to(color_at(b, pixel(renderer, robot_body(6.0, 4.0, 1.0), (6.0, 4.0))), frames.ROBOT)


def test_absent_humans_not_drawn():
    renderer = FrameRenderer(room(), width=WIDTH, height=HEIGHT, view="map")
    shown = renderer.render(make_state(mask=(True, True, True)))
    renderer.reset()
    hidden = renderer.render(make_state(mask=(True, True, False)))
    uv = pixel(renderer, (8.0, 2.0))
    assert close_to(color_at(shown, uv), frames.HUMAN)
    assert close_to(color_at(hidden, uv), frames.BACKGROUND, tol=5)


def test_overlay_extras():
    renderer = FrameRenderer(room(), width=WIDTH, height=HEIGHT, view="map", dt=0.025)
    laser = LaserConfig(num_rays=90, fov_deg=360.0, max_range=10.0)
    overlay = Overlay(
        path=np.array([[3.0, 5.0], [5.0, 6.0], [9.0, 7.0]]),
        carrot=np.array([5.0, 6.0]),
        goal=np.array([9.0, 7.0, 1.0]),
        laser_ranges=np.full(90, 2.0),
        laser=laser,
        action="Follow",
        highlight=0,
        info=("humans 2",),
    )
    plain = renderer.render(make_state())
    frame = renderer.render(make_state(), overlay=overlay)
    assert close_to(color_at(frame, pixel(renderer, (5.0, 6.0))), frames.CARROT)
    # Follow target ring: just outside the human's disc.
    ring = pixel(renderer, (7.0, 5.0 + 0.2 + 2.0 / renderer.scale))
    assert close_to(color_at(frame, ring), frames.HIGHLIGHT, tol=80)
    # The scan (all rays 2 m) puts red dots on a circle around the robot.
    dot = pixel(renderer, (3.0, 7.0))
    patch = frame[dot[1] - 1 : dot[1] + 2, dot[0] - 1 : dot[0] + 2].reshape(-1, 3).astype(int)
    assert any(close_to(c, frames.LASER, tol=60) for c in patch)
    # Text box in the top-left corner differs from the frame without the action label.
    assert not np.array_equal(frame[:40, :80], plain[:40, :80])


def test_laser_size_mismatch_raises():
    renderer = FrameRenderer(room(), width=WIDTH, height=HEIGHT, view="map")
    with pytest.raises(ValueError, match="laser_ranges"):
        renderer.render(make_state(), overlay=Overlay(laser_ranges=np.ones(5), laser=LaserConfig(num_rays=6)))


def test_trails_follow_humans_and_reset():
    renderer = FrameRenderer(
        room(), width=WIDTH, height=HEIGHT, view="map", trail_length=10, trail_spacing=0.1
    )
    for step in range(30):
        renderer.render(make_state(humans=((2.0 + 0.05 * step, 6.0), (2.0, 2.0), (8.0, 2.0)), step=step))
    assert renderer._trail_count[0] == 10  # walked 1.45 m: the trail is full
    assert renderer._trail_count[1] == 1  # standing still: one point
    assert renderer._trail_count[2] == 0  # absent
    frame = renderer.render(make_state(humans=((3.5, 6.0), (2.0, 2.0), (8.0, 2.0)), step=30))
    behind = color_at(frame, pixel(renderer, (3.1, 6.0)))
    assert not close_to(behind, frames.BACKGROUND, tol=5)  # the faded trail
    assert behind[2] > behind[0]  # blue-ish
    renderer.render(make_state(step=0))  # step count went back: a new episode
    assert renderer._trail_count.max() <= 1


def test_bad_arguments():
    with pytest.raises(ValueError, match="view"):
        FrameRenderer(room(), view="top")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="width"):
        FrameRenderer(room(), width=4)
    renderer = FrameRenderer(room(), width=WIDTH, height=HEIGHT)
    with pytest.raises(IndexError):
        renderer.render(make_state(), row=1)


def test_map_bounds_and_graph():
    m = room()
    assert map_bounds(m) == (-0.5, -0.5, 10.5, 8.5)
    graph = Map(
        name="g",
        walls=m.walls,
        nodes=np.array([[2.0, 4.0], [8.0, 4.0]]),
        edges=np.array([[0, 1]]),
        legal_poses=np.zeros((0, 3)),
        region=(0.0, 0.0, 10.0, 8.0),
    )
    assert map_bounds(graph) == (0.0, 0.0, 10.0, 8.0)
    state = make_state(robot=(3.0, 1.0, 0.0), humans=((1.0, 1.0),), mask=(True,))
    with_graph = FrameRenderer(graph, width=WIDTH, height=HEIGHT, view="map", show_graph=True).render(state)
    without = FrameRenderer(graph, width=WIDTH, height=HEIGHT, view="map").render(state)
    renderer = FrameRenderer(graph, width=WIDTH, height=HEIGHT, view="map")
    mid = pixel(renderer, (5.0, 4.0))
    assert close_to(color_at(with_graph, mid), frames.GRAPH_EDGE, tol=40)
    assert close_to(color_at(without, mid), frames.BACKGROUND, tol=5)


def test_follow_view_far_from_origin_uses_tiles():
    """A robot at negative and large coordinates still renders (tiles are made on demand)."""
    renderer = FrameRenderer(room(), width=WIDTH, height=HEIGHT, view="follow")
    for robot in ((-30.0, -20.0, 0.0), (0.0, 4.0, 0.0), (200.0, 150.0, 2.0)):
        frame = renderer.render(make_state(robot=robot))
        assert close_to(color_at(frame, pixel(renderer, robot_body(*robot), robot[:2])), frames.ROBOT)


def test_human_window_with_agg():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    window = HumanWindow(title="test")
    assert window.is_open
    window.show(np.zeros((HEIGHT, WIDTH, 3), np.uint8))
    window.show(np.full((HEIGHT, WIDTH, 3), 255, np.uint8))
    window.close()
    assert not window.is_open
    with pytest.raises(RuntimeError):
        window.show(np.zeros((HEIGHT, WIDTH, 3), np.uint8))


def test_two_windows_of_one_title_are_open_at_once():
    """Two envs with render_mode="human" in one process (two policies side by side, an env and its
    copy) each get a window: the second used to raise matplotlib's "Figure 'socialzoo' already exists"."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    first, second = HumanWindow(), HumanWindow()
    assert first.is_open and second.is_open and first.fig is not second.fig
    first.show(np.zeros((HEIGHT, WIDTH, 3), np.uint8))
    second.show(np.full((HEIGHT, WIDTH, 3), 255, np.uint8))
    first.close()
    assert not first.is_open and second.is_open
    second.show(np.zeros((HEIGHT, WIDTH, 3), np.uint8))
    second.close()


def test_import_does_not_load_matplotlib():
    code = (
        "import sys, socialzoo.render.frames, socialzoo.render.animation; print('matplotlib' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
