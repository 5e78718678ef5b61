"""The demonstration recorder: chunked recording, resuming after an interruption, config checks."""

import numpy as np
import pytest

from socialzoo.agents.demonstrations import DemonstrationError, load_demonstrations
from socialzoo.bench import demonstrations
from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations


@pytest.fixture
def rooms_path(rooms_map_path):
    return str(rooms_map_path)


@pytest.mark.parametrize(
    ("field", "value"),
    [("episodes", 0), ("chunk_episodes", 1.5), ("batch_size", True), ("base_seed", -1)],
)
def test_demo_config_refuses_bad_counts(field, value):
    with pytest.raises(ValueError, match=rf"DemoConfig\.{field} .*{value!r}"):
        DemoConfig(**{field: value})


def test_demo_config_refuses_an_unknown_policy():
    with pytest.raises(ValueError, match="unknown policy 'robocop'"):
        DemoConfig(policy="robocop")


def test_interrupted_recording_resumes(tmp_path, rooms_path, monkeypatch):
    config = DemoConfig(
        map=rooms_path, episodes=5, chunk_episodes=2, batch_size=2, env_overrides={"max_steps": 50}
    )
    whole = record_demonstrations(tmp_path / "whole.npz", config)

    real_write = demonstrations._write_npz
    calls = []

    def dying_write(path, arrays):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        real_write(path, arrays)

    monkeypatch.setattr(demonstrations, "_write_npz", dying_write)
    target = tmp_path / "resumed.npz"
    with pytest.raises(KeyboardInterrupt):
        record_demonstrations(target, config)
    monkeypatch.setattr(demonstrations, "_write_npz", real_write)
    partial, _ = load_demonstrations(target)  # the finished chunk is readable already
    assert partial["episode_ids"].tolist() == [0, 1]
    record_demonstrations(target, config)
    a, meta_a = load_demonstrations(whole)
    b, meta_b = load_demonstrations(target)
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    assert meta_a["config_hash"] == meta_b["config_hash"]
    other = DemoConfig(map=rooms_path, episodes=4, chunk_episodes=2, env_overrides={"max_steps": 50})
    with pytest.raises(DemonstrationError, match="another config"):
        record_demonstrations(target, other)


def test_demonstrations_are_none_of_the_maps_test_scenarios(tmp_path, rooms_path):
    """On a map without a registered test set the demonstrations' default base seed was its generated
    test set's (20220100): BC, GAIL, DAgger and PIPS trained on the scenarios the benchmark tests on."""
    from socialzoo.bench.test_sets import stored_test_set
    from socialzoo.scenarios.scenario_sets import map_case_sets

    demos = DemoConfig(map=rooms_path, episodes=3).test_set()
    tested = stored_test_set(rooms_path, tmp_path, 3)
    for k in range(3):
        a, b = demos.scenario(k), tested.scenario(k)
        assert a.seed != b.seed and not np.array_equal(a.human_spawn, b.human_spawn)
    assert demos.base_seed not in {ts.base_seed for ts in map_case_sets(rooms_path).values()}
    assert DemoConfig().base_seed == demonstrations.DEMO_BASE_SEED  # gdc1's demonstrations are as before
    with pytest.raises(ValueError, match=r"DemoConfig\.base_seed 20220100 .* test set of map"):
        DemoConfig(map=rooms_path, base_seed=20220100)
    with pytest.raises(ValueError, match=r"DemoConfig\.base_seed 20220001 .* test set of map 'gdc1'"):
        DemoConfig(base_seed=20220001)
