"""Packaging: every subpackage is listed in pyproject.toml and a built wheel carries the maps."""

import subprocess
import sys
import zipfile
from pathlib import Path

import tomllib

ROOT = Path(__file__).resolve().parents[1]


def test_every_subpackage_is_listed():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {
        ".".join(p.parent.relative_to(ROOT).parts)
        for p in (ROOT / "socialzoo").rglob("__init__.py")
        if "__pycache__" not in p.parts
    }
    assert found - listed == set(), f"add these to [tool.setuptools] packages: {sorted(found - listed)}"
    assert "socialzoo._maps" in listed


def test_wheel_ships_the_maps(tmp_path):
    """A non-editable install gets the maps inside the package (socialzoo/_maps/*.json)."""
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            str(ROOT),
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(tmp_path),
        ],
        check=True,
        capture_output=True,
    )
    (wheel,) = tmp_path.glob("socialzoo-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    shipped = {p.name for p in (ROOT / "maps").glob("*.json")}
    assert shipped and {f"socialzoo/_maps/{name}" for name in shipped} <= names
    assert "socialzoo/core/world.py" in names
    # The shipped learned policies and their run records.
    policies = {p.name for p in (ROOT / "socialzoo" / "agents" / "shipped").glob("*.*")}
    assert {f"socialzoo/agents/shipped/{name}" for name in policies} <= names
