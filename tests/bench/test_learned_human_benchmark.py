"""Benchmarks among learned humans (`humans="learned:PATH"`, a people spec the env drives):
deterministic for a fixed seed, stored under a config hash that holds the policy file's digest,
and reachable from `socialzoo benchmark --humans`."""

import json
import math
import shutil

import pytest

from socialzoo.bench.experiment import (
    STORE_NAME,
    BenchmarkConfig,
    hashed_people,
    people_overrides,
    run_benchmark,
)
from socialzoo.bench.human_metrics import HUMAN_METRIC_KEYS
from socialzoo.bench.runner import RunSpec, env_config_for
from socialzoo.bench.store import ResultsStore
from socialzoo.cli import main as socialzoo_main
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet

TRIALS = 4
MAX_STEPS = 150


@pytest.fixture(scope="module")
def rooms(rooms_map_path):
    return {
        "rooms": TestSet(
            str(rooms_map_path), 7, 20, ScenarioConfig(min_humans=3, max_humans=5), name="rooms-test"
        )
    }


def config(humans, **changes):
    base = dict(
        policies=("ref",),
        maps=("rooms",),
        trials=TRIALS,
        batch_size=4,
        workers=1,
        env_overrides={"max_steps": MAX_STEPS},
        humans=humans,
        human_metrics=True,
    )
    base.update(changes)
    return BenchmarkConfig(**base)


def stored(out_dir):
    """Every stored trial without its finish time, NaN replaced by a marker, in trial order."""
    with ResultsStore(out_dir / STORE_NAME) as store:
        rows = store.rows()
    clean = []
    for row in sorted(rows, key=lambda r: r["scenario_index"]):
        row.pop("finished_at")
        clean.append({k: "nan" if isinstance(v, float) and math.isnan(v) else v for k, v in row.items()})
    return clean


def run(cfg, out, rooms):
    return run_benchmark(cfg, out, test_sets=rooms, progress=False, figures=False)


@pytest.fixture(scope="module")
def learned_run(rooms, walker_policy_path, tmp_path_factory):
    out = tmp_path_factory.mktemp("learned")
    result = run(config(f"learned:{walker_policy_path}"), out, rooms)
    assert (result.computed, result.reused) == (TRIALS, 0)
    return out


def test_learned_humans_run_is_deterministic_and_batch_independent(
    rooms, walker_policy_path, learned_run, tmp_path
):
    rows = stored(learned_run)
    assert len(rows) == TRIALS
    assert all(set(HUMAN_METRIC_KEYS) <= set(r) for r in rows)
    # Same seed, fresh store: the same rows, one episode at a time or four at once. (The walker's
    # zero weights make every product exact; a trained network's actions can differ in the last bit
    # with the number of people acted on together, BLAS's blocking, and its episodes then differ.)
    for batch in (1, 4):
        out = tmp_path / f"b{batch}"
        run(config(f"learned:{walker_policy_path}", batch_size=batch), out, rooms)
        assert stored(out) == rows


def test_learned_humans_replace_the_social_force_humans(rooms, learned_run, write_walker, tmp_path):
    social = tmp_path / "social"
    run(config("social_force"), social, rooms)
    learned_rows, social_rows = stored(learned_run), stored(social)
    assert [r["seed"] for r in learned_rows] == [r["seed"] for r in social_rows]
    assert learned_rows[0]["config_hash"] != social_rows[0]["config_hash"]
    assert [r["humans_mean_speed"] for r in learned_rows] != [r["humans_mean_speed"] for r in social_rows]
    # Walkers that ask for tanh(0.5) = 0.46 of their preferred speed walk at about half the pace
    # of the social-force humans (the social and wall forces still act on learned humans).
    slow = tmp_path / "slow"
    run(config(f"learned:{write_walker(tmp_path / 'slow.safetensors', speed=0.5)}"), slow, rooms)
    slow_speed = sum(r["humans_mean_speed"] for r in stored(slow)) / TRIALS
    social_speed = sum(r["humans_mean_speed"] for r in social_rows) / TRIALS
    assert 0.3 * social_speed < slow_speed < 0.7 * social_speed
    text = (learned_run / "humans.md").read_text()
    assert "learned:" in text and "route goal reach rate" in text
    # A rerun into the same folder without the people's metrics leaves no older people tables beside it.
    assert (social / "humans.md").is_file()
    run(config("social_force", human_metrics=False), social, rooms)
    assert not (social / "humans.md").exists() and not (social / "humans.csv").exists()


def test_config_hash_follows_the_policy_file_digest(
    rooms, walker_policy_path, write_walker, learned_run, tmp_path
):
    out = tmp_path / "store"
    shutil.copytree(learned_run, out)
    # The same bytes under another name: read back from the store.
    copy = shutil.copy(walker_policy_path, tmp_path / "copy.safetensors")
    again = run(config(f"learned:{copy}"), out, rooms)
    assert (again.computed, again.reused) == (0, TRIALS)
    # Another policy file: another config hash, every trial runs again, nothing overwritten.
    slower = write_walker(tmp_path / "slow.safetensors", speed=0.5)
    other = run(config(f"learned:{slower}"), out, rooms)
    assert (other.computed, other.reused) == (TRIALS, 0)
    hashes = {r["config_hash"] for r in stored(out)}
    assert len(hashes) == 2
    recorded = json.loads((out / "config.json").read_text())
    assert recorded["benchmark"]["humans"] == f"learned:{slower}"


def test_bad_human_specs_fail_naming_them(tmp_path):
    with pytest.raises(ValueError, match=r"BenchmarkConfig.humans: .*no such learned policy file"):
        config(f"learned:{tmp_path / 'missing.safetensors'}")
    with pytest.raises(
        ValueError, match=r"BenchmarkConfig.humans: .* is a folder, not a learned policy file"
    ):
        config(f"learned:{tmp_path}")
    with pytest.raises(ValueError, match=r"BenchmarkConfig.humans: .*unknown model 'robots'"):
        config("robots")
    with pytest.raises(ValueError, match="name the learned policy file as learned:PATH"):
        config("learned")


def test_the_people_spec_is_the_envs_and_learner_driven_humans_are_refused(walker_policy_path, rooms):
    walker = f"learned:{walker_policy_path}"
    assert people_overrides(config(walker)) == {"people": {"models": walker, "counterfactual": False}}
    mix = f"{walker}@0.4+sf@0.6"
    assert people_overrides(config(mix, counterfactual=True)) == {
        "people": {"models": mix, "counterfactual": True}
    }
    assert people_overrides(config("social_force")) == people_overrides(config("sf")) == {}
    # The hash names a learned file by its bytes; other specs as they are.
    assert walker_policy_path.name not in hashed_people(mix) and "sha256:" in hashed_people(mix)
    assert hashed_people("sf@0.5+orca@0.5") == "sf@0.5+orca@0.5"
    # num_learned_humans are a learner's agents (multi-agent training): a benchmark has none.
    with pytest.raises(
        ValueError, match="num_learned_humans = 2 asks for human agents that a learner drives"
    ):
        config(walker, env_overrides={"num_learned_humans": 2})
    learner_slots = env_config_for(rooms["rooms"], num_learned_humans=2)
    with pytest.raises(ValueError, match="'rooms-test' has num_learned_humans = 2"):
        RunSpec(test_sets=rooms, env_configs={"rooms-test": learner_slots})


def test_cli_benchmark_with_learned_humans(rooms_map_path, walker_policy_path, tmp_path, capsys):
    out = tmp_path / "results"
    argv = ["benchmark", "--policies", "ref", "--maps", str(rooms_map_path), "--trials", "2"]
    argv += ["--max-steps", "60", "--workers", "1", "--batch-size", "2", "--no-figures", "--no-progress"]
    argv += ["--humans", f"learned:{walker_policy_path}@0.5+sf@0.5", "--human-metrics"]
    assert socialzoo_main([*argv, "--out", str(out)]) == 0
    assert "2 trials run, 0 read from the store" in capsys.readouterr().out
    assert (out / "humans.md").is_file() and (out / "humans.csv").is_file()
    env = next(iter(json.loads((out / "config.json").read_text())["env_configs"].values()))
    assert env["people"]["models"] == f"learned:{walker_policy_path}@0.5+sf@0.5"
    assert env["num_learned_humans"] == 0
    # A missing file is named.
    assert socialzoo_main(["benchmark", "--humans", "learned:nowhere.safetensors", "--out", str(out)]) == 2
    assert "nowhere.safetensors" in capsys.readouterr().err
