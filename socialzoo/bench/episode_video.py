"""One episode of a policy, animated: the `socialzoo demo` command and the quick benchmark's GIF."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.env.config import EnvConfig
from socialzoo.nav.scenarios import Scenario


@dataclass(frozen=True)
class EpisodeVideo:
    """What `animate_episode` wrote.

    Attributes:
        path: the GIF or MP4 file.
        frames: frames written.
        metrics: the episode's metrics (socialzoo.env.metrics.SUMMARY_KEYS).
    """

    path: Path
    frames: int
    metrics: dict[str, Any]


def animate_episode(
    path: str | Path,
    env_config: EnvConfig,
    scenario: Scenario,
    policy: Any,
    *,
    label: str = "",
    view: str = "follow",
    stride: int = 4,
    fps: float = 20.0,
    max_frames: int = 600,
    size: tuple[int, int] = (480, 360),
) -> EpisodeVideo:
    """Run `policy` (a socialzoo.agents Policy) on one scenario and write the animation.

    One frame every `stride` steps (at the defaults 100 ms of simulated time per frame, played at
    twice real time); the episode stops after `max_frames` frames if it has not ended.
    """
    from socialzoo.env.core import SocialNavCore
    from socialzoo.nav.subpolicies import ACTION_NAMES
    from socialzoo.render.animation import write_animation
    from socialzoo.render.frames import FrameRenderer, Overlay

    core = SocialNavCore(env_config, 1)
    core.reset_rows(np.array([0]), [scenario])
    renderer = FrameRenderer(
        core.map,
        width=size[0],
        height=size[1],
        view=view,  # type: ignore[arg-type]
        robot_config=env_config.world.robot,
        human_radius=env_config.world.human.radius,
        dt=env_config.dt,
    )
    count = 0

    def frame(action: str | None) -> np.ndarray:
        assert core.state is not None
        target = int(core.target_human[0, 0])
        plans = core.navigator.plans
        overlay = Overlay(
            path=plans.paths[0, 0, : int(plans.lengths[0, 0])],
            carrot=core.carrot[0, 0],
            action=action,
            highlight=target if target >= 0 else None,
            info=(label,) if label else (),
        )
        return renderer.render(core.state, row=0, overlay=overlay)

    def frames() -> Iterator[np.ndarray]:
        nonlocal count
        yield frame(None)
        count, step = 1, 0
        while not core.done.all() and count < max_frames:
            action = np.asarray(policy.act(core.obs, core)).reshape(core.done.shape)
            core.step(action)
            step += 1
            if step % stride == 0 or core.done.all():
                count += 1
                name = ACTION_NAMES[int(action[0, 0])] if env_config.robot_action == "subpolicy" else None
                yield frame(name)

    written = write_animation(frames(), path, fps=fps)
    return EpisodeVideo(path=Path(written), frames=count, metrics=core.episode_summaries([0])[0])
