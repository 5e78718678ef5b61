"""Compacting a core: every per-row array is carried over (a new one added to the core, its plans,
metrics or state and forgotten here fails this test), and the kept rows step on exactly as they
would have in the full batch, with two robots per row."""

import dataclasses

import numpy as np
import pytest

from socialzoo.env.compaction import compact_core
from socialzoo.env.config import EnvConfig
from socialzoo.env.core import SocialNavCore
from socialzoo.env.scenario_source import with_robots
from socialzoo.scenarios.scenario import ScenarioConfig, generate_scenario

B, R = 5, 2
KEEP = [4, 1, 3]


@pytest.fixture(scope="module")
def stepped_core(rooms_map_path):
    """A core of B rows and R robots, stepped 40 times with seeded random actions."""
    config = EnvConfig(
        map=str(rooms_map_path), scenario=ScenarioConfig(min_humans=2, max_humans=6), num_robots=R
    )
    core = SocialNavCore(config, B)
    scenarios = [
        with_robots(generate_scenario(core.map, 100 + i, config.scenario), core.map, R) for i in range(B)
    ]
    core.reset_rows(np.arange(B), scenarios)
    rng = np.random.default_rng(0)
    for _ in range(40):
        core.step(rng.integers(0, 4, (B, R)))
    return core


def plain(summaries):
    """Summaries with NaN replaced by a marker (NaN != NaN)."""
    return [{k: "nan" if v != v else v for k, v in s.items()} for s in summaries]


def arrays_of(obj):
    """The numpy arrays held by an object's attributes (dataclass fields included)."""
    return {k: v for k, v in vars(obj).items() if isinstance(v, np.ndarray)}


def test_every_per_row_array_is_carried_over(stepped_core):
    old = stepped_core
    new = compact_core(old, KEEP)
    robot_rows = [row * R + k for row in KEEP for k in range(R)]
    assert new.batch_size == len(KEEP)
    pairs = [
        ("core", old, new),
        ("navigator", old.navigator, new.navigator),
        ("plans", old.navigator.plans, new.navigator.plans),
        ("metrics", old.metrics, new.metrics),
        ("state", old.state, new.state),
    ]
    checked = 0
    for where, a, b in pairs:
        for name, value in arrays_of(a).items():
            got = getattr(b, name)
            if value.shape[:1] == (B,):
                want = value[KEEP]
            elif value.shape[:1] == (B * R,):
                want = value[robot_rows]
            else:
                want = value  # shared by every row (e.g. the learned-human slots)
            np.testing.assert_array_equal(got, want, err_msg=f"{where}.{name}")
            checked += 1
    assert checked >= 30
    assert new.scenarios == [old.scenarios[i] for i in KEEP]
    assert dataclasses.fields(new.state) == dataclasses.fields(old.state)
    assert new.sight is not old.sight  # a fresh cache: it only saves work


def test_kept_rows_step_on_as_in_the_full_batch(stepped_core):
    full = compact_core(stepped_core, range(B))  # a copy: the fixture stays as it is
    small = compact_core(stepped_core, KEEP)
    rng = np.random.default_rng(1)
    robot_rows = [row * R + k for row in KEEP for k in range(R)]
    for _ in range(60):
        actions = rng.integers(0, 4, (B, R))
        a = full.step(actions)
        b = small.step(actions[KEEP])
        for field in ("obs", "reward", "terminated", "truncated", "force", "blame", "human_collisions"):
            np.testing.assert_array_equal(getattr(b, field), getattr(a, field)[KEEP], err_msg=field)
    assert plain(small.metrics.summaries()) == plain(full.metrics.summaries(robot_rows))


def test_bad_rows(stepped_core):
    for rows in ([], [1, 1], [B]):
        with pytest.raises(ValueError, match=r"distinct rows of 0\.\.4"):
            compact_core(stepped_core, rows)
    fresh = SocialNavCore(stepped_core.config, 2, map_data=stepped_core.map)
    with pytest.raises(RuntimeError, match="never reset"):
        compact_core(fresh, [0])
