"""EnvConfig: overrides, the plain-JSON round trip, and renamed fields refused by name."""

from __future__ import annotations

import gymnasium as gym
import pytest

import socialzoo  # noqa: F401  (registers the ids)
from socialzoo.env.config import RENAMED_FIELDS, EnvConfig
from socialzoo.env.parallel import parallel_env


def test_resolve_applies_overrides_to_a_base():
    assert EnvConfig.resolve() == EnvConfig()
    assert EnvConfig.resolve(None, {}) == EnvConfig()
    base = EnvConfig(map="open_room", max_steps=100)
    assert EnvConfig.resolve(base) is base
    got = EnvConfig.resolve(base, {"num_learned_humans": 2, "reward": {"success_bonus": 50.0}})
    assert got.map == "open_room" and got.max_steps == 100 and got.num_learned_humans == 2
    assert got.reward.success_bonus == 50.0 and got.reward.w_blame == base.reward.w_blame
    with pytest.raises(TypeError, match="EnvConfig"):
        EnvConfig.resolve({"map": "gdc1"})  # type: ignore[arg-type]


def test_round_trip_through_a_plain_dict():
    cfg = EnvConfig(map="open_room", num_robots=2, num_learned_humans=3)
    assert EnvConfig.from_dict(cfg.to_dict()) == cfg


@pytest.mark.parametrize("old", sorted(RENAMED_FIELDS))
def test_renamed_fields_are_refused_naming_the_new_name(old):
    new = RENAMED_FIELDS[old]
    message = f"{old} was renamed {new}"
    with pytest.raises(ValueError, match=message):
        EnvConfig.from_dict({**EnvConfig().to_dict(), old: 1})
    with pytest.raises(ValueError, match=message):
        EnvConfig().replace(**{old: 1})
    with pytest.raises(ValueError, match=message):
        EnvConfig.resolve(None, {old: 1})
    with pytest.raises(ValueError, match=message):
        gym.make("socialzoo/ActionSelection-v2", map="open_room", **{old: 1})
    with pytest.raises(ValueError, match=message):
        parallel_env(map="open_room", **{old: 1})


def test_unknown_fields_are_named():
    with pytest.raises(ValueError, match=r"unknown field\(s\) \['num_robot'\]"):
        EnvConfig().replace(num_robot=2)
    with pytest.raises(ValueError, match=r"EnvConfig.reward: unknown field"):
        EnvConfig().replace(reward={"bonus": 1.0})


@pytest.mark.parametrize("env_id", ["socialzoo/Doorway-v2", "socialzoo/CrowdNav-v1"])
def test_an_unknown_keyword_of_an_id_is_also_pythons_type_error(env_id):
    """An unknown keyword is a TypeError in Python's words as for any callable (it was a ValueError
    only), so callers that probe an optional keyword work: TorchRL's GymEnv passes frameskip and
    drops it on that error. It stays a ValueError naming the field and the known ones."""
    for error in (TypeError, ValueError):
        with pytest.raises(
            error,
            match=r"unknown field\(s\) \['frameskip'\]; known: .*unexpected keyword argument 'frameskip'",
        ):
            gym.make(env_id, frameskip=1)


@pytest.mark.parametrize("name", ["batch_size", "config", "task"])
def test_a_task_constructors_own_argument_given_as_a_config_field_is_named(name):
    """`--task-config batch_size=2` (or config=, task=) met the task constructor's own argument as a
    second value: a TypeError traceback from the benchmark, the replay and gym.make alike."""
    from socialzoo.bench.task_benchmark import TaskId
    from socialzoo.core.validation import UnknownFieldError

    message = rf"task 'crowdnav': '{name}' is not a config field"
    with pytest.raises(UnknownFieldError, match=message):
        TaskId.of("socialzoo/CrowdNav-v1").make(1, **{name: 2})
    if name == "batch_size":  # gym.make's config= and task= are the adapter's own arguments
        with pytest.raises(ValueError, match=message):
            gym.make("socialzoo/CrowdNav-v1", batch_size=2)


def test_map_data_must_be_a_loaded_map():
    from socialzoo.env.tasks import make_task

    with pytest.raises(ValueError, match=r"map_data must be a loaded Map .* got 'x'"):
        make_task("action_selection", 1, None, map="open_room", map_data="x")
