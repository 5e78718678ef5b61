"""Frame rendering speed: FrameRenderer frames/s at 640x480 on gdc1 with 25 humans, both views.

The states come from a real rollout (humans walking their routes, the robot pure-pursuing its
global path); each frame carries the full overlay (path, carrot, goal, 180-ray laser scan, action
label, highlighted human). Prints frames/s; --png DIR saves the last frame of each view, --gif PATH
also writes and times an animation; --json prints one JSON object per view (name, width, height,
antialias, frames, frames_per_s, and with --gif the follow view's gif_frames, gif_s, gif_mib).

Run: python benchmarks/render_speed.py [--steps 600] [--antialias 2] [--png DIR] [--gif PATH] [--json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from _common import positive_int

from socialzoo.core.config import LaserConfig, WorldConfig
from socialzoo.core.laser import laser_scan
from socialzoo.env.world import step_world
from socialzoo.maps.map_file import load_map
from socialzoo.nav.graph import NavGraph
from socialzoo.render.frames import FrameRenderer, Overlay
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.start_state import scenarios_to_state

HUMANS = 25
ACTIONS = ("GoAlone", "Follow", "Pass", "Halt")


def carrot_on(path: np.ndarray, position: np.ndarray, lookahead: float) -> np.ndarray:
    """The point `lookahead` metres further along `path` than its point closest to `position`."""
    seg = np.diff(path, axis=0)
    length = np.linalg.norm(seg, axis=1)
    t = np.clip(np.einsum("ij,ij->i", position - path[:-1], seg) / np.maximum(length**2, 1e-12), 0, 1)
    dist = np.linalg.norm(path[:-1] + t[:, None] * seg - position, axis=1)
    k = int(np.argmin(dist))
    along = np.concatenate(([0.0], np.cumsum(length)))
    target = along[k] + t[k] * length[k] + lookahead
    j = int(np.clip(np.searchsorted(along, target) - 1, 0, len(seg) - 1))
    u = np.clip((target - along[j]) / max(length[j], 1e-12), 0, 1)
    return path[j] + u * seg[j]


def rollout(num_steps: int, map_name: str = "gdc1", seed: int = 0):
    """States and overlays of one robot pure-pursuing its global path among 25 humans."""
    m = load_map(map_name)
    state = scenarios_to_state(
        [generate_scenario(m, seed, ScenarioConfig(min_humans=HUMANS, max_humans=HUMANS))]
    )
    world = WorldConfig()
    laser = LaserConfig()
    path = NavGraph.from_map(m).plan(state.robot_pose[0, 0, :2], state.robot_goal[0, 0, :2])
    states, overlays = [], []
    for step in range(num_steps):
        pose = state.robot_pose[0, 0]
        carrot = carrot_on(path, pose[:2], 1.5)
        error = np.arctan2(carrot[1] - pose[1], carrot[0] - pose[0]) - pose[2]
        error = (error + np.pi) % (2 * np.pi) - np.pi
        command = np.array([[[1.0 * max(0.0, np.cos(error)), np.clip(2.0 * error, -1.5, 1.5)]]])
        ranges = laser_scan(state, m.wall_index, laser, world.human.radius)[0, 0]
        dist = np.linalg.norm(state.human_pos[0] - pose[:2], axis=1)
        nearest = int(np.argmin(np.where(state.human_mask[0], dist, np.inf)))
        overlays.append(
            Overlay(
                path=path,
                carrot=carrot,
                laser_ranges=ranges,
                laser=laser,
                action=ACTIONS[(step // 100) % len(ACTIONS)],
                highlight=nearest,
            )
        )
        states.append(state)
        state, _ = step_world(state, m.wall_index, world, command)
    return m, states, overlays


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--steps", type=positive_int, default=600, help="rollout length whose frames are rendered")
    p.add_argument("--map", default="gdc1")
    p.add_argument("--antialias", type=positive_int, default=2)
    p.add_argument("--png", type=Path, default=None, help="directory for the last frame of each view")
    p.add_argument("--gif", type=Path, default=None, help="also write a GIF of the follow view here")
    p.add_argument("--json", action="store_true", help="print one JSON object per view")
    args = p.parse_args()
    m, states, overlays = rollout(args.steps, args.map)
    for view in ("follow", "map"):
        renderer = FrameRenderer(m, width=640, height=480, view=view, antialias=args.antialias)
        renderer.render(states[0], overlay=overlays[0])  # draws the static background once
        renderer.reset()
        start = time.perf_counter()
        frames = [renderer.render(s, overlay=o) for s, o in zip(states, overlays, strict=True)]
        elapsed = time.perf_counter() - start
        name = f"{view} 640x480 antialias={args.antialias}"
        figure = {"name": name, "width": 640, "height": 480, "antialias": args.antialias}
        figure.update(frames=len(frames), frames_per_s=len(frames) / elapsed)
        if not args.json:
            print(f"{view:<7} 640x480 antialias={args.antialias}: {figure['frames_per_s']:8.1f} frames/s")
        if args.png is not None:
            from PIL import Image

            args.png.mkdir(parents=True, exist_ok=True)
            Image.fromarray(frames[-1]).save(args.png / f"render_{view}.png")
        if args.gif is not None and view == "follow":
            from socialzoo.render.animation import write_animation

            start = time.perf_counter()
            write_animation(frames, args.gif, fps=20, stride=2)
            elapsed = time.perf_counter() - start
            figure.update(gif_frames=len(frames[::2]), gif_s=elapsed, gif_mib=args.gif.stat().st_size / 2**20)
            if not args.json:
                # 3 significant digits: a short run's GIF (22 KiB at --steps 5) printed as "0.0 MiB".
                print(f"GIF of {figure['gif_frames']} frames: {elapsed:.3g} s, {figure['gif_mib']:.3g} MiB")
        if args.json:
            print(json.dumps(figure), flush=True)


if __name__ == "__main__":
    main()
