"""The multi-agent trainers on tiny runs: a short MAPPO run improves the learned humans' reward on
open_room; IPPO, co-training (simultaneous and alternating) and the multi-process and Ray
collectors run; run folders hold run.json with the seed, TensorBoard logs, checkpoints (the
untrained policy at step 0) and history.csv."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("torchrl")

from socialzoo.agents import make_policy  # noqa: E402
from socialzoo.env.human_policy import LearnedHumanPolicy  # noqa: E402
from socialzoo.env.registration import ENV_VERSION  # noqa: E402
from socialzoo.env.torchrl_env import SocialNavTorchEnv  # noqa: E402
from socialzoo.train.cotrain import CotrainArgs  # noqa: E402
from socialzoo.train.cotrain import train as cotrain  # noqa: E402
from socialzoo.train.humans import HumansArgs  # noqa: E402
from socialzoo.train.humans import train as train_humans  # noqa: E402
from socialzoo.train.marl_run import read_history  # noqa: E402

# Open room, five learned humans (every human of the scenario), short episodes.
TINY = dict(
    map="open_room",
    num_learned_humans=5,
    max_humans=5,
    max_steps=200,
    batch_size=16,
    frames_per_batch=1024,
    minibatch_size=256,
    checkpoint_every=4096,
    progress=False,
)


def mean_human_reward(path, config, *, seed: int = 1234, batch_size: int = 8, steps: int = 200) -> float:
    """Mean reward per present learned human and step of the policy file's (deterministic) humans
    among Ref robots, on the scenario stream of `seed`."""
    policy = LearnedHumanPolicy.load(path)
    env = SocialNavTorchEnv(config, batch_size=batch_size, robot_policy=make_policy("ref"), seed=seed)
    td = env.reset()
    total, count = 0.0, 0
    for _ in range(steps):
        mask = td["human", "mask"]
        action = policy.act(td["human", "observation"].numpy())
        td["human", "action"] = torch.as_tensor(action, dtype=torch.float32)
        out, td = env.step_and_maybe_reset(td)
        total += float(out["next", "human", "reward"].squeeze(-1)[mask].sum())
        count += int(mask.sum())
    env.close()
    return total / count


@pytest.fixture(scope="module")
def mappo_run(tmp_path_factory):
    # From humans standing still (no walk prior) exploring widely, so that the test sees learning,
    # not the prior.
    args = HumansArgs(
        out=tmp_path_factory.mktemp("mappo"),
        algo="mappo",
        frames=8192,
        seed=3,
        walk_prior=0.0,
        init_std=1.0,
        **TINY,
    )
    return args, train_humans(args)


def test_short_mappo_run_improves_the_human_reward_on_open_room(mappo_run):
    args, final = mappo_run
    config = args.env_config()
    untrained = args.out / "checkpoints" / "step_000000000.humans.safetensors"
    before = mean_human_reward(untrained, config)
    after = mean_human_reward(final, config)
    # The untrained humans barely move (progress ~0, speed penalty); the trained ones walk their routes.
    assert after > before + 0.01, (before, after)
    assert after > 0


def test_run_folder_records_seed_checkpoints_tensorboard_and_history(mappo_run):
    args, final = mappo_run
    record = json.loads((args.out / "run.json").read_text())
    assert record["args"]["seed"] == 3 and record["args"]["algo"] == "mappo"
    assert record["finished"] and record["results"]["frames"] == 8192
    assert record["results"]["checkpoints"] == [
        "checkpoints/step_000000000.humans.safetensors",
        "checkpoints/step_000004096.humans.safetensors",
        "checkpoints/step_000008192.humans.safetensors",
    ]
    assert list((args.out / "tensorboard").glob("events.out.tfevents.*"))
    history = read_history(args.out / "history.csv")
    assert [row["frames"] for row in history] == [1024.0 * k for k in range(1, 9)]
    assert all(np.isfinite(row["human/loss_objective"]) for row in history)
    training = LearnedHumanPolicy.load(final).header["training"]
    assert training["seed"] == 3 and training["algo"] == "mappo" and training["frames"] == 8192
    # A rerun of the finished run does not train again.
    mtime = final.stat().st_mtime_ns
    assert train_humans(args) == final and final.stat().st_mtime_ns == mtime


def test_trained_policy_saves_and_loads_to_identical_actions(mappo_run, tmp_path):
    _, final = mappo_run
    policy = LearnedHumanPolicy.load(final)
    obs = np.random.default_rng(0).normal(size=(5, 3, policy.input_size)).astype(np.float32)
    copy = policy.save(tmp_path / "copy.safetensors", policy.header["env_id"], policy.header["training"])
    again = LearnedHumanPolicy.load(copy)
    np.testing.assert_array_equal(again.act(obs), policy.act(obs))
    assert again.digest == policy.digest  # same content, same bytes


def test_ippo_runs(tmp_path):
    args = HumansArgs(out=tmp_path, algo="ippo", frames=2048, seed=0, **TINY)
    final = train_humans(args)
    assert LearnedHumanPolicy.load(final).header["training"]["algo"] == "ippo"
    assert len(read_history(tmp_path / "history.csv")) == 2


def test_checkpoints_are_named_by_the_frames_they_trained_on(tmp_path):
    # Found with --frames 600 --frames-per-batch 256 --checkpoint-every 100: the files said steps 100,
    # 200, ..., 600 (100 and 200 the same weights, after 256 frames) and the final policy said 768.
    tiny = {**TINY, "batch_size": 4, "frames_per_batch": 256, "minibatch_size": 128, "checkpoint_every": 100}
    args = HumansArgs(out=tmp_path, frames=600, epochs=1, stats_steps=8, seed=0, **tiny)
    final = train_humans(args)
    names = sorted(p.name for p in (tmp_path / "checkpoints").iterdir())
    assert names == [f"step_{n:09d}.humans.safetensors" for n in (0, 256, 512, 768)]
    last = LearnedHumanPolicy.load(tmp_path / "checkpoints" / names[-1]).header["training"]["frames"]
    assert last == LearnedHumanPolicy.load(final).header["training"]["frames"] == 768


@pytest.mark.parametrize("schedule", ["simultaneous", "alternating"])
def test_cotrain_runs_and_writes_both_policies(tmp_path, schedule):
    tiny = {**TINY, "num_learned_humans": 2, "checkpoint_every": 10_000}
    args = CotrainArgs(
        out=tmp_path, schedule=schedule, alternate_every=1, num_robots=2, frames=3072, seed=0, **tiny
    )
    final = cotrain(args)
    assert final.name == "humans.safetensors" and (tmp_path / "robot.safetensors").is_file()
    robot = make_policy(f"mappo:{tmp_path / 'robot.safetensors'}")
    assert robot.name == "mappo"
    history = read_history(tmp_path / "history.csv")
    updated = [
        (
            np.isfinite(r.get("robot/loss_objective", np.nan)),
            np.isfinite(r.get("human/loss_objective", np.nan)),
        )
        for r in history
    ]
    if schedule == "simultaneous":
        assert updated == [(True, True)] * 3
    else:  # robots first, then humans, one batch each
        assert updated == [(True, False), (False, True), (True, False)]


@pytest.mark.parametrize("collector", ["multiprocess", "ray"])
def test_distributed_collectors_run(tmp_path, collector, monkeypatch):
    if collector == "ray":
        pytest.importorskip("ray")
        from datetime import timedelta

        from torchrl.weight_update import _ray

        # TorchRL waits 60 s for the Ray collectors to join its weight-sync process group; on a
        # busy 2-core machine starting two actors that import torch takes longer than that.
        monkeypatch.setattr(_ray, "_DIST_TIMEOUT", timedelta(seconds=600))
    tiny = {**TINY, "batch_size": 8, "frames_per_batch": 512}
    args = HumansArgs(out=tmp_path, frames=1024, collector=collector, workers=2, seed=0, **tiny)
    final = train_humans(args)
    assert LearnedHumanPolicy.load(final).header["training"]["frames"] == 1024
    record = json.loads((tmp_path / "run.json").read_text())
    assert record["args"]["collector"] == collector and record["results"]["frames"] == 1024


def test_a_ray_address_nothing_answers_at_is_one_line_in_seconds(tmp_path, capsys):
    # RayCollector's ray.init waited minutes on a cluster address nothing answered at.
    import socket

    from socialzoo.cli import main

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # closed once the socket is
    argv = ["train", "humans", "--collector", "ray", "--ray-address", f"127.0.0.1:{port}", "--workers", "2"]
    argv += [
        "--frames",
        "512",
        "--frames-per-batch",
        "512",
        "--batch-size",
        "8",
        "--out",
        str(tmp_path / "run"),
    ]
    assert main(argv) == 2
    said = f"cannot reach the Ray cluster at '127.0.0.1:{port}' (127.0.0.1:{port}: Connection refused)"
    assert capsys.readouterr().err == f"socialzoo train humans: error: {said}\n"


def test_bad_arguments_name_the_field(tmp_path):
    with pytest.raises(ValueError, match=r"HumansArgs\.algo"):
        HumansArgs(out=tmp_path, algo="ddpg")
    with pytest.raises(ValueError, match="frames_per_batch"):
        HumansArgs(out=tmp_path, batch_size=16, frames_per_batch=1000)
    with pytest.raises(ValueError, match=r"CotrainArgs\.schedule"):
        CotrainArgs(out=tmp_path, schedule="sometimes")
    # A minibatch larger than the batch was cut to the batch while run.json recorded it as asked.
    with pytest.raises(
        ValueError,
        match=r"HumansArgs\.minibatch_size \(6401\) must be at most a collected batch, frames_per_batch \(6400\)",
    ):
        HumansArgs(out=tmp_path, minibatch_size=6401)
    # No human to learn: `socialzoo train humans --num-learned-humans 0` failed inside the run with a
    # traceback (exit 1) instead of a named argument error (exit 2).
    for zero in ({"num_learned_humans": 0}, {"env_overrides": {"num_learned_humans": 0}}):
        with pytest.raises(ValueError, match=r"HumansArgs\.num_learned_humans must be >= 1"):
            HumansArgs(out=tmp_path, **zero)
    assert CotrainArgs(out=tmp_path, num_learned_humans=0).env_config().num_learned_humans == 0


def test_env_overrides_of_a_nested_config_keep_the_runs_own_fields(tmp_path):
    # Found with --max-humans 8 --env-overrides '{"scenario": {"min_humans": 2}}': the run trained
    # with 25 human slots, the override's dict replacing the run's scenario dict instead of adding to it;
    # and --env-overrides '{"human_reward": {"wall_clearance": 0}}' dropped --reward for the env's defaults.
    reward = {"progress": 2.0, "robot_contact": 0.7}
    args = HumansArgs(
        out=tmp_path,
        num_learned_humans=4,
        max_humans=8,
        reward=reward,
        env_overrides={"scenario": {"min_humans": 2}, "human_reward": {"wall_clearance": 0.0}},
    )
    config = args.env_config()
    assert (config.scenario.min_humans, config.scenario.max_humans) == (2, 8)
    assert (config.human_reward.progress, config.human_reward.robot_contact) == (2.0, 0.7)
    assert config.human_reward.wall_clearance == 0.0
    # A plain value still replaces the run's own.
    assert HumansArgs(out=tmp_path, env_overrides={"map": "gdc1"}, map="open_room").env_config().map == "gdc1"


def test_fewer_human_slots_than_the_scenarios_least_head_count_lower_it(tmp_path):
    # `socialzoo train humans --num-learned-humans 3 --max-humans 3` was refused with
    # "ScenarioConfig.min_humans (5) exceeds max_humans (3)", a field no flag of the trainer sets.
    config = HumansArgs(out=tmp_path, num_learned_humans=3, max_humans=3).env_config()
    assert (config.scenario.min_humans, config.scenario.max_humans) == (3, 3)
    assert HumansArgs(out=tmp_path).env_config().scenario.min_humans == 5  # the default run's, unchanged
    with pytest.raises(ValueError, match=r"HumansArgs\.max_humans must be an int >= 0, got -1"):
        HumansArgs(out=tmp_path, num_learned_humans=0, max_humans=-1)


def test_cotrain_learns_the_groups_of_its_env_config(tmp_path):
    # `socialzoo train cotrain --schedule alternating --env-overrides '{"num_learned_humans": 0}'` ended
    # in a KeyError traceback on the humans' first turn, and its final file was looked for as
    # humans.safetensors: both read --num-learned-humans instead of the env the run trains in.
    from socialzoo.train.cotrain import TRAINER

    args = CotrainArgs(
        out=tmp_path, schedule="alternating", alternate_every=1, env_overrides={"num_learned_humans": 0}
    )
    assert [list(args.groups_at(i)) for i in range(3)] == [["robot"]] * 3
    assert TRAINER.policy_path(args).name == "robot.safetensors"
    both = CotrainArgs(out=tmp_path, schedule="alternating", alternate_every=1)
    assert [list(both.groups_at(i)) for i in range(3)] == [["robot"], ["human"], ["robot"]]
    assert TRAINER.policy_path(both).name == "humans.safetensors"


def test_walk_prior_starts_humans_walking_towards_their_waypoint():
    import torch
    from tensordict import TensorDict

    from socialzoo.train.mappo import human_actor

    obs = torch.randn(64, 5, 12)
    for prior in (0.0, 0.9):
        actor = human_actor(12, 16, 2, torch.zeros(12), torch.ones(12), walk_prior=prior, init_std=0.5)
        out = actor.module[0](TensorDict({("human", "observation"): obs}, batch_size=[64]))
        mean = torch.tanh(out["human", "loc"]).detach()
        assert abs(float(mean[..., 0].mean()) - prior) < 0.05 and float(mean[..., 1].abs().max()) < 0.2
        assert torch.allclose(out["human", "scale"], torch.full_like(out["human", "scale"], 0.5))
    # With an action scale the prior is still a fraction of the preferred speed: the mean action
    # is walk_prior / action_scale.
    actor = human_actor(12, 16, 2, torch.zeros(12), torch.ones(12), walk_prior=1.0, action_scale=1.25)
    out = actor.module[0](TensorDict({("human", "observation"): obs}, batch_size=[64]))
    assert abs(float(torch.tanh(out["human", "loc"].detach())[..., 0].mean()) - 0.8) < 0.05
    with pytest.raises(ValueError, match="walk_prior"):
        HumansArgs(out=Path("unused"), walk_prior=1.0, action_scale=1.0)
    with pytest.raises(ValueError, match="action_scale"):
        HumansArgs(out=Path("unused"), action_scale=0.0)
    assert (
        HumansArgs(out=Path("unused"), action_scale=1.3, walk_prior=1.0).env_config().human_action_scale
        == 1.3
    )


def test_mirror_symmetric_humans_act_alike_on_the_left_and_the_right(tmp_path):
    # A random symmetric actor: on the mirror image of a situation (every y component negated) its
    # mean action is the mirror image (y negated), in torch and in the exported numpy policy, which
    # gives the torch actor's tanh(mean) and keeps the symmetry through a save and load.
    import torch
    from tensordict import TensorDict

    from socialzoo.env.config import EnvConfig
    from socialzoo.env.human_agents import human_mirror_signs, human_observation_size
    from socialzoo.train.mappo import export_humans, human_actor

    config = EnvConfig(map="open_room", num_learned_humans=1, human_action_frame="human")
    size = human_observation_size(config.num_human_neighbours)
    signs = human_mirror_signs(config.num_human_neighbours)
    torch.manual_seed(0)
    loc, scale = torch.randn(size), torch.rand(size) + 0.5
    actor = human_actor(size, 16, 2, loc, scale, walk_prior=0.9, mirror=torch.from_numpy(signs))
    with torch.no_grad():
        for p in actor.parameters():
            p.add_(0.3 * torch.randn_like(p))  # far from the prior's near-zero output weights
        obs = torch.randn(32, 3, size)
        mean = actor.module[0](TensorDict({("human", "observation"): obs}, batch_size=[32]))["human", "loc"]
        mirrored = actor.module[0](
            TensorDict({("human", "observation"): obs * torch.from_numpy(signs)}, batch_size=[32])
        )["human", "loc"]
    torch.testing.assert_close(mirrored, mean * torch.tensor([1.0, -1.0]), atol=1e-5, rtol=1e-5)
    assert mean[..., 1].abs().mean() > 0.05  # the test is not passed by a zero lateral output
    policy = export_humans(actor, config)
    assert policy.mirror_symmetric
    np.testing.assert_allclose(policy.act(obs.numpy()), torch.tanh(mean).numpy(), atol=1e-5)
    env_id = f"socialzoo/MultiAgent-v{ENV_VERSION}"
    loaded = LearnedHumanPolicy.load(policy.save(tmp_path / "sym.safetensors", env_id, {}))
    assert loaded.mirror_symmetric
    np.testing.assert_allclose(
        loaded.act(obs.numpy() * signs), loaded.act(obs.numpy()) * [1.0, -1.0], atol=1e-6
    )
    # An unsymmetrised actor of the same weights is not symmetric: the wrapper is what does it.
    plain = human_actor(size, 16, 2, loc, scale, walk_prior=0.9)
    plain.module[0].module[0].load_state_dict(actor.module[0].module[0].net.state_dict())
    with torch.no_grad():
        out = plain.module[0](TensorDict({("human", "observation"): obs}, batch_size=[32]))["human", "loc"]
        out_m = plain.module[0](
            TensorDict({("human", "observation"): obs * torch.from_numpy(signs)}, batch_size=[32])
        )["human", "loc"]
    assert not torch.allclose(out_m, out * torch.tensor([1.0, -1.0]), atol=1e-3)


def test_the_humans_file_says_how_its_training_world_walked_learned_people(tmp_path):
    # Found training with --env-overrides '{"world": {"human": {"learned_forces": false,
    # "learned_relaxation_time": 4.0}}}': the file said forces on and no relaxation time, so every world
    # that walked it (benchmark --humans learned:PATH) pushed its people with the social and wall forces
    # and relaxed them at 0.5 s, not as they were trained.
    import torch

    from socialzoo.env.config import EnvConfig
    from socialzoo.env.human_agents import human_observation_size
    from socialzoo.train.mappo import export_humans, human_actor

    size = human_observation_size(EnvConfig().num_human_neighbours)
    actor = human_actor(size, 8, 1, torch.zeros(size), torch.ones(size), walk_prior=0.9)
    env_id = f"socialzoo/MultiAgent-v{ENV_VERSION}"
    walks = {"learned_forces": False, "learned_relaxation_time": 4.0}
    config = EnvConfig(map="open_room", num_learned_humans=1).replace(world={"human": walks})
    loaded = LearnedHumanPolicy.load(
        export_humans(actor, config).save(tmp_path / "a.safetensors", env_id, {})
    )
    assert (loaded.learned_forces, loaded.relaxation_time) == (False, 4.0)
    # The default world: forces on, its people's 0.5 s.
    plain = export_humans(actor, EnvConfig(map="open_room", num_learned_humans=1))
    assert (plain.learned_forces, plain.relaxation_time) == (True, 0.5)
