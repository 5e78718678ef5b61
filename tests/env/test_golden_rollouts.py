"""Seeded rollouts of a few cases per id family and adapter stay bit for bit what they were.

The digests (tests/env/golden_rollouts.json) come from tools/rollout_digests.py, recorded before the
task-interface refactor (commit 87ad9b0); a change that moves a seeded rollout on purpose bumps the
ids' version and records the digests again (`python tools/rollout_digests.py --out
tests/env/golden_rollouts.json`). Each case keeps the digests of its observations, rewards, end
flags and infos apart, so a failure says which part moved. They hold under the reference numerics
(tools/reference_numerics.py: numpy's kernels no wider than AVX2, which tests/conftest.py sets),
on any x86-64 machine. The one adapter per ecosystem changed
infos only, and their digests were recorded again then (observations, rewards and flags of every
case unchanged): CrowdNav's env, VectorEnv and ParallelEnv report the task's per-step "closest",
"force", "blame", "human_collisions" and "wall_collision" (the viewer's charts), its
final_info metrics are zeros outside the ended rows (as the benchmark's were, not NaN) and its
final_obs zeros outside them; the benchmark's VectorEnv final_info also carries the people's
metrics (group intrusions, counterfactual costs) that the single env reports.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

GOLDEN = json.loads((Path(__file__).parent / "golden_rollouts.json").read_text())

# A few cases per id family and adapter (the tool checks all of them).
CHECKED = [
    "single ActionSelection short",
    "vector ActionSelection short",
    "single ActionSelection velocity",
    "vector socialzoo/Doorway-v2",
    "vector ActionSelection people=learned:socialzoo/agents/shipped/humans.safetensors",
    "vector ActionSelection counterfactual",
    "single socialzoo/CrowdNav-v1",
    "vector socialzoo/CrowdNavWalls-v1",
    "vector CrowdNav discrete",
    "vector CrowdNav dict",
    "parallel benchmark 2 robots 3 learned",
    "parallel crowdnav 3 robots",
    "sb3 benchmark short",
    "torchrl multi-agent",
    "torchrl single",
    "torchrl crowdnav",
]


@pytest.mark.parametrize("case", CHECKED)
def test_seeded_rollout_is_bit_for_bit_the_recorded_one(case: str, load_tool, tmp_path, monkeypatch) -> None:
    assert load_tool("reference_numerics").numpy_follows_reference(), (
        "numpy runs with kernels wider than the digests' reference (tools/reference_numerics.py): "
        "it was imported before tests/conftest.py could set NPY_DISABLE_CPU_FEATURES"
    )
    monkeypatch.chdir(tmp_path)  # the tool runs from any folder (the learned case reads a shipped file)
    digests = load_tool("rollout_digests").record([case])[case]
    changed = {
        part: (GOLDEN[case][part], digests[part]) for part in digests if digests[part] != GOLDEN[case][part]
    }
    assert not changed, f"{case}: parts changed (recorded, now): {changed}"


def test_the_digest_tells_apart_rollouts_that_differ(load_tool) -> None:
    tool = load_tool("rollout_digests")
    a = tool.gym_single("socialzoo/CrowdNav-v1", seed=3, steps=20)
    b = tool.gym_single("socialzoo/CrowdNav-v1", seed=4, steps=20)
    assert a == tool.gym_single("socialzoo/CrowdNav-v1", seed=3, steps=20)
    assert a["obs"] != b["obs"]
