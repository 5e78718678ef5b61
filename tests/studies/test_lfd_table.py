"""The LfD table: policy files evaluated on the same first scenarios of gdc1-test, stored and read
back, written beside the paper's numbers."""

import csv
import itertools

import numpy as np
import pytest

from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.policy_file import current_env_version
from socialzoo.studies.lfd import (
    CSV_COLUMNS,
    PAPER_LFD,
    find_lfd_policies,
    lfd_policy_file,
    run_lfd_evaluation,
    write_lfd_md,
)


def _write_policy(path, name, seed):
    rng = np.random.default_rng(seed)
    sizes = [107, 8, 4]
    weights = [(rng.normal(size=(o, i)), rng.normal(size=o)) for i, o in itertools.pairwise(sizes)]
    header = {"env_id": f"socialzoo/ActionSelection-v{current_env_version()}", "training": {"algo": name}}
    return MlpPolicy(name, weights, "tanh", {"layout": "paper", "num_human_slots": 25}).save(path, header)


@pytest.fixture
def lfd_root(tmp_path):
    root = tmp_path / "lfd"
    _write_policy(lfd_policy_file(root, "bc", 3_500), "bc", 0)
    _write_policy(lfd_policy_file(root, "gail", 3_500), "gail", 1)
    _write_policy(lfd_policy_file(root, "bc", 155_400), "bc", 2)
    return root


def test_policies_are_found_by_name_and_size(lfd_root):
    found = find_lfd_policies(lfd_root)
    assert sorted(found) == [("bc", 3_500), ("bc", 155_400), ("gail", 3_500)]
    assert found[("bc", 3_500)] == lfd_root / "bc_3500" / "bc.safetensors"


def test_evaluation_writes_the_table_and_resumes_from_the_store(lfd_root, tmp_path):
    policies = find_lfd_policies(lfd_root)
    out = tmp_path / "eval"
    kwargs = dict(trials=2, workers=1, batch_size=4, env_overrides={"max_steps": 40}, progress=False)
    result = run_lfd_evaluation(policies, out, **kwargs)
    assert result.computed == 6 and result.reused == 0
    # Paper order: BC before GAIL, largest set first.
    assert [(r["policy"], r["demonstration_steps"]) for r in result.rows] == [
        ("bc", 155_400), ("bc", 3_500), ("gail", 3_500)
    ]  # fmt: skip
    for row in result.rows:
        assert row["trials"] == 2 and 0.0 <= row["success_rate"] <= 1.0
        assert (row["paper_success_pct"], row["paper_average_step_reward"]) == PAPER_LFD[
            (row["policy"], row["demonstration_steps"])
        ]
    with (out / "lfd.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert tuple(rows[0]) == CSV_COLUMNS and len(rows) == 3
    md = (out / "lfd.md").read_text()
    assert "| BC | 155,400 |" in md and "| 84 |" in md and "| GAIL | 3,500 |" in md
    again = run_lfd_evaluation(policies, out, **kwargs)
    assert again.computed == 0 and again.reused == 6 and again.rows == result.rows


def test_a_missing_policy_file_is_named(tmp_path):
    with pytest.raises(ValueError, match="gail"):
        run_lfd_evaluation({("gail", 3_500): tmp_path / "nope.safetensors"}, tmp_path / "out")


def test_markdown_leaves_unknown_paper_cells_empty(tmp_path):
    row = dict.fromkeys(CSV_COLUMNS)
    row.update(policy="pips", demonstration_steps=3_500, success_rate=0.5, success_ci_low=0.4)
    row.update(success_ci_high=0.6, average_step_reward=0.1)
    text = write_lfd_md([row], tmp_path / "t.md", 10).read_text()
    assert "| PIPS | 3,500 | 50.0 [40.0, 60.0] |  | 0.100 |  |" in text
