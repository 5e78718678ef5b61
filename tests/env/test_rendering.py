"""CoreRenderer: the one renderer of a task's row (envs' render() and the episode videos)."""

import numpy as np
import pytest

from socialzoo.env.gym_env import ActionSelectionEnv
from socialzoo.env.rendering import CoreRenderer
from socialzoo.nav.subpolicies import ACTION_NAMES

pytest.importorskip("PIL")


def _overlays(renderer):
    """Record the overlay of every frame the renderer draws."""
    seen = []
    draw = renderer.frames.render

    def spy(state, **kwargs):
        seen.append(kwargs["overlay"])
        return draw(state, **kwargs)

    renderer.frames.render = spy
    return seen


def test_size_info_and_the_last_action():
    env = ActionSelectionEnv(map="open_room", max_steps=10)
    env.reset(seed=0)
    task = env.unwrapped.task
    renderer = CoreRenderer(task, "rgb_array", width=320, height=200, info=("Ref",))
    overlays = _overlays(renderer)
    first = renderer.frame(0)
    assert first.shape == (200, 320, 3) and first.dtype == np.uint8
    env.step(1)
    renderer.frame(0)
    # No action has been chosen before the first step; after it, the one chosen (Halt).
    assert [o.action for o in overlays] == [None, ACTION_NAMES[1]]
    assert all(o.info == ("Ref",) for o in overlays)
    labelled = CoreRenderer(task, "rgb_array", width=320, height=200, info=("Ref",)).frame(0)
    plain = CoreRenderer(task, "rgb_array", width=320, height=200).frame(0)
    assert not np.array_equal(plain, labelled)  # the info line is drawn


def test_bad_render_mode_is_refused():
    env = ActionSelectionEnv(map="open_room", max_steps=10)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="render_mode must be 'rgb_array' or 'human', got 'ansi'"):
        CoreRenderer(env.unwrapped.task, "ansi")
