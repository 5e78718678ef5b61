"""Compacting a task and its core: every per-row array is carried over (a new one added to the task,
the core, its plans, metrics or state and forgotten here fails this test), and the kept rows step on
exactly as they would have in the full batch, with two robots per row."""

import dataclasses

import numpy as np
import pytest

from socialzoo.env.compaction import compact_core
from socialzoo.env.config import EnvConfig
from socialzoo.env.scenario_source import with_robots
from socialzoo.env.tasks.action_selection import ActionSelectionTask
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario

B, R = 5, 2
KEEP = [4, 1, 3]


@pytest.fixture(scope="module")
def stepped_task(rooms_map_path):
    """A task of B rows and R robots, stepped 40 times with seeded random actions."""
    config = EnvConfig(
        map=str(rooms_map_path), scenario=ScenarioConfig(min_humans=2, max_humans=6), num_robots=R
    )
    task = ActionSelectionTask(config, B)
    scenarios = [
        with_robots(generate_scenario(task.map, 100 + i, config.scenario), task.map, R) for i in range(B)
    ]
    task.reset_rows(np.arange(B), scenarios)
    rng = np.random.default_rng(0)
    for _ in range(40):
        task.step(rng.integers(0, 4, (B, R)))
    return task


def plain(summaries):
    """Summaries with NaN replaced by a marker (NaN != NaN)."""
    return [{k: "nan" if v != v else v for k, v in s.items()} for s in summaries]


def arrays_of(obj):
    """The numpy arrays held by an object's attributes (dataclass fields included)."""
    return {k: v for k, v in vars(obj).items() if isinstance(v, np.ndarray)}


# What compaction starts afresh on purpose: the sight-line cache (it only saves work), the
# state before the last step (the next step writes it before reading it), and the bank of
# recordings (the kept rows' reset fills it with their recordings and points them there).
NOT_CARRIED = {"task.core.sight", "task.core.before", "task.core.replay.bank"}


def nested_pairs(where, a, b, depth=0):
    """(path, old object, new object) for an object and every socialzoo object it holds, found by
    walking attributes (so per-row state nested anywhere, such as the navigator's recovery, is
    checked without being listed here)."""
    if where in NOT_CARRIED or depth > 4 or a is b:  # the same object: shared (walls, map, graph)
        return
    yield where, a, b
    for name, value in vars(a).items():
        if (
            hasattr(value, "__dict__")
            and type(value).__module__.startswith("socialzoo.")
            and not callable(value)
        ):
            yield from nested_pairs(f"{where}.{name}", value, getattr(b, name), depth + 1)


def test_every_per_row_array_is_carried_over(stepped_task):
    old = stepped_task
    new = old.compact(KEEP)
    robot_rows = [row * R + k for row in KEEP for k in range(R)]
    assert new.batch_size == new.core.batch_size == len(KEEP)
    checked = 0
    for where, a, b in nested_pairs("task", old, new):
        for name, value in arrays_of(a).items():
            got = getattr(b, name)
            if value.shape[:1] == (B,):
                want = value[KEEP]
            elif value.shape[:1] == (B * R,):
                want = value[robot_rows]
            elif value.shape[1:2] == (B,):
                want = value[:, KEEP]  # rows on the second axis (the people's counterfactual pairs)
            else:
                want = value  # shared by every row (e.g. the learned-human slots)
            np.testing.assert_array_equal(got, want, err_msg=f"{where}.{name}")
            checked += 1
    assert checked >= 60
    assert new.core.scenarios == [old.core.scenarios[i] for i in KEEP]
    assert dataclasses.fields(new.core.state) == dataclasses.fields(old.core.state)
    assert new.core.sight is not old.core.sight  # a fresh cache: it only saves work


def test_kept_rows_step_on_as_in_the_full_batch(stepped_task):
    full = stepped_task.compact(range(B))  # a copy: the fixture stays as it is
    small = stepped_task.compact(KEEP)
    rng = np.random.default_rng(1)
    robot_rows = [row * R + k for row in KEEP for k in range(R)]
    for _ in range(60):
        actions = rng.integers(0, 4, (B, R))
        a = full.step(actions).detail
        b = small.step(actions[KEEP]).detail
        for field in ("obs", "reward", "terminated", "truncated", "force", "blame", "human_collisions"):
            np.testing.assert_array_equal(getattr(b, field), getattr(a, field)[KEEP], err_msg=field)
    assert plain(small.metrics.summaries()) == plain(full.metrics.summaries(robot_rows))


def test_a_compacted_core_judges_recorded_contacts_as_the_full_one(stepped_task, monkeypatch):
    # The CrowdNav task's cores count people walking into the robot by its in-step judgement
    # (contacts_in_step); a compacted core built without it would count world contacts instead.
    for judged_in_step in (True, False):
        monkeypatch.setattr(stepped_task.core.replay, "contacts_in_step", judged_in_step)
        assert compact_core(stepped_task.core, KEEP).replay.contacts_in_step is judged_in_step


def test_bad_rows(stepped_task):
    for rows in ([], [1, 1], [B]):
        with pytest.raises(ValueError, match=r"distinct rows of 0\.\.4"):
            compact_core(stepped_task.core, rows)
    fresh = ActionSelectionTask(stepped_task.config, 2, map_data=stepped_task.map)
    with pytest.raises(RuntimeError, match="never reset"):
        compact_core(fresh.core, [0])


def same(a, b):
    """Equal arrays, NaN equal to NaN."""
    return np.array_equal(a, b, equal_nan=a.dtype.kind in "fc")


def test_scripted_rows_are_carried_over():
    """A suite family's scripts (people who stop, wait at a door, stay) live in the core's script
    runner: compacting keeps each kept row's script where it was, and the rows step on alike."""
    from socialzoo.scenarios.catalogue import get_family

    family = get_family("entering_elevator")  # the doors close, people are released
    task = ActionSelectionTask(EnvConfig(map=None, family=family.name), 3)
    task.reset_rows(np.arange(3), [family.make(seed, m=task.map) for seed in (1, 2, 3)])
    rng = np.random.default_rng(0)
    script = task.core.script
    at_reset = {name: value.copy() for name, value in arrays_of(script).items()}
    for _ in range(400):  # until the scripts' own state has moved on from the reset's
        task.step(rng.integers(0, 4, (3, 1)))
        moved = [name for name, value in arrays_of(script).items() if not same(value, at_reset[name])]
        if moved:
            break
    assert script.scripted.all() and moved
    keep = [2, 0]
    full, small = task.compact(range(3)), task.compact(keep)
    for name, value in arrays_of(task.core.script).items():
        np.testing.assert_array_equal(getattr(small.core.script, name), value[keep], err_msg=f"script.{name}")
    for _ in range(80):
        actions = rng.integers(0, 4, (3, 1))
        a, b = full.step(actions).detail, small.step(actions[keep]).detail
        np.testing.assert_array_equal(b.obs, a.obs[keep])
