"""tools/ref_tradeoff.py: a setting is dominated only by one with at least its success and less
blame, and a setting's row is Ref's own metrics on validation scenarios."""

from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def tool(load_tool):
    return load_tool("ref_tradeoff")


def test_dominated_needs_as_much_success_and_less_blame(tool):
    ref = {"success": 0.9, "blame": 0.03}
    assert tool.dominated(ref, [ref, {"success": 0.9, "blame": 0.02}])
    assert not tool.dominated(ref, [ref, {"success": 0.89, "blame": 0.01}])
    assert not tool.dominated(ref, [ref, {"success": 0.95, "blame": 0.03}])
    assert not tool.dominated(ref, [ref])


def test_a_wider_corridor_halts_more_and_so_blames_less(tool):
    narrow = tool.evaluate(
        "gdc1", 3, {"corridor_half_width": 0.3, "lookahead_margin": 0.9, "heading_tolerance": 0.8}
    )
    wide = tool.evaluate(
        "gdc1", 3, {"corridor_half_width": 3.0, "lookahead_margin": 0.9, "heading_tolerance": 0.8}
    )
    assert narrow["corridor_half_width"] == 0.3 and 0.0 <= narrow["success"] <= 1.0
    assert wide["blame"] < narrow["blame"]


def test_a_halt_offset_copy_changes_only_the_halt_score(tool, tmp_path):
    from socialzoo.agents.mlp import MlpPolicy
    from socialzoo.nav.subpolicies import HALT

    shipped = ROOT / "socialzoo" / "agents" / "shipped" / "dagger.safetensors"
    original = MlpPolicy.load(shipped)
    obs = np.random.default_rng(0).normal(size=(64, original.input_size)).astype(np.float32)
    same = MlpPolicy.load(tool.with_halt_offset(f"dagger:{shipped}", 0.0, tmp_path).partition(":")[2])
    halts = MlpPolicy.load(tool.with_halt_offset(f"dagger:{shipped}", 1e3, tmp_path).partition(":")[2])
    assert np.array_equal(same.act(obs), original.act(obs))
    assert (halts.act(obs) == HALT).all() and not (original.act(obs) == HALT).all()
    shift = halts.scores(obs) - original.scores(obs)
    assert np.allclose(shift[:, HALT], 1e3) and np.allclose(np.delete(shift, HALT, axis=1), 0.0, atol=1e-4)
    assert halts.header["training"]["halt_offset"] == 1e3
