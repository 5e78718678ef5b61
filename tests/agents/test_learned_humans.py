"""Learned human policies at inference: the file round trip, bad files and specs, mixed learned and
scripted populations, and the shipped policy (trained by `socialzoo train humans`, seed recorded)."""

import json

import numpy as np
import pytest

from socialzoo.agents import SHIPPED_DIR
from socialzoo.env.config import EnvConfig
from socialzoo.env.human_policy import LearnedHumanPolicy
from socialzoo.env.policy_file import PolicyFileError, save_policy_file
from socialzoo.env.tasks.action_selection import ActionSelectionTask
from socialzoo.nav.subpolicies import HALT
from socialzoo.scenarios.scenario import Scenario

SHIPPED = SHIPPED_DIR / "humans.safetensors"


def test_round_trip_gives_identical_actions(walker_policy_path, tmp_path):
    rng = np.random.default_rng(1)
    policy = LearnedHumanPolicy.load(walker_policy_path)
    layers = [(rng.normal(size=w.shape), rng.normal(size=b.shape)) for w, b in policy.layers]
    loc, scale = rng.normal(size=policy.input_size), rng.uniform(0.5, 2.0, policy.input_size)
    original = LearnedHumanPolicy(layers, "tanh", loc, scale, policy.num_neighbours, "world", 1.25)
    path = original.save(tmp_path / "p.safetensors", policy.header["env_id"], {"seed": 7})
    loaded = LearnedHumanPolicy.load(path)
    obs = rng.normal(size=(3, 4, policy.input_size))
    np.testing.assert_array_equal(loaded.act(obs), original.act(obs))
    assert loaded.act(obs).shape == (3, 4, 2) and (np.abs(loaded.act(obs)) <= 1).all()
    assert loaded.env_overrides() == {
        "num_human_neighbours": policy.num_neighbours,
        "human_action_frame": "world",
        "human_action_scale": 1.25,
    }
    assert loaded.config()["training"] == {"seed": 7} and len(loaded.config()["file_sha256"]) == 64


def test_bad_files_and_specs_are_named(walker_policy_path, tmp_path):
    policy = LearnedHumanPolicy.load(walker_policy_path)
    tensors = {"obs_loc": policy.obs_loc, "obs_scale": policy.obs_scale}
    path = save_policy_file(tmp_path / "ppo.safetensors", tensors, {**policy.header, "policy": "ppo"})
    with pytest.raises(PolicyFileError, match="not a learned human policy"):
        LearnedHumanPolicy.load(path)
    with pytest.raises(ValueError, match="the last layer gives 3 outputs"):
        LearnedHumanPolicy(
            [(np.zeros((3, policy.input_size)), np.zeros(3))],
            "tanh",
            policy.obs_loc,
            policy.obs_scale,
            policy.num_neighbours,
            "human",
        )
    with pytest.raises(ValueError, match="scale > 0"):
        LearnedHumanPolicy(
            policy.layers, "tanh", policy.obs_loc, 0 * policy.obs_scale, policy.num_neighbours, "human"
        )
    with pytest.raises(ValueError, match=r"LearnedHumanPolicy\.action_scale must be > 0, got 0\.0"):
        LearnedHumanPolicy(
            policy.layers, "tanh", policy.obs_loc, policy.obs_scale, policy.num_neighbours, "human", 0.0
        )
    # A file from before the action scale existed was trained with scale 1.
    observation = {k: v for k, v in policy.header["observation"].items() if k != "action_scale"}
    tensors = {"obs_loc": policy.obs_loc, "obs_scale": policy.obs_scale}
    for i, (w, b) in enumerate(policy.layers):
        tensors[f"net.{i}.weight"], tensors[f"net.{i}.bias"] = w, b
    old = save_policy_file(
        tmp_path / "old.safetensors", tensors, {**policy.header, "observation": observation}
    )
    assert LearnedHumanPolicy.load(old).env_overrides()["human_action_scale"] == 1.0
    assert not LearnedHumanPolicy.load(old).mirror_symmetric
    network = {**policy.header["network"], "mirror_symmetric": "yes"}
    odd = save_policy_file(tmp_path / "odd.safetensors", tensors, {**policy.header, "network": network})
    with pytest.raises(PolicyFileError, match=r"network\.mirror_symmetric must be true or false"):
        LearnedHumanPolicy.load(odd)
    with pytest.raises(ValueError, match="act: observations of shape"):
        policy.act(np.zeros((2, policy.input_size + 1)))


def test_mixed_population_learned_slots_follow_the_policy_the_rest_their_social_force(write_walker, tmp_path):
    # Five humans walking up the open room side by side; the first two are learned slow walkers
    # (tanh(0.5) = 0.46 of their preferred speed), the other three keep their social force.
    slow = LearnedHumanPolicy.load(write_walker(tmp_path / "slow.safetensors", speed=0.5))
    spawn = [[1.0 + 2.0 * i, 1.5] for i in range(5)]
    goals = [[1.0 + 2.0 * i, 9.0] for i in range(5)]
    scenario = Scenario(
        map_name="open_room",
        seed=3,
        robot_starts=[[9.5, 9.5, 0.0]],
        robot_goals=[[9.5, 5.0, 0.0]],
        human_spawn=spawn,
        human_start_index=[-1] * 5,
        human_goal_index=[-1] * 5,
        human_routes=tuple(np.array([s, g]) for s, g in zip(spawn, goals, strict=True)),
        human_speed=[1.0] * 5,
    )
    config = EnvConfig(map="open_room", num_learned_humans=2, **slow.env_overrides())
    task = ActionSelectionTask(config, 1)
    task.reset_rows([0], [scenario])
    assert task.human_obs.shape == (1, 2, slow.input_size)
    for _ in range(120):  # 3 s
        task.step(np.array([[HALT]]), slow.act(task.human_obs))
    speed = np.linalg.norm(task.core.state.human_vel[0, :5], axis=-1)
    assert np.all(np.abs(speed[:2] - np.tanh(0.5)) < 0.05)
    assert np.all(speed[2:] > 0.9)


def test_shipped_human_policy_loads_and_records_its_training():
    assert SHIPPED.stat().st_size < 2**20
    policy = LearnedHumanPolicy.load(SHIPPED)
    training = policy.header["training"]
    assert training["algo"] == "mappo" and training["trainer"] == "humans" and training["map"] == "gdc1"
    record = json.loads((SHIPPED_DIR / "humans.run.json").read_text())
    assert (
        record["command"].startswith("socialzoo train humans") and record["args"]["seed"] == training["seed"]
    )
    assert record["finished"] and record["args"]["frames"] == record["results"]["frames"]
    # The checkpoint was chosen by `socialzoo humans select` on validation scenarios, never a test set,
    # among the checkpoints of that run.
    selection = json.loads((SHIPPED_DIR / "humans.selection.json").read_text())
    assert selection["scenarios"] == "gdc1-val" and selection["chosen"]["frames"] == training["frames"]
    assert training["frames"] <= record["results"]["frames"] and selection["chosen"]["met"]
    checkpoint = f"checkpoints/step_{training['frames']:09d}.humans.safetensors"
    assert checkpoint in record["results"]["checkpoints"]
    assert policy.mirror_symmetric and record["args"]["mirror_symmetric"]
    obs = np.random.default_rng(0).normal(size=(8, policy.input_size))
    assert np.isfinite(policy.act(obs)).all()


def test_the_file_says_whether_forces_act_on_its_people_and_the_world_takes_it(walker_policy_path, tmp_path):
    from socialzoo.core.config import WorldConfig
    from socialzoo.core.walls import WallIndex
    from socialzoo.env.core import BatchedCore
    from socialzoo.humans.models import PeopleConfig

    policy = LearnedHumanPolicy.load(walker_policy_path)
    assert policy.learned_forces  # files without the dynamics section: forces on, as before
    free = LearnedHumanPolicy(
        policy.layers, "tanh", policy.obs_loc, policy.obs_scale, policy.num_neighbours, "human",
        learned_forces=False,
    )  # fmt: skip
    path = free.save(tmp_path / "free.safetensors", policy.header["env_id"], {})
    assert LearnedHumanPolicy.load(path).learned_forces is False

    def world_of(spec: str) -> WorldConfig:
        core = BatchedCore(
            1, 1, 2, WorldConfig(), WallIndex(np.zeros((0, 4))), people=PeopleConfig(models=spec)
        )
        return core.world

    assert world_of(f"learned:{path}").human.learned_forces is False
    assert world_of(f"learned:{walker_policy_path}").human.learned_forces is True
    assert world_of("sf").human.learned_forces is True
    header = {**LearnedHumanPolicy.load(path).header, "dynamics": {"learned_forces": "no"}}
    tensors = {"obs_loc": free.obs_loc, "obs_scale": free.obs_scale}
    for i, (w, b) in enumerate(free.layers):
        tensors[f"net.{i}.weight"], tensors[f"net.{i}.bias"] = w, b
    bad = save_policy_file(tmp_path / "bad.safetensors", tensors, header)
    with pytest.raises(PolicyFileError, match=r"dynamics\.learned_forces must be true or false"):
        LearnedHumanPolicy.load(bad)


def test_the_file_says_its_peoples_relaxation_time_and_the_world_takes_it(walker_policy_path, tmp_path):
    from socialzoo.core.config import HumanConfig, WorldConfig
    from socialzoo.core.walls import WallIndex
    from socialzoo.env.core import BatchedCore
    from socialzoo.humans.models import PeopleConfig

    policy = LearnedHumanPolicy.load(walker_policy_path)
    assert policy.relaxation_time is None  # files without it: the walking world's own
    slow = LearnedHumanPolicy(
        policy.layers, "tanh", policy.obs_loc, policy.obs_scale, policy.num_neighbours, "human",
        learned_forces=False, relaxation_time=2.0,
    )  # fmt: skip
    path = slow.save(tmp_path / "slow.safetensors", policy.header["env_id"], {})
    assert LearnedHumanPolicy.load(path).relaxation_time == 2.0

    def human_of(spec: str) -> HumanConfig:
        world = WorldConfig(human=HumanConfig(relaxation_time=0.7))
        return BatchedCore(
            1, 1, 2, world, WallIndex(np.zeros((0, 4))), people=PeopleConfig(models=spec)
        ).world.human

    taken = human_of(f"learned:{path}")
    assert taken.learned_tau == 2.0 and taken.relaxation_time == 0.7  # the other people's stays
    assert human_of(f"learned:{walker_policy_path}").learned_tau == 0.7
    with pytest.raises(ValueError, match=r"LearnedHumanPolicy\.relaxation_time must be > 0, got -1\.0"):
        LearnedHumanPolicy(
            policy.layers, "tanh", policy.obs_loc, policy.obs_scale, policy.num_neighbours, "human",
            relaxation_time=-1.0,
        )  # fmt: skip
