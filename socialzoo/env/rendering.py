"""Rendering of a task's row: the frame renderer plus the overlay the task knows about."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from socialzoo.render.frames import HumanWindow


class CoreRenderer:
    """Draws one row of a task's core (a map's world), for render_mode "rgb_array" or "human".

    Kept apart from the envs so that stepping never pays for drawing; the renderer is built on the
    first render() call only.

    Args:
        task: the task (socialzoo.env.tasks) whose core has a map.
        render_mode: "rgb_array" or "human".
        view: "follow" (centred on the robot) or "map" (the whole map).
        width: frame width, pixels.
        height: frame height, pixels.
        info: text lines shown on every frame under the action and time, e.g. the policy's name.
        world_map: the map drawn (default the core's; a task in the open gives one without walls).
    """

    def __init__(
        self,
        task: Any,
        render_mode: str,
        view: str = "follow",
        *,
        width: int = 640,
        height: int = 480,
        info: tuple[str, ...] = (),
        world_map: Any = None,
    ) -> None:
        from socialzoo.render.frames import FrameRenderer

        if render_mode not in ("rgb_array", "human"):
            raise ValueError(f"render_mode must be 'rgb_array' or 'human', got {render_mode!r}")
        self.task = task
        world = task.core.world
        self.render_mode = render_mode
        self.info = tuple(info)
        self.frames = FrameRenderer(
            task.core.map if world_map is None else world_map,
            width=width,
            height=height,
            view=view,  # type: ignore[arg-type]
            robot_config=world.robot,
            human_radius=world.human.radius,
            dt=world.dt,
        )
        self.window: HumanWindow | None = None

    def __getstate__(self) -> dict[str, Any]:
        """The renderer without its window (pyplot and an open figure do not pickle): a copy or
        an unpickled renderer opens a window of its own at its next frame."""
        return {**self.__dict__, "window": None}

    def reset(self) -> None:
        """Forget trails (a new episode)."""
        self.frames.reset()

    def frame(self, row: int = 0, robot: int = 0) -> np.ndarray:
        """(H, W, 3) uint8 frame of `row`, following robot `robot`.

        The overlay shows the robot's global path and carrot (where the core has a navigator), the
        human it follows or passes (the task's `target_human`, where it has one) and the action it
        chose last (Task.action_name; none before its first step).
        """
        from socialzoo.render.frames import Overlay

        task, core = self.task, self.task.core
        navigator = core.navigator
        path = carrot = None
        if navigator is not None:
            path = navigator.plans.paths[row, robot, : int(navigator.plans.lengths[row, robot])]
            carrot = core.carrot[row, robot]
        target = getattr(task, "target_human", None)
        highlight = None if target is None or target[row, robot] < 0 else int(target[row, robot])
        action = task.action_name(row, robot) if core.state.step_count[row] > 0 else None
        overlay = Overlay(path=path, carrot=carrot, action=action, highlight=highlight, info=self.info)
        return self.frames.render(core.state, row=row, robot=robot, overlay=overlay)

    def render(self, row: int = 0, robot: int = 0) -> np.ndarray | None:
        """The frame (rgb_array) or None after showing it in a window (human)."""
        frame = self.frame(row, robot)
        if self.render_mode == "rgb_array":
            return frame
        from socialzoo.render.frames import HumanWindow

        if self.window is None:
            # One frame per step of the task, which may be several physics steps (CrowdNav's substeps).
            self.window = HumanWindow(fps=self.task.frames_per_second)
        self.window.show(frame)
        return None

    def close(self) -> None:
        """Close the window, if one was opened."""
        if self.window is not None:
            self.window.close()
            self.window = None
