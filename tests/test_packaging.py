"""Packaging: every subpackage is listed in pyproject.toml and a built wheel carries the maps, the
episode viewer's files and the shipped policies."""

import importlib.metadata
import os
import re
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest
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
    """A non-editable install gets the maps inside the package (socialzoo/_maps/*.json): the wheel
    built from the sdist, as `python -m build` makes it; the sdist holds no tests."""
    build_sdist = "import sys; from setuptools import build_meta; build_meta.build_sdist(sys.argv[1])"
    subprocess.run(
        [sys.executable, "-c", build_sdist, str(tmp_path)], check=True, capture_output=True, cwd=ROOT
    )
    (sdist,) = tmp_path.glob("socialzoo-*.tar.gz")
    with tarfile.open(sdist) as archive:
        top = {Path(name).parts[1] for name in archive.getnames() if len(Path(name).parts) > 1}
    assert {"socialzoo", "maps", "pyproject.toml", "LICENSE"} <= top and "tests" not in top
    pip_wheel = [sys.executable, "-m", "pip", "wheel", str(sdist), "--no-deps", "--no-build-isolation", "-q"]
    subprocess.run([*pip_wheel, "-w", str(tmp_path)], check=True, capture_output=True)
    (wheel,) = tmp_path.glob("socialzoo-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    shipped = {p.name for p in (ROOT / "maps").glob("*.json")}
    assert shipped and {f"socialzoo/_maps/{name}" for name in shipped} <= names
    assert "socialzoo/env/world.py" in names
    viewer = {f"socialzoo/render/viewer/{p.name}" for p in (ROOT / "socialzoo/render/viewer").iterdir()}
    assert len(viewer) == 3 and viewer <= names  # the episode viewer's page, stylesheet and script
    policies = {p.name for p in (ROOT / "socialzoo" / "agents" / "shipped").glob("*.*")}
    assert {f"socialzoo/agents/shipped/{name}" for name in policies} <= names


def _requirement_name(requirement: str) -> str:
    return re.split(r"[\s<>=!~;\[]", requirement, maxsplit=1)[0].lower().replace("_", "-")


def extra_only_modules() -> list[str]:
    """Top-level modules installed here whose distribution only an extra of pyproject.toml brings."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    core = {_requirement_name(r) for r in project["dependencies"]}
    extras = {_requirement_name(r) for reqs in project["optional-dependencies"].values() for r in reqs} - core
    return sorted(
        module
        for module, dists in importlib.metadata.packages_distributions().items()
        if {_requirement_name(d) for d in dists} & extras
    )


# Runs argv's socialzoo command with the extras' modules hidden, as after `pip install socialzoo`.
CORE_INSTALL = """
import sys
blocked = set(sys.argv[1].split(","))
class Hide:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in blocked:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, Hide())
from socialzoo.cli import main
sys.exit(main(sys.argv[2:]))
"""


def core_install(*argv: str, cwd: Path) -> subprocess.CompletedProcess:
    """`socialzoo ARGV` with the extras' modules hidden and the progress bar on."""
    return subprocess.run(
        [sys.executable, "-c", CORE_INSTALL, ",".join(extra_only_modules()), *argv],
        capture_output=True,
        text=True,
        cwd=cwd,
        env={**os.environ, "SOCIALZOO_PROGRESS": "bar", "PYTHONPATH": str(ROOT)},
    )


def test_a_core_install_runs_the_benchmark(tmp_path):
    """Without the extras (torch, matplotlib, ...), the benchmark runs Ref and a shipped learned
    policy with its progress bar: tqdm drew it, and tqdm was only in the extras."""
    blocked = extra_only_modules()
    assert {"torch", "matplotlib"} <= set(blocked) and "tqdm" not in blocked
    argv = ["benchmark", "--policies", "ref,ppo", "--maps", "gdc1", "--trials", "1", "--workers", "1"]
    done = core_install(*argv, "--no-figures", "--out", str(tmp_path), cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "summary.csv").is_file()


@pytest.mark.parametrize(
    "argv",
    [
        ("benchmark", "--policies", "ref", "--maps", "gdc1", "--trials", "1"),
        ("suite", "--policies", "ref", "--scenarios", "frontal_approach", "--seeds", "1"),
    ],
    ids=lambda argv: argv[0],
)
def test_figures_without_the_plot_extra_are_refused_before_the_run(tmp_path, argv):
    """They ran every trial, then stopped with a traceback of `No module named 'matplotlib'`."""
    done = core_install(*argv, "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 2, done.stderr[-2000:]
    assert "Traceback" not in done.stderr and "pip install 'socialzoo[plot]'" in done.stderr
    assert ("--no-figures" in done.stderr) == (argv[0] == "benchmark")
    assert not (tmp_path / "out" / "results.sqlite").exists()


def test_every_distribution_of_the_plot_train_and_ray_extras_names_its_extra():
    from socialzoo.cli import EXTRA_MODULES

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    installed = importlib.metadata.packages_distributions()
    for extra in ("plot", "train", "ray"):
        for requirement in project["optional-dependencies"][extra]:
            name = _requirement_name(requirement)
            modules = [m for m, dists in installed.items() if name in {_requirement_name(d) for d in dists}]
            if modules:  # installed here
                assert any(EXTRA_MODULES.get(m) == extra for m in modules), (name, modules)


@pytest.mark.parametrize(
    ("argv", "extra"),
    [
        (["map", "show", "gdc1", "--out", "map.png"], "plot"),
        (["train", "ppo", "--out", "ppo", "--total-steps", "2000"], "train"),
    ],
    ids=["map show", "train ppo"],
)
def test_a_command_that_needs_an_extra_names_it(tmp_path, argv, extra):
    """They ended in a traceback of `No module named 'matplotlib'` (or 'torch')."""
    done = core_install(*argv, cwd=tmp_path)
    assert done.returncode == 2, done.stderr[-2000:]
    assert "Traceback" not in done.stderr and f"pip install 'socialzoo[{extra}]'" in done.stderr
