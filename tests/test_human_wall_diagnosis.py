"""tools/human_wall_diagnosis.py runs on social-force and learned humans and prints its table."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_diagnosis_prints_a_row_per_policy(walker_policy_path):
    out = subprocess.run(
        [
            sys.executable,
            str(ROOT / "tools" / "human_wall_diagnosis.py"),
            "--scenarios",
            "2",
            "--steps",
            "40",
            "social_force",
            str(walker_policy_path),
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    rows = [line for line in out.splitlines() if line.startswith("| ") and "policy" not in line]
    assert [r.split("|")[1].strip() for r in rows] == ["social_force", str(walker_policy_path)]
    # The walker walks straight at its waypoint: no lateral action; social-force humans have none.
    assert rows[0].rstrip(" |").endswith("nan") and rows[1].rstrip(" |").endswith("+0.000")
