"""One episode of a policy, animated with the envs' renderer (socialzoo.env.rendering.CoreRenderer):
the `socialzoo demo` command and the quick benchmark's GIF."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.env.config import EnvConfig
from socialzoo.scenarios.scenario import Scenario


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
    human_policy: Any = None,
) -> EpisodeVideo:
    """Run `policy` (a socialzoo.agents Policy) on one scenario and write the animation.

    One frame every `stride` steps (at the defaults 100 ms of simulated time per frame, played at
    twice real time); the episode stops after `max_frames` frames if it has not ended.
    `human_policy` (socialzoo.env.human_policy.LearnedHumanPolicy) drives the env config's
    learned human slots.
    """
    from socialzoo.env.rendering import CoreRenderer
    from socialzoo.env.tasks.action_selection import ActionSelectionTask
    from socialzoo.render.animation import write_animation

    task = ActionSelectionTask(env_config, 1)
    task.reset_rows(np.array([0]), [scenario])
    renderer = CoreRenderer(
        task, "rgb_array", view, width=size[0], height=size[1], info=(label,) if label else ()
    )
    count = 0

    def frames() -> Iterator[np.ndarray]:
        nonlocal count
        yield renderer.frame(0)
        count, step = 1, 0
        while not task.core.done.all() and count < max_frames:
            action = np.asarray(policy.act(task.obs, task)).reshape(task.core.done.shape)
            task.step(action, None if human_policy is None else human_policy.act(task.human_obs))
            step += 1
            if step % stride == 0 or task.core.done.all():
                count += 1
                yield renderer.frame(0)

    written = write_animation(frames(), path, fps=fps)
    return EpisodeVideo(
        path=Path(written), frames=count, metrics=task.episode_metrics(np.zeros(1, dtype=np.intp))[0]
    )
