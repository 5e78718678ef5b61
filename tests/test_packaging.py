"""Packaging: every folder of the package is listed in pyproject.toml and a wheel carries every file
of it: the modules, the maps and their reference data, the episode viewer's files, the shipped
policies, the scenario cards and the JSON Schemas."""

import importlib.metadata
import os
import re
import shutil
import subprocess
import sys
import tarfile
import warnings
import zipfile
from pathlib import Path, PurePosixPath

import pytest
import tomllib

ROOT = Path(__file__).resolve().parents[1]
# Where each source folder of the package lies in an install (pyproject.toml's package-dir).
INSTALLED_AS = {"socialzoo": "socialzoo", "maps": "socialzoo/_maps"}


def package_files() -> dict[str, str]:
    """The committed files of the package, by the name an install gives them:
    {"socialzoo/_maps/gdc1.json": "maps/gdc1.json", ...}; what `python -m build` reads from a clean
    checkout."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("needs the git checkout (git ls-files)")
    listed = subprocess.run(
        ["git", "ls-files", "-z", *INSTALLED_AS], check=True, capture_output=True, text=True, cwd=ROOT
    ).stdout
    files = {}
    for name in filter(None, listed.split("\0")):
        top, *rest = PurePosixPath(name).parts
        if (ROOT / name).is_file():  # not deleted in the working tree
            files["/".join([INSTALLED_AS[top], *rest])] = name
    return files


def test_every_folder_of_the_package_is_listed():
    """A folder of data alone (agents/shipped, scenarios/cards, ...) is a package to setuptools too:
    unlisted, a build warned that it was "absent from the `packages` configuration"."""
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(PurePosixPath(name).parent.parts) for name in package_files()}
    assert found - listed == set(), f"add these to [tool.setuptools] packages: {sorted(found - listed)}"
    assert "socialzoo._maps" in listed


def test_a_wheel_would_hold_every_file_of_the_package(tmp_path, monkeypatch):
    """setuptools' own plan of the wheel's files (build_py over the egg_info file list, which is what
    `python -m build` does, without building; about a second) holds every committed file under
    socialzoo/ and maps/, and the plan is made without setuptools' warnings. The social_gym reference
    data under maps/reference/ was left out, so `socialzoo map drive` on an install lacked two
    of its buildings."""
    from setuptools.config.pyprojecttoml import apply_configuration
    from setuptools.dist import Distribution

    monkeypatch.chdir(ROOT)
    dist = apply_configuration(Distribution(), "pyproject.toml")
    dist.script_name = "setup.py"  # as setuptools.build_meta runs it (sdist's defaults look for it)
    dist.get_command_obj("egg_info").egg_base = str(tmp_path)  # its files, not in the checkout
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        build_py = dist.get_command_obj("build_py")
        build_py.ensure_finalized()
        planned = build_py.get_output_mapping()  # {build_lib/socialzoo/...: source}
    held = {Path(dest).relative_to(build_py.build_lib).as_posix() for dest in planned}
    missing = set(package_files()) - held
    assert missing == set(), f"not in the wheel (pyproject.toml's package-data): {sorted(missing)}"
    said = [str(w.message).splitlines()[0] for w in caught if "setuptools" in w.category.__module__]
    assert said == []


def test_the_sdist_and_its_wheel_hold_every_file_of_the_package(tmp_path):
    """A non-editable install gets every file of the package, the maps inside it (socialzoo/_maps/):
    the wheel built from the sdist, as `python -m build` makes it, quietly; the sdist holds no tests.
    Both from a copy of the checkout's files: an egg-info folder left in the checkout by an earlier
    build adds the files its SOURCES.txt names to the next sdist."""
    committed = package_files()
    source = tmp_path / "source"
    for name in [*committed.values(), "pyproject.toml", "MANIFEST.in", "README.md", "LICENSE", "NOTICE"]:
        (source / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / name, source / name)
    build = "import sys; from setuptools import build_meta; getattr(build_meta, sys.argv[1])(sys.argv[2])"
    run = {"check": True, "capture_output": True, "text": True}
    subprocess.run([sys.executable, "-c", build, "build_sdist", str(tmp_path)], cwd=source, **run)
    (sdist,) = tmp_path.glob("socialzoo-*.tar.gz")
    with tarfile.open(sdist) as archive:
        archive.extractall(tmp_path / "unpacked", filter="data")
        in_sdist = {PurePosixPath(*PurePosixPath(name).parts[1:]).as_posix() for name in archive.getnames()}
    assert {"socialzoo", "maps", "pyproject.toml", "LICENSE"} <= in_sdist and "tests" not in in_sdist
    assert set(committed.values()) - in_sdist == set()
    (unpacked,) = (tmp_path / "unpacked").iterdir()
    built = subprocess.run([sys.executable, "-c", build, "build_wheel", str(tmp_path)], cwd=unpacked, **run)
    assert "is absent from the `packages` configuration" not in built.stderr
    (wheel,) = tmp_path.glob("socialzoo-*.whl")
    in_wheel = set(zipfile.ZipFile(wheel).namelist())
    assert set(committed) - in_wheel == set()


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
