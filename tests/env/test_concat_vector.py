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

    venv = ConcatVectorEnv(_parts())
    model = PPO("MlpPolicy", SB3VecEnv(venv.num_envs, vector_env=venv), n_steps=16, batch_size=40, seed=0)
    model.learn(80)
