"""What a re-run may differ by: two trainings of one seed in one process give the same weights
(BC, and PPO through SB3), torch's settings are the run's only, and every run record names the
machine facts that decide torch-trained numbers (socialzoo.train.machine)."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

from socialzoo.env.policy_file import read_policy_file
from socialzoo.train.machine import KERNEL_FLAGS, cpu_facts, machine_facts

CPUINFO = """processor\t: 0
vendor_id\t: GenuineIntel
model name\t: Intel(R) Xeon(R) Platinum 8480+
flags\t\t: fpu sse4_2 avx avx2 fma avx512f avx512bw avx512_vnni amx_tile

processor\t: 1
model name\t: something else
"""


def weights_digest(path) -> str:
    tensors, _ = read_policy_file(path)
    h = hashlib.sha256()
    for key in sorted(tensors):
        h.update(key.encode())
        h.update(np.ascontiguousarray(tensors[key]).tobytes())
    return h.hexdigest()


def test_cpu_facts_from_cpuinfo():
    facts = cpu_facts(CPUINFO)
    assert facts["model"] == "Intel(R) Xeon(R) Platinum 8480+" and facts["vendor"] == "GenuineIntel"
    assert facts["kernel_flags"] == [
        "sse4_2",
        "avx",
        "avx2",
        "fma",
        "avx512f",
        "avx512bw",
        "avx512_vnni",
        "amx_tile",
    ]
    assert set(facts["kernel_flags"]) <= set(KERNEL_FLAGS)


def test_machine_facts_are_plain_json():
    pytest.importorskip("torch")
    facts = machine_facts()
    assert json.loads(json.dumps(facts)) == facts
    assert facts["python"] and facts["numpy"]["version"] and facts["cpu"]["logical_cpus"]
    torch = facts["torch"]
    assert torch["version"] and torch["threads"] >= 1 and torch["interop_threads"] >= 1
    assert "cpu_capability" in torch["build"] and isinstance(torch["mkldnn_available"], bool)


@pytest.fixture(scope="module")
def two_bc_runs(small_demos, tmp_path_factory):
    """Two BC trainings of one seed, one after the other in this process."""
    from socialzoo.train.bc import Args, train

    root = tmp_path_factory.mktemp("bc_twice")
    args = dict(demos=small_demos, steps=1500, hidden=(32, 32), epochs=1, min_updates=60, batch_size=64)
    return [
        train(Args(**args, out=root / name, checkpoint_every=60, progress=False, seed=5)) for name in "ab"
    ]


def test_bc_twice_same_weights(two_bc_runs):
    first, second = two_bc_runs
    assert first.read_bytes() != b""
    assert weights_digest(first) == weights_digest(second)


def test_run_record_names_the_machine(two_bc_runs):
    import torch

    record = json.loads((two_bc_runs[0].parent / "run.json").read_text())
    machine = record["machine"]
    assert machine["cpu"]["model"] and isinstance(machine["cpu"]["kernel_flags"], list)
    assert machine["torch"]["version"] == torch.__version__
    assert machine["torch"]["threads"] == 1  # the run's (args.threads), not the process's
    assert machine["torch"]["deterministic_algorithms"] is True
    assert machine["numpy"]["version"] == np.__version__ and machine["python"]
    # The settings were the run's only.
    assert not torch.are_deterministic_algorithms_enabled()


def test_ppo_twice_same_weights(tmp_path):
    pytest.importorskip("stable_baselines3")
    from socialzoo.train.ppo import PPOArgs, train

    common = dict(
        total_steps=200, checkpoint_every=200, num_envs=4, n_steps=50, n_epochs=1, map="open_room",
        family="circle_crossing", max_steps=100, seed=2, progress=False,
    )  # fmt: skip
    first = train(PPOArgs(out=tmp_path / "a", **common))
    second = train(PPOArgs(out=tmp_path / "b", **common))
    assert weights_digest(first) == weights_digest(second)
    record = json.loads((first.parent / "run.json").read_text())
    assert record["machine"]["torch"]["threads"] == 1
