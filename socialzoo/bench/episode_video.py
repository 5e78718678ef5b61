"""One episode of a policy in any task, animated with the task's renderer (Task.make_renderer, the envs'):
the `socialzoo demo` command and the quick benchmark's GIF."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.episode_play import episode_outcome, play_episode, step_seconds


@dataclass(frozen=True)
class EpisodeVideo:
    """What `animate_episode` wrote.

    Attributes:
        path: the GIF or MP4 file.
        frames: frames written.
        steps: the steps played.
        seconds: the simulated time played, s.
        outcome: how robot 0's episode ended (socialzoo.bench.replay.episode_outcome), or "not over"
            when the animation stopped at its longest first.
        metrics: the episode's metrics (its task's episode_metrics; those so far if not over).
    """

    path: Path
    frames: int
    steps: int
    seconds: float
    outcome: str
    metrics: dict[str, Any]


def animate_episode(
    path: str | Path,
    task: Any,
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
    """Run `policy` on row 0 of a task of one row (any task, already reset: see
    socialzoo.bench.episode_play.scenario_task and socialzoo.bench.replay.case_task) and write the animation.

    One frame every `stride` steps and one of the episode's last state (at the action-selection task's
    defaults 100 ms of simulated time per frame, played at twice real time); the animation stops after
    `max_frames` frames if the episode has not ended. `human_policy` drives the task's learned-human
    agents (socialzoo.bench.episode_play.play_episode).
    """
    from socialzoo.render.animation import write_animation

    renderer = task.make_renderer(
        "rgb_array", view, width=size[0], height=size[1], info=(label,) if label else ()
    )
    played = _Played()

    def frames() -> Iterator[np.ndarray]:
        yield renderer.render(0)
        played.frames = 1
        if max_frames <= 1:
            return
        for _, step, ended in play_episode(task, policy, human_policy):
            played.steps += 1
            if played.steps % stride == 0 or ended:
                played.frames += 1
                yield renderer.render(0)
            if ended:
                metrics = task.episode_metrics(np.zeros(1, dtype=np.intp))[0]
                played.outcome = episode_outcome(metrics, step)
            elif played.frames >= max_frames:
                return

    written = write_animation(frames(), path, fps=fps)
    return EpisodeVideo(
        path=Path(written),
        frames=played.frames,
        steps=played.steps,
        seconds=played.steps * step_seconds(task),
        outcome=played.outcome,
        metrics=task.episode_metrics(np.zeros(1, dtype=np.intp))[0],
    )


@dataclass
class _Played:
    """What the animation's frames played so far."""

    frames: int = 0
    steps: int = 0
    outcome: str = "not over"
