"""People specs: parsing, named errors, and the seeded assignment of each scenario's people."""

import numpy as np
import pytest

from socialzoo.humans.models import PeopleConfig, PeopleSpecError, assign_models, head_counts, parse_people


def test_specs_name_models_and_shares():
    assert [(p.model, p.share, p.path) for p in parse_people("sf")] == [("sf", 1.0, None)]
    assert parse_people("social_force")[0].model == "sf"
    mix = parse_people("sf@0.5 + orca@0.3 + learned:runs/h.safetensors@0.2")
    assert [(p.model, p.share) for p in mix] == [("sf", 0.5), ("orca", 0.3), ("learned", 0.2)]
    assert mix[2].path == "runs/h.safetensors" and mix[2].name == "learned:runs/h.safetensors"


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("robots", "unknown model 'robots'"),
        ("sf@0.5+orca@0.4", "the shares sum to 0.9, not 1"),
        ("sf@0.5+orca", "every model of a mix needs its share"),
        ("sf@1.5", r"must be in \(0, 1\]"),
        ("sf@half", "must be a number"),
        ("orca@0.5+orca@0.5", "names the model 'orca' twice"),
        ("sf@0.5+sf-eth-ucy@0.5", r"names the model 'sf' twice \(the preset sf-eth-ucy sets sf's parameters"),
        # Two reacting models in one crowd: the message said only that 'hybrid' was named twice.
        (
            "hybrid:sf@0.5+hybrid:orca@0.5",
            r"'hybrid' twice \(the hybrid people of a crowd react as one model",
        ),
        ("learned", "name the learned policy file as learned:PATH"),
        ("orca:fast", "orca takes no file"),
        ("", "non-empty string"),
    ],
)
def test_bad_specs_fail_naming_what_is_wrong(spec, message):
    with pytest.raises(PeopleSpecError, match=message):
        parse_people(spec)
    with pytest.raises(ValueError, match=f"PeopleConfig.models: .*{message}"):
        PeopleConfig(models=spec)


def test_a_learned_policys_file_name_may_hold_plus_and_at_signs():
    """A learned policy's path such as runs/a+b/x@2.safetensors was split as a mix ('+') and a share
    ('@'): "unknown model 'b/x'". A '+' before a part that names no model, or an '@' before no number,
    after learned:PATH belongs to the path; a mix still splits where a model follows."""
    (part,) = parse_people("learned:runs/a+b/x@2.safetensors")
    assert (part.model, part.path, part.share) == ("learned", "runs/a+b/x@2.safetensors", 1.0)
    (part,) = parse_people("hybrid:learned:runs/a+b/x.safetensors")
    assert (part.model, part.reacts_as, part.path) == ("hybrid", "learned", "runs/a+b/x.safetensors")
    learned, sf = parse_people("learned:runs/a+b/x.safetensors@0.4+sf@0.6")
    assert (learned.path, learned.share, sf.model, sf.share) == ("runs/a+b/x.safetensors", 0.4, "sf", 0.6)
    with pytest.raises(PeopleSpecError, match="unknown model 'robots'"):
        parse_people("sf@0.5+robots@0.5")  # not a learned part before it: a model's name, unknown


def test_bad_group_sizes_and_flags_are_refused():
    with pytest.raises(ValueError, match=r"PeopleConfig.group_sizes\[1\] must be >= 0.0"):
        PeopleConfig(group_sizes=(1.0, -1.0, 0.0))
    with pytest.raises(ValueError, match="3 weights"):
        PeopleConfig(group_sizes=(1.0, 1.0))
    with pytest.raises(ValueError, match="counterfactual must be a bool"):
        PeopleConfig(counterfactual="yes")
    assert PeopleConfig(group_sizes=[1, 0, 0]).group_sizes == (1.0, 0.0, 0.0)


def test_head_counts_follow_the_shares():
    assert head_counts([0.5, 0.3, 0.2], 10).tolist() == [5, 3, 2]
    assert head_counts([0.5, 0.5], 7).tolist() == [4, 3]
    assert head_counts([1 / 3] * 3, 5).sum() == 5


def test_assignment_is_seeded_per_scenario():
    parts = parse_people("sf@0.6+orca@0.4")
    a = assign_models(parts, 20, seed=11)
    assert np.array_equal(a, assign_models(parts, 20, seed=11))
    assert np.bincount(a).tolist() == [12, 8]
    assert any(not np.array_equal(a, assign_models(parts, 20, seed=s)) for s in range(12, 20))
    assert assign_models(parse_people("orca"), 5, seed=1).tolist() == [0] * 5


def test_fitted_presets_name_their_model_and_set_its_parameters() -> None:
    import numpy as np

    from socialzoo.core.config import WorldConfig
    from socialzoo.core.walls import WallIndex
    from socialzoo.env.core import BatchedCore
    from socialzoo.humans.models import MODEL_IDS, ORCA, PeopleConfig, parse_people
    from socialzoo.humans.presets import PRESETS

    (part,) = parse_people("orca-eth-ucy")
    assert (part.model, part.preset, part.name) == ("orca", "orca-eth-ucy", "orca-eth-ucy")
    assert MODEL_IDS[part.model] == ORCA
    assert parse_people("hybrid:sf-eth-ucy")[0].name == "hybrid:sf-eth-ucy"
    world = WorldConfig()
    core = BatchedCore(1, 1, 2, world, WallIndex(np.zeros((0, 4))), people=PeopleConfig(models="sf-eth-ucy"))
    for field, value in PRESETS["sf-eth-ucy"]["human"].items():
        assert getattr(core.world.human, field) == value
    assert core.world.orca == world.orca
    plain = BatchedCore(1, 1, 2, world, WallIndex(np.zeros((0, 4))))
    assert plain.world == world
