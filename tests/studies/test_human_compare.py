"""compare_humans: both populations on the same scenarios, the table, figure and targets; and
`socialzoo humans compare`."""

import pytest

from socialzoo.cli import main as socialzoo_main
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet
from socialzoo.studies.human_compare import ComparisonConfig, check_targets, compare_humans


def row(population, reach, hh=1.0, hw=0.0, hr=0.0, map_name="m"):
    return {
        "population": population,
        "map": map_name,
        "humans_goal_rate_mean": reach,
        "humans_hh_collisions_mean": hh,
        "humans_hw_collisions_mean": hw,
        "humans_hr_collisions_mean": hr,
    }


def test_targets_reach_within_ten_percent_and_no_more_collisions():
    assert check_targets([row("social_force", 0.8), row("learned", 0.73)])["m"] == {
        "reach": True,
        "collisions": True,
        "met": True,
    }
    assert not check_targets([row("social_force", 0.8), row("learned", 0.71)])["m"]["reach"]
    more = check_targets([row("social_force", 0.8), row("learned", 0.9, hr=0.1)])["m"]
    assert more == {"reach": True, "collisions": False, "met": False}


def test_compare_humans_runs_both_populations_on_the_same_scenarios(
    rooms_map_path, walker_policy_path, tmp_path
):
    pytest.importorskip("matplotlib")
    rooms = {
        "rooms": TestSet(
            str(rooms_map_path), 7, 20, ScenarioConfig(min_humans=3, max_humans=5), name="rooms-test"
        )
    }
    config = ComparisonConfig(
        humans=f"learned:{walker_policy_path}",
        maps=("rooms",),
        trials=3,
        workers=1,
        batch_size=3,
        env_overrides={"max_steps": 120},
    )
    result = compare_humans(config, tmp_path, test_sets=rooms, progress=False)
    assert [(r["population"], r["map"], r["trials"]) for r in result.rows] == [
        ("social_force", "rooms", 3),
        ("learned", "rooms", 3),
    ]
    assert set(result.targets["rooms"]) == {"reach", "collisions", "met"}
    assert {p.name for p in result.files} == {"comparison.csv", "comparison.md", "comparison.png"}
    text = (tmp_path / "comparison.md").read_text()
    assert (
        "| route goal reach rate |" in text
        and "| robot success rate |" in text
        and "Targets on rooms" in text
    )
    # A rerun reads both populations back from their stores and finds the same rows.
    again = compare_humans(config, tmp_path, test_sets=rooms, progress=False, figures=False)
    assert again.rows == result.rows or str(again.rows) == str(result.rows)  # NaN != NaN


def test_cli_rejects_social_force_and_names_bad_input(tmp_path, capsys):
    assert socialzoo_main(["humans", "compare", "--humans", "social_force", "--out", str(tmp_path)]) == 2
    assert "ComparisonConfig.humans must be 'learned:PATH'" in capsys.readouterr().err
    assert (
        socialzoo_main(["humans", "compare", "--humans", "learned:nowhere.st", "--out", str(tmp_path)]) == 2
    )
    assert "nowhere.st" in capsys.readouterr().err


def test_validation_scenarios_are_no_test_set(tmp_path, walker_policy_path, capsys):
    from socialzoo.scenarios.scenario_sets import TEST_SETS, validation_set
    from socialzoo.studies.rl_curves import VALIDATION_SET

    val = validation_set("ghc3")
    assert val.name == "ghc3-val" and val.map_name == "ghc3" and len(val) == 1000
    assert val.base_seed not in {t.base_seed for t in TEST_SETS.values()}
    assert VALIDATION_SET == validation_set("gdc1")  # the RL curves' choices use the same scenarios
    with pytest.raises(ValueError, match=r"quick .* and validation exclude each other"):
        ComparisonConfig(humans=f"learned:{walker_policy_path}", quick=True, validation=True)
    with pytest.raises(SystemExit):
        socialzoo_main(
            [
                "humans",
                "compare",
                "--humans",
                f"learned:{walker_policy_path}",
                "--quick",
                "--validation",
                "--out",
                str(tmp_path),
            ]
        )
    assert "not allowed with argument" in capsys.readouterr().err
