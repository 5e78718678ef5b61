"""ConcatVectorEnv: parts on different maps as one VectorEnv (and one SB3 VecEnv)."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.env.concat_vector import ConcatVectorEnv
from socialzoo.env.vector import TaskVectorEnv


def _parts(sizes=(2, 3)):
    families = (("hallway", "hallway_head_on"), ("intersection", "crossing"))
    return [
        TaskVectorEnv(n, task="action_selection", map=m, family=f, max_steps=200)
        for n, (m, f) in zip(sizes, families, strict=True)
    ]


def test_rows_are_the_parts_rows_end_to_end_and_episodes_end_in_each_part():
    venv = ConcatVectorEnv(_parts())
    obs, info = venv.reset(seed=3)
    assert obs.shape == (5, venv.single_observation_space.shape[0])
    assert info["scenario_seed"].shape == (5,)
    ended = np.zeros(5, dtype=bool)
    for _ in range(260):
        obs, reward, terminated, truncated, info = venv.step(np.zeros(5, dtype=np.int64))
        assert obs.shape[0] == reward.shape[0] == terminated.shape[0] == 5
        done = terminated | truncated
        if done.any():
            assert info["_final_obs"].tolist() == done.tolist()
            assert set(np.flatnonzero(info["final_info"]["_metrics"])) == set(np.flatnonzero(done))
        ended |= done
    assert ended.all()  # every row of both maps ended an episode (max_steps 200)


def test_the_same_seed_gives_the_same_rollout():
    def roll():
        venv = ConcatVectorEnv(_parts())
        obs, _ = venv.reset(seed=11)
        out = [obs]
        for _ in range(30):
            out.append(venv.step(np.ones(5, dtype=np.int64))[0])
        return np.stack(out)

    assert np.array_equal(roll(), roll())


def test_a_reset_mask_resets_each_parts_own_rows():
    """options["reset_mask"] names rows of the whole env: each part resets its slice of it (a part
    with no masked row is left as it is), as Gymnasium's vector envs take the mask. Every part
    refused the whole (5,) mask before."""
    venv, alone = ConcatVectorEnv(_parts()), ConcatVectorEnv(_parts())
    venv.reset(seed=3)
    alone.reset(seed=3)
    for _ in range(5):
        obs = venv.step(np.ones(5, dtype=np.int64))[0]
        alone.step(np.ones(5, dtype=np.int64))
    mask = np.array([False, False, False, True, False])  # one row of part 1, none of part 0
    new_obs, info = venv.reset(seed=8, options={"reset_mask": mask})
    part_obs, part_info = alone.parts[1].reset(seed=alone_seed(8, 1), options={"reset_mask": mask[2:]})
    assert np.array_equal(new_obs[:2], obs[:2])  # part 0 untouched
    assert np.array_equal(new_obs[2:], part_obs)
    assert info["scenario_seed"].tolist() == [0, 0, *part_info["scenario_seed"].tolist()]
    assert not np.array_equal(new_obs[3], obs[3]) and np.array_equal(new_obs[[2, 4]], obs[[2, 4]])
    with pytest.raises(ValueError, match=r"ConcatVectorEnv: options\['reset_mask'\] must be 5 bools"):
        venv.reset(options={"reset_mask": np.array([3])})
    with pytest.raises(RuntimeError, match="first reset"):
        ConcatVectorEnv(_parts()).reset(options={"reset_mask": mask})


def test_fixed_cases_are_one_per_row_end_to_end():
    """options {"split": NAME, "cases": [one per reset row]} (TaskVectorEnv's, and SB3VecEnv's
    set_options) give each part its own rows' cases, from its own split; with a reset_mask, one
    case per masked row. Every part was given the whole list and refused it before."""
    venv = ConcatVectorEnv(_parts())
    obs, info = venv.reset(options={"split": "val", "cases": [4, 5, 6, 7, 8]})
    first = _parts()
    expected = [
        part.reset(options={"split": "val", "cases": c})
        for part, c in zip(first, ([4, 5], [6, 7, 8]), strict=True)
    ]
    assert np.array_equal(obs, np.concatenate([o for o, _ in expected]))
    assert info["scenario_seed"].tolist() == [s for _, i in expected for s in i["scenario_seed"].tolist()]
    mask = np.array([False, True, True, False, False])
    obs, info = venv.reset(options={"split": "val", "cases": [1, 2], "reset_mask": mask})
    part_0 = first[0].reset(options={"split": "val", "cases": [1], "reset_mask": mask[:2]})[0]
    part_1 = first[1].reset(options={"split": "val", "cases": [2], "reset_mask": mask[2:]})[0]
    assert np.array_equal(obs, np.concatenate([part_0, part_1]))
    with pytest.raises(ValueError, match="ConcatVectorEnv: 5 rows to reset but 3 cases"):
        venv.reset(options={"split": "val", "cases": [0, 1, 2]})


def alone_seed(seed: int, part: int) -> int:
    """The seed ConcatVectorEnv gives part `part` for `seed`."""
    return int(np.random.SeedSequence([seed, part]).generate_state(1)[0])


def test_bad_actions_are_refused_before_any_part_steps():
    """A batch of another row count, or a bad action in a later part's rows, raises naming
    ConcatVectorEnv before any part steps. Extra rows were dropped silently, and a NaN in part 1's
    rows raised from part 1 after part 0 had stepped, so the parts' episodes fell out of step."""
    venv = ConcatVectorEnv(
        [TaskVectorEnv(n, task="crowdnav", variant=v) for n, v in ((2, ""), (1, "Square"))]
    )
    venv.reset(seed=0)
    before = [part.core.state.copy() for part in venv.parts]
    bad_batches = {
        r"actions must have shape \(3, 2\), got \(4, 2\)": np.zeros((4, 2)),
        r"action nan at \(2, 0\) is not a finite number in \[-1.0, 1.0\]": np.array(
            [[0, 0], [0, 0], [np.nan, 0]]
        ),
        r"action 2.0 at \(1, 1\)": np.array([[0, 0], [0, 2.0], [0, 0]]),
    }
    for match, actions in bad_batches.items():
        with pytest.raises(ValueError, match="ConcatVectorEnv: " + match):
            venv.step(actions)
    for part, state in zip(venv.parts, before, strict=True):
        np.testing.assert_array_equal(part.core.state.robot_pose, state.robot_pose)
        assert int(part.core.state.step_count[0]) == int(state.step_count[0])


def test_it_renders_every_parts_rows_as_a_vector_env_does():
    """render() gives every row's frame, the parts' in row order (a tuple of num_envs frames, as
    Gymnasium's vector envs and TaskVectorEnv give them); None when the parts draw nothing.
    It raised NotImplementedError (Gymnasium's VectorEnv.render) whatever the parts' render_mode."""
    parts = [
        TaskVectorEnv(n, task="crowdnav", variant=v, render_mode="rgb_array")
        for n, v in ((2, ""), (1, "Square"))
    ]
    venv = ConcatVectorEnv(parts)
    assert venv.render_mode == "rgb_array" and venv.metadata["render_fps"] == parts[0].metadata["render_fps"]
    venv.reset(seed=0)
    venv.step(np.zeros((3, 2)))
    frames = venv.render()
    assert isinstance(frames, tuple) and len(frames) == 3
    expected = [
        parts[0].draw("rgb_array", row=0),
        parts[0].draw("rgb_array", row=1),
        parts[1].draw("rgb_array"),
    ]
    assert all(np.array_equal(f, e) for f, e in zip(frames, expected, strict=True))
    silent = ConcatVectorEnv([TaskVectorEnv(1, task="crowdnav")])
    assert silent.render_mode is None and silent.render() is None
    with pytest.raises(ValueError, match="part 1's render_mode None differs from part 0's 'rgb_array'"):
        ConcatVectorEnv([parts[0], TaskVectorEnv(1, task="crowdnav")])


def test_parts_whose_spaces_differ_are_refused():
    other = TaskVectorEnv(1, task="crowdnav")
    with pytest.raises(ValueError, match="part 1's observation space"):
        ConcatVectorEnv([_parts((1, 1))[0], other])
    with pytest.raises(ValueError, match="at least one part"):
        ConcatVectorEnv([])


def test_sb3_trains_on_it():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    from socialzoo.env.sb3_vec import SB3VecEnv
    from socialzoo.train.sb3_common import quiet_logger

    venv = ConcatVectorEnv(_parts())
    model = PPO("MlpPolicy", SB3VecEnv(venv.num_envs, vector_env=venv), n_steps=16, batch_size=40, seed=0)
    model.set_logger(quiet_logger())  # SB3's own logger leaves an empty /tmp/SB3-<date> folder
    model.learn(80)
