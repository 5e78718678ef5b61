"""Rendering of an env core's row: the frame renderer plus the overlay the env knows about.

Kept apart from the envs so that stepping never pays for drawing; the renderer is built on the
first render() call only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from socialzoo.nav.subpolicies import ACTION_NAMES

if TYPE_CHECKING:
    from socialzoo.env.core import SocialNavCore


class CoreRenderer:
    """Draws one row of a SocialNavCore, for render_mode "rgb_array" or "human".

    Args:
        core: the env core.
        render_mode: "rgb_array" or "human".
        view: "follow" (centred on the robot) or "map" (the whole map).
        width: frame width, pixels.
        height: frame height, pixels.
        info: text lines shown on every frame under the action and time, e.g. the policy's name.
    """

    def __init__(
        self,
        core: SocialNavCore,
        render_mode: str,
        view: str = "follow",
        *,
        width: int = 640,
        height: int = 480,
        info: tuple[str, ...] = (),
    ) -> None:
        from socialzoo.render.frames import FrameRenderer

        if render_mode not in ("rgb_array", "human"):
            raise ValueError(f"render_mode must be 'rgb_array' or 'human', got {render_mode!r}")
        self.core = core
        self.render_mode = render_mode
        self.info = tuple(info)
        self.frames = FrameRenderer(
            core.map,
            width=width,
            height=height,
            view=view,  # type: ignore[arg-type]
            robot_config=core.config.world.robot,
            human_radius=core.config.world.human.radius,
            dt=core.config.dt,
        )
        self.window = None

    def reset(self) -> None:
        """Forget trails (a new episode)."""
        self.frames.reset()

    def frame(self, row: int = 0, robot: int = 0) -> np.ndarray:
        """(H, W, 3) uint8 frame of `row`, following robot `robot`.

        The overlay shows the robot's global path, carrot and the human it follows or passes, and
        (sub-policy actions) the action it chose last; no action before its first step.
        """
        from socialzoo.render.frames import Overlay

        core = self.core
        assert core.state is not None
        plans = core.navigator.plans
        length = int(plans.lengths[row, robot])
        target = int(core.target_human[row, robot])
        action = None
        if core.config.robot_action == "subpolicy" and core.state.step_count[row] > 0:
            action = ACTION_NAMES[int(core.prev_action[row, robot])]
        overlay = Overlay(
            path=plans.paths[row, robot, :length],
            carrot=core.carrot[row, robot],
            action=action,
            highlight=target if target >= 0 else None,
            info=self.info,
        )
        return self.frames.render(core.state, row=row, robot=robot, overlay=overlay)

    def render(self, row: int = 0, robot: int = 0) -> np.ndarray | None:
        """The frame (rgb_array) or None after showing it in a window (human)."""
        frame = self.frame(row, robot)
        if self.render_mode == "rgb_array":
            return frame
        from socialzoo.render.frames import HumanWindow

        if self.window is None:
            self.window = HumanWindow(fps=1.0 / self.core.config.dt)
        self.window.show(frame)
        return None

    def close(self) -> None:
        """Close the window, if one was opened."""
        if self.window is not None:
            self.window.close()
            self.window = None
