"""socialzoo.studies.ref_tradeoff: a setting is dominated only by one with at least its success
and less blame, a setting's row is Ref's own metrics on validation scenarios, and the table and
the command say so."""

from pathlib import Path

import numpy as np
import pytest

from socialzoo.cli import main
from socialzoo.studies import ref_tradeoff
from socialzoo.studies.ref_tradeoff import RefTradeoff, RefTradeoffConfig

ROOT = Path(__file__).resolve().parents[2]


def test_dominated_needs_as_much_success_and_less_blame():
    ref = {"success": 0.9, "blame": 0.03}
    assert ref_tradeoff.dominated(ref, [ref, {"success": 0.9, "blame": 0.02}])
    assert not ref_tradeoff.dominated(ref, [ref, {"success": 0.89, "blame": 0.01}])
    assert not ref_tradeoff.dominated(ref, [ref, {"success": 0.95, "blame": 0.03}])
    assert not ref_tradeoff.dominated(ref, [ref])


def test_a_wider_corridor_halts_more_and_so_blames_less():
    narrow = ref_tradeoff.evaluate(
        "gdc1", 3, {"corridor_half_width": 0.3, "lookahead_margin": 0.9, "heading_tolerance": 0.8}
    )
    wide = ref_tradeoff.evaluate(
        "gdc1", 3, {"corridor_half_width": 3.0, "lookahead_margin": 0.9, "heading_tolerance": 0.8}
    )
    assert narrow["corridor_half_width"] == 0.3 and 0.0 <= narrow["success"] <= 1.0
    assert wide["blame"] < narrow["blame"]


def test_a_halt_offset_copy_changes_only_the_halt_score(tmp_path):
    from socialzoo.agents.mlp import MlpPolicy
    from socialzoo.nav.subpolicies import HALT

    shipped = ROOT / "socialzoo" / "agents" / "shipped" / "dagger.safetensors"
    original = MlpPolicy.load(shipped)
    obs = np.random.default_rng(0).normal(size=(64, original.input_size)).astype(np.float32)
    same = MlpPolicy.load(ref_tradeoff.with_halt_offset(f"dagger:{shipped}", 0.0, tmp_path).partition(":")[2])
    halts = MlpPolicy.load(
        ref_tradeoff.with_halt_offset(f"dagger:{shipped}", 1e3, tmp_path).partition(":")[2]
    )
    assert np.array_equal(same.act(obs), original.act(obs))
    assert (halts.act(obs) == HALT).all() and not (original.act(obs) == HALT).all()
    shift = halts.scores(obs) - original.scores(obs)
    assert np.allclose(shift[:, HALT], 1e3) and np.allclose(np.delete(shift, HALT, axis=1), 0.0, atol=1e-4)
    assert halts.header["training"]["halt_offset"] == 1e3
    # A learned policy named alone is its shipped file.
    by_name = MlpPolicy.load(ref_tradeoff.with_halt_offset("dagger", 0.0, tmp_path).partition(":")[2])
    assert np.array_equal(by_name.act(obs), original.act(obs))
    assert by_name.header["training"]["from"] == "dagger"


def test_the_table_marks_dominated_rows_and_counts_the_policies():
    settings = ref_tradeoff.ref_settings()
    assert len(settings) == 18 and settings[0] == {
        "corridor_half_width": 0.45,
        "lookahead_margin": 0.4,
        "heading_tolerance": 0.8,
    }
    rows = [{**s, "success": 0.9, "blame": 0.02 + 0.001 * k, "human_collision": 1, "not_reached": 0}
            for k, s in enumerate(settings[:2])]  # fmt: skip
    learned = [("dagger:F", -1.0, {"success": 0.95, "blame": 0.01})]
    table = ref_tradeoff.tradeoff_table(RefTradeoff(RefTradeoffConfig(trials=7), rows, learned, 3.2))
    lines = table.splitlines()
    assert lines[2] == "| 0.45 | 0.4 | 0.8 | 90.0 | 0.0200 | 1 | 0 | no |"
    assert lines[3].endswith("| yes |")
    assert "| dagger:F | -1 | 95.0 | 0.0100 | no |" in lines
    assert lines[-1] == "3 policies x 7 gdc1-val scenarios in 3 s"


@pytest.mark.parametrize(
    ("words", "message"),
    [
        (["--halt-offsets=1,x"], "comma-separated numbers"),
        (["--learned", "no-colon"], "unknown policy 'no-colon'"),
        (["--learned", "ref"], "'ref' is not a learned MlpPolicy"),
        (["--learned", "dagger:missing.safetensors"], "no such file"),
        (["--trials", "0"], "positive integer"),
    ],
)
def test_the_command_refuses_bad_options(words, message, capsys):
    try:
        status = main(["study", "ref-tradeoff", *words])
    except SystemExit as stop:
        status = stop.code
    assert status == 2 and message in capsys.readouterr().err
