"""tools/ref_tradeoff.py: a setting is dominated only by one with at least its success and less
blame, and a setting's row is Ref's own metrics on validation scenarios."""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def tool():
    spec = importlib.util.spec_from_file_location("ref_tradeoff", ROOT / "tools" / "ref_tradeoff.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


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
