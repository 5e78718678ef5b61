"""tools/line_report.py counts the package's lines at a commit, wherever it is run from."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.skipif(not (ROOT / ".git").exists(), reason="reads the checkout's git history")


def run(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(ROOT / "tools" / "line_report.py"), *args],
        capture_output=True,
        text=True,
        cwd=cwd,
    )


def test_the_counts_are_the_same_from_any_folder():
    # Run from tools/ it printed "HEAD 0 0 0 0 0 0": git read the folder "socialzoo" under tools/.
    from_root, from_tools = run("HEAD", cwd=ROOT), run("HEAD", cwd=ROOT / "tools")
    assert from_root.returncode == 0 and from_tools.returncode == 0, from_tools.stderr
    assert int(from_root.stdout.splitlines()[1].split()[1]) > 100  # files
    assert from_tools.stdout == from_root.stdout


def test_an_unknown_revision_is_named():
    out = run("no-such-revision", cwd=ROOT)
    assert out.returncode == 1 and "no-such-revision" in out.stderr and "Traceback" not in out.stderr
