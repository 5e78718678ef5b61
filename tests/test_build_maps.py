"""tools/build_maps.py rebuilds every shipped map byte for byte (maps/README.md promises it)."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_build_maps_reproduces_the_shipped_maps(tmp_path):
    run = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "build_maps.py"), "--out-dir", str(tmp_path)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    built = sorted(p.name for p in tmp_path.glob("*.json"))
    assert built == sorted(p.name for p in (ROOT / "maps").glob("*.json")), "every shipped map is built"
    for name in built:
        assert (tmp_path / name).read_bytes() == (ROOT / "maps" / name).read_bytes(), name
