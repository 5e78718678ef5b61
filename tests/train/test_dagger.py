"""DAgger: its first round is BC, each later round adds the learner's own states labelled by Ref,
its rollouts drive scenarios of their own seeds, and its run folder records the rounds."""

import json
from types import SimpleNamespace

import numpy as np
import pytest

from socialzoo.agents import make_policy
from socialzoo.agents.demonstrations import load_demonstrations
from socialzoo.agents.engineered import Ref
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.scenarios.scenario_sets import get_test_set, validation_set
from socialzoo.train import bc, dagger

WIDE_REF = Ref(corridor_half_width=4.0, lookahead_margin=8.0)
SMALL = dict(hidden=(32, 32), epochs=1, min_updates=40, batch_size=128, progress=False)


def _args(small_demos, out, **changes):
    return dagger.Args(**{**dict(demos=small_demos, steps=None, out=out, episodes=2), **SMALL, **changes})


@pytest.fixture(scope="module")
def run(small_demos, tmp_path_factory):
    """A two-round run, with the (obs, action) pairs each round was fitted to."""
    fits = []
    fit_actions = bc.fit_actions
    monkeypatch = pytest.MonkeyPatch()

    def recording_fit(loss_module, obs, action, *args, **kwargs):
        fits.append((obs.copy(), action.copy()))
        return fit_actions(loss_module, obs, action, *args, **kwargs)

    monkeypatch.setattr(bc, "fit_actions", recording_fit)
    # A wide-eyed Ref as the expert: it halts or follows for people far off the robot's way, so its
    # labels differ from the learner's actions on the short test episodes.
    monkeypatch.setattr(dagger, "expert_of", lambda data: WIDE_REF)
    try:
        path = dagger.train(_args(small_demos, tmp_path_factory.mktemp("run") / "dagger", iterations=1))
    finally:
        monkeypatch.undo()
    return path, fits


def test_a_round_adds_the_learners_states_labelled_by_the_expert(run, small_demos):
    path, fits = run
    demos, _ = load_demonstrations(small_demos)
    rollout, _ = load_demonstrations(path.parent / "rollouts" / "round_000.npz")
    assert len(fits) == 2 and len(fits[0][0]) == len(demos["action"])
    obs, action = fits[1]
    n = len(demos["action"])
    np.testing.assert_array_equal(obs[:n], demos["obs"])
    np.testing.assert_array_equal(action[:n], demos["action"])
    # The added states are the ones round 0's policy reached, and their labels are the expert's
    # actions there, not the learner's.
    np.testing.assert_array_equal(obs[n:], rollout["obs"])
    learner = MlpPolicy.load(path.parent / "checkpoints" / "step_000000000.safetensors")
    np.testing.assert_array_equal(learner.act(rollout["obs"]), rollout["action"])
    np.testing.assert_array_equal(action[n:], WIDE_REF.act(rollout["obs"]))
    assert (action[n:] != rollout["action"]).any()  # so the two labellings can be told apart
    record = json.loads((path.parent / "run.json").read_text())["results"]
    assert record["rollout_steps"] == len(rollout["action"]) and record["rounds"] == 2
    [differs] = record["closed_loop_disagreement"]
    assert differs == pytest.approx(np.mean(action[n:] != rollout["action"]))


def test_the_rollouts_drive_scenarios_of_their_own_seeds(run, small_demos):
    path, _ = run
    demos, _ = load_demonstrations(small_demos)
    rollout, _ = load_demonstrations(path.parent / "rollouts" / "round_000.npz")
    seeds = set(rollout["episode_seeds"].tolist())
    assert len(seeds) == 2
    held_out = {s.seed(k) for s in (validation_set("gdc1"), get_test_set("gdc1-test")) for k in range(len(s))}
    assert not seeds & held_out and not seeds & set(demos["episode_seeds"].tolist())


def test_the_run_folder_records_each_rounds_policy(run):
    path, _ = run
    assert path.name == "dagger.safetensors"
    assert sorted(p.name for p in (path.parent / "checkpoints").iterdir()) == [
        "step_000000000.safetensors", "step_000000001.safetensors"
    ]  # fmt: skip
    policy = make_policy(f"dagger:{path}")
    assert policy.header["policy"] == "dagger"
    assert policy.header["training"]["demonstrations"]["policy"] == "ref"
    # The final policy is the last round's.
    last = MlpPolicy.load(path.parent / "checkpoints" / "step_000000001.safetensors")
    for (w, b), (w2, b2) in zip(policy.layers, last.layers, strict=True):
        np.testing.assert_array_equal(w, w2)
        np.testing.assert_array_equal(b, b2)


def test_no_rounds_is_behaviour_cloning(small_demos, tmp_path):
    plain = MlpPolicy.load(dagger.train(_args(small_demos, tmp_path / "dagger", iterations=0)))
    cloned = MlpPolicy.load(bc.train(bc.Args(demos=small_demos, steps=None, out=tmp_path / "bc", **SMALL)))
    for (w, b), (w2, b2) in zip(plain.layers, cloned.layers, strict=True):
        np.testing.assert_array_equal(w, w2)
        np.testing.assert_array_equal(b, b2)


@pytest.mark.parametrize(
    ("policy", "layout", "message"),
    [("goalone", "paper", "demonstrations are of 'goalone'"), ("ref", "reference", "use 'reference'")],
)
def test_the_expert_must_be_refs_demonstrations_in_the_paper_layout(policy, layout, message):
    data = SimpleNamespace(
        path="demos.npz",
        metadata={"config": {"policy": policy, "policy_kwargs": {}}},
        observation={"layout": layout},
    )
    with pytest.raises(ValueError, match=message) as err:
        dagger.expert_of(data)
    assert "demos.npz" in str(err.value)


def test_ref_parameters_of_the_demonstrations_carry_to_the_expert():
    data = SimpleNamespace(
        path="demos.npz",
        metadata={"config": {"policy": "ref", "policy_kwargs": {"corridor_half_width": 0.5}}},
        observation={"layout": "paper"},
    )
    assert dagger.expert_of(data).cfg.corridor_half_width == 0.5


def test_bad_round_counts_are_refused(small_demos, tmp_path):
    with pytest.raises(ValueError, match="iterations"):
        _args(small_demos, tmp_path, iterations=-1)
    with pytest.raises(ValueError, match="episodes"):
        _args(small_demos, tmp_path, episodes=0)
