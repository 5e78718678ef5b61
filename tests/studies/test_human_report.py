"""`socialzoo humans report`: how each crowd model walks, one row and one figure per model."""

import numpy as np
import pytest

from socialzoo.cli import main as socialzoo_main
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.studies.human_report import (
    HumanReportConfig,
    human_report,
    model_slug,
    targets,
    weidmann_speed,
)

SMALL = {
    "map": "open_room",
    "scenarios": 2,
    "seconds": 4.0,
    "scenario": ScenarioConfig(min_humans=4, max_humans=6),
}


def test_weidmann_curve():
    assert weidmann_speed(np.array([5.4, 6.0])).tolist() == [0.0, 0.0]
    assert 1.3 < weidmann_speed(np.array([0.1]))[0] <= 1.34
    assert weidmann_speed(np.array([2.0]), free_speed=1.0)[0] == pytest.approx(
        weidmann_speed(np.array([2.0]))[0] / 1.34
    )


def test_report_rows_and_files(tmp_path, walker_policy_path):
    config = HumanReportConfig(humans=("sf", "orca", f"learned:{walker_policy_path}"), **SMALL)
    results, files = human_report(config, tmp_path, figures=False)
    assert [r.spec for r in results] == list(config.humans)
    for r in results:
        assert r.row["people"] > 0 and 0.0 < r.row["mean_speed"] < 1.5
        assert r.row["pp_contacts_per_min"] >= 0 and len(r.speed) == len(r.density) > 0
    assert results[1].row["pp_contacts_per_min"] == 0.0  # ORCA people keep apart
    text = (tmp_path / "report.md").read_text()
    assert "| orca |" in text and "reach" in text
    assert {p.name for p in files} == {"report.md", "report.csv", "config.json"}
    assert model_slug(f"sf@0.5+learned:{walker_policy_path}@0.5") == "sf0.5-learned0.5"


def test_learned_targets_are_checked_against_the_social_force():
    rows = [
        {"model": "sf", "reach_rate": 0.5, "pw_contacts_per_min": 0.2},
        {"model": "learned:a", "reach_rate": 0.46, "pw_contacts_per_min": 0.1},
        {"model": "learned:b", "reach_rate": 0.4, "pw_contacts_per_min": 0.3},
    ]
    assert targets(rows) == {
        "learned:a": {"reach": True, "wall_contacts": True},
        "learned:b": {"reach": False, "wall_contacts": False},
    }


def test_bad_report_configs_fail_naming_them():
    with pytest.raises(ValueError, match="unknown model 'robots'"):
        HumanReportConfig(humans=("robots",))
    with pytest.raises(ValueError, match="must not set people"):
        HumanReportConfig(env_overrides={"people": {"models": "orca"}})
    with pytest.raises(ValueError, match=r"HumanReportConfig\.scenarios must be an int >= 1"):
        HumanReportConfig(scenarios=0)


def test_cli_humans_report(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out = tmp_path / "report"
    argv = ["humans", "report", "--humans", "sf,groups", "--map", "open_room", "--scenarios", "1"]
    assert socialzoo_main([*argv, "--seconds", "2", "--out", str(out)]) == 0
    assert "| groups |" in capsys.readouterr().out
    assert (out / "walk_sf.png").is_file() and (out / "walk_groups.png").is_file()
    assert socialzoo_main(["humans", "report", "--humans", "sf@0.5", "--out", str(out)]) == 2
    assert "the shares sum to 0.5, not 1" in capsys.readouterr().err


def test_a_preset_walks_with_its_fitted_parameters(tmp_path):
    # sf-eth-ucy relaxes four times slower and pushes weakly: its people walk otherwise than sf's.
    config = HumanReportConfig(humans=("sf", "sf-eth-ucy"), **SMALL)
    plain, fitted = (r.row for r in human_report(config, tmp_path, figures=False)[0])
    assert plain["mean_speed"] != fitted["mean_speed"]


def test_an_unknown_map_fails_leaving_no_folder(tmp_path, capsys):
    out = tmp_path / "report"
    assert socialzoo_main(["humans", "report", "--map", "nowhere", "--out", str(out)]) == 2
    assert "unknown map 'nowhere'" in capsys.readouterr().err
    assert not out.exists()


def test_the_shipped_learned_humans_are_named_learned_not_by_this_machines_path(tmp_path, capsys):
    """`socialzoo humans report --humans learned` labelled its row, its figure and config.json with
    the shipped file's absolute path (learned:/home/.../socialzoo/agents/shipped/humans.safetensors)."""
    from socialzoo.agents import SHIPPED_DIR

    out = tmp_path / "report"
    argv = ["humans", "report", "--humans", "sf,learned", "--map", "open_room", "--scenarios", "1"]
    assert socialzoo_main([*argv, "--seconds", "2", "--out", str(out), "--no-figures"]) == 0
    assert "| learned |" in capsys.readouterr().out
    for name in ("report.md", "report.csv", "config.json"):
        assert str(SHIPPED_DIR) not in (out / name).read_text(), name
