"""`socialzoo reproduce --reference`: PPO and DQN trained and evaluated with the reference code's
quirks, reported beside ours and the paper's; two runs of it give the same table."""

import json

import pytest

from socialzoo.reproduce.plan import quick_settings
from socialzoo.reproduce.results import RESULTS_DIR, load
from socialzoo.reproduce.run import reproduce


def _tiny_settings():
    """As tests/reproduce/conftest.py's tiny settings: one checkpoint per RL run, short episodes."""
    return quick_settings(
        rl_total_steps=200,
        rl_checkpoint_every=200,
        select_trials=0,
        demo_episodes=1,
        demo_env_overrides={"max_steps": 100},
        eval_env_overrides={"max_steps": 150},
        batch_size=1,
    )


@pytest.fixture(scope="module")
def two_reference_runs(tmp_path_factory):
    pytest.importorskip("torch")
    pytest.importorskip("stable_baselines3")
    settings = _tiny_settings()
    outs = [tmp_path_factory.mktemp(name) for name in ("a", "b")]
    for out in outs:
        reproduce(out, settings, parts="demos", progress=False, reference=True)
    return outs


def test_reference_rows_and_report(two_reference_runs):
    out = two_reference_runs[0]
    results = load(out / RESULTS_DIR)
    rows = results["reference"]
    assert {(r["experiment"], r["policy"]) for r in rows} == {
        (e, p) for e in ("performance", "transfer") for p in ("dqn", "ppo")
    }
    work = next(p for p in out.iterdir() if (p / "settings.json").is_file())
    record = json.loads((work / "reference" / "rl" / "ppo" / "run.json").read_text())
    assert record["args"]["env_overrides"]["quirks"]["reward_distance_plus_bonus"] is True
    assert record["machine"]["torch"]["version"]
    # PPO is evaluated from its file without normalisation.
    evaluated = list((work / "reference" / "evaluated" / "ppo").glob("*.unnormalised.safetensors"))
    assert len(evaluated) == 1
    text = (out / "REPRODUCTION.md").read_text()
    assert "## The reference code's quirks (`--reference`)" in text
    assert "| performance | PPO |" in text or "| performance | ppo |" in text.lower()
    assert "## What a re-run may differ by" in text
    machines = [t["machine"] for t in results["training"] if t.get("machine")]
    assert machines and all(m["torch"] and m["threads"] == 1 for m in machines)


def test_two_runs_give_the_same_table(two_reference_runs):
    a, b = (load(out / RESULTS_DIR)["reference"] for out in two_reference_runs)
    assert a == b


def test_one_quirk_alone_then_another_keeps_both(tmp_path):
    """`--reference QUIRK`: a training quirk alone retrains PPO and DQN with just that switch; PPO's
    evaluation quirk alone evaluates the default PPO runs without their normalisation (no DQN rows:
    it does not reach DQN); a later run of another set keeps the earlier set's rows."""
    pytest.importorskip("torch")
    pytest.importorskip("stable_baselines3")
    settings = _tiny_settings()
    reproduce(tmp_path, settings, parts="demos", progress=False, reference="goal_distance_x_only")
    reproduce(tmp_path, settings, parts="demos", progress=False, reference=["ppo_eval_without_normalisation"])
    rows = load(tmp_path / RESULTS_DIR)["reference"]
    assert {(r["quirks"], r["experiment"], r["policy"]) for r in rows} == {
        *{("goal_distance_x_only", e, p) for e in ("performance", "transfer") for p in ("dqn", "ppo")},
        *{("ppo_eval_without_normalisation", e, "ppo") for e in ("performance", "transfer")},
    }
    work = next(p for p in tmp_path.iterdir() if (p / "settings.json").is_file())
    alone = work / "reference" / "alone"
    record = json.loads((alone / "goal_distance_x_only" / "rl" / "dqn" / "run.json").read_text())
    assert record["args"]["env_overrides"]["quirks"] == {"goal_distance_x_only": True}
    # The evaluation quirk trained nothing of its own: the default PPO run, evaluated unnormalised.
    assert (work / "rl" / "ppo" / "run.json").is_file()
    assert not (alone / "ppo_eval_without_normalisation" / "rl").exists()
    unnormalised = alone / "ppo_eval_without_normalisation" / "evaluated" / "ppo"
    evaluated = list(unnormalised.glob("*.unnormalised.safetensors"))
    assert len(evaluated) == 1
    text = (tmp_path / "REPRODUCTION.md").read_text()
    assert "| performance | PPO | goal distance along x only |" in text
    assert "| performance | PPO | PPO evaluated without its normalisation |" in text


def test_reference_sets_are_checked():
    from socialzoo.reproduce.plan import reference_sets

    assert reference_sets(False) == () and reference_sets(None) == () and reference_sets(()) == ()
    assert reference_sets(True) == ("all",)
    assert reference_sets("goal_distance_x_only, all,goal_distance_x_only") == ("goal_distance_x_only", "all")
    with pytest.raises(
        ValueError, match="unknown reference quirk 'x_only'; known: all, goal_distance_x_only"
    ):
        reference_sets("x_only")
