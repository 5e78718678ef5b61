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


@pytest.mark.parametrize(
    "env_id", ["socialzoo/CrowdNav-v1", "socialzoo/CrowdNav20-v1", "socialzoo/CrowdNavWalls-v1"]
)
def test_the_crowdnav_task_renders(env_id):
    # The CrowdNav ids refused every render_mode: the arena has no map for the frame renderer.
    import gymnasium as gym

    from socialzoo.render.frames import ROBOT

    env = gym.make(env_id, render_mode="rgb_array")
    assert env.unwrapped.metadata["render_modes"] == ["human", "rgb_array"]
    env.reset(seed=0)
    env.step(env.action_space.sample())
    frame = env.render()
    assert frame.shape == (480, 640, 3) and frame.dtype == np.uint8
    # The follow view is centred on the robot, drawn as its disc (radius 0.3 m) in the robot's colour
    # beside its heading chevron: a ring of pixels halfway out from the centre.
    radius = 0.3 * 480 / 16.0  # pixels: the view shows +-8 m along its shorter side
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    ring = np.stack((240 + 0.7 * radius * np.sin(angles), 320 + 0.7 * radius * np.cos(angles)), -1)
    colours = frame[ring[:, 0].round().astype(int), ring[:, 1].round().astype(int)]
    assert (np.abs(colours.astype(int) - ROBOT).max(-1) < 40).mean() > 0.5
    # The map view of the open arena shows the cases' circle with 1 m to spare.
    task = env.unwrapped.task
    if task.core.map is None:
        frames = task.make_renderer("rgb_array", view="map").frames
        reach = task.config.cases.circle_radius + 1.0
        assert frames.map.region == (-reach, -reach, reach, reach) and len(frames.map.walls) == 0
    env.close()


@pytest.mark.parametrize("task", ["action_selection", "crowdnav"])
def test_a_vector_env_renders_every_row_as_gymnasium_vector_envs_do(task):
    """Gymnasium's VectorEnv.render gives one frame per env (its vector RecordVideo asserts a
    sequence of num_envs frames); the task's vector env rendered row 0's frame alone."""
    from collections.abc import Sequence

    from socialzoo.env.vector import TaskVectorEnv

    env = TaskVectorEnv(
        3, render_mode="rgb_array", task=task, **({"map": "open_room"} if task != "crowdnav" else {})
    )
    env.reset(seed=0)
    env.step(env.action_space.sample())
    frames = env.render()
    assert isinstance(frames, Sequence) and len(frames) == env.num_envs
    for k, frame in enumerate(frames):
        assert frame.shape == (480, 640, 3) and frame.dtype == np.uint8
        assert np.array_equal(frame, env.draw("rgb_array", row=k))
    assert not np.array_equal(frames[0], frames[1])  # each row's own world
    assert TaskVectorEnv(2, task=task).render() is None


@pytest.mark.parametrize(
    ("env_id", "overrides", "fps"),
    [
        ("socialzoo/CrowdNavWalls-v1", {}, 4.0),  # 0.25 s steps of 10 physics substeps each
        ("socialzoo/CrowdNav-v1", {"time_step": 0.1}, 10.0),
        ("socialzoo/ActionSelection-v2", {"map": "open_room"}, 40.0),
        ("socialzoo/ActionSelection-v2", {"map": "open_room", "world": {"dt": 0.05}}, 20.0),
    ],
)
def test_frames_come_at_the_pace_of_the_tasks_step(env_id, overrides, fps):
    """render_mode "human" shows a frame per step for one step's simulated time, and the adapters'
    metadata["render_fps"] (which Gymnasium's RecordVideo writes videos at) is one frame per step.
    The window paced frames by the physics step (40 fps for 0.25 s steps of 10 substeps: 10x too
    fast) and the metadata kept CrowdNav's default 4 whatever its time_step."""
    import gymnasium as gym
    import matplotlib

    from socialzoo.env.parallel import TaskParallelEnv
    from socialzoo.env.vector import TaskVectorEnv

    matplotlib.use("Agg")
    env = gym.make(env_id, render_mode="human", **overrides)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    assert env.unwrapped._renderer.window.fps == pytest.approx(fps)
    assert env.metadata["render_fps"] == pytest.approx(fps)
    env.close()
    kwargs = {**gym.spec(env_id).kwargs, **overrides}
    assert TaskVectorEnv(1, **kwargs).metadata["render_fps"] == pytest.approx(fps)
    assert TaskParallelEnv(**kwargs).metadata["render_fps"] == pytest.approx(fps)


def test_an_env_showing_a_window_can_be_copied_and_pickled():
    """copy.deepcopy or pickle of an env whose "human" window is open (a lookahead copy, a
    snapshot) raised "cannot pickle 'module' object" (the window's pyplot and figure); the copy
    now opens a window of its own at its next frame and the original keeps its."""
    import copy
    import pickle

    import gymnasium as gym
    import matplotlib

    matplotlib.use("Agg")
    env = gym.make("socialzoo/CrowdNav-v1", render_mode="human")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    window = env.unwrapped._renderer.window
    for twin in (copy.deepcopy(env), pickle.loads(pickle.dumps(env))):
        twin.step(twin.action_space.sample())
        assert twin.unwrapped._renderer.window.is_open and twin.unwrapped._renderer.window is not window
        twin.close()
    assert window.is_open
    env.close()


@pytest.mark.parametrize("task", ["action_selection", "crowdnav"])
def test_rendering_before_the_first_reset_says_to_reset(task):
    """render() before reset() raised AttributeError "'NoneType' object has no attribute
    'step_count'" from the renderer (TaskVectorEnv, which gymnasium.make_vec does not wrap, and the
    unwrapped TaskEnv); it now says to reset first, as the ParallelEnv did."""
    from socialzoo.env.gym_env import TaskEnv
    from socialzoo.env.vector import TaskVectorEnv

    for env in (
        TaskVectorEnv(2, task=task, render_mode="rgb_array"),
        TaskEnv(task=task, render_mode="rgb_array"),
    ):
        with pytest.raises(RuntimeError, match=f"{type(env).__name__}: call reset\\(\\) before render\\(\\)"):
            env.render()


def test_the_map_view_of_a_recorded_scene_shows_where_its_people_and_robot_are(tmp_path, monkeypatch):
    """The CrowdNav task's map view in the open showed 5 m around the origin for any family: a
    recorded scene far from the origin (real scenes' coordinates are the camera's) was off the
    picture. It now shows the rows' scenarios: robots' starts and goals, people's routes."""
    from socialzoo.data.tracks import Recording, Track
    from socialzoo.env.tasks.crowdnav import CrowdNavTask
    from socialzoo.scenarios.catalogue import register_family
    from socialzoo.scenarios.recorded import RecordedScene

    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))
    walkers = [Track(p, 3 * p, np.linspace([40.0 + p, 20.0], [48.0 - p, 30.0], 30)) for p in range(4)]
    register_family(
        RecordedScene(Recording(name="far", dt=0.4, num_frames=40, tracks=tuple(walkers), source="test"))
    )
    task = CrowdNavTask(None, 2, family="recorded_far")
    task.reset(np.arange(2), {})
    x0, y0, x1, y1 = task.make_renderer("rgb_array", view="map").frames.map.region
    state = task.core.state
    for points in (state.robot_pose[..., :2], state.robot_goal[..., :2], state.human_pos[state.human_mask]):
        xy = points.reshape(-1, 2)
        assert ((xy[:, 0] > x0) & (xy[:, 0] < x1) & (xy[:, 1] > y0) & (xy[:, 1] < y1)).all()
    assert x0 > 30.0 and y0 > 10.0  # the scene, not the origin
