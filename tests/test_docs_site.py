"""The documentation site builds without a warning, and its API reference covers every subpackage."""

import importlib
import os
import re
import shlex
import subprocess
import sys
import textwrap
from pathlib import Path

import gymnasium as gym
import pytest

from socialzoo.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]


def _subpackages() -> list[str]:
    return sorted(p.parent.name for p in (ROOT / "socialzoo").glob("*/__init__.py"))


def test_every_subpackage_has_an_api_page():
    nav = (ROOT / "mkdocs.yml").read_text()
    for name in _subpackages():
        page = ROOT / "docs" / "api" / f"{name}.md"
        assert page.is_file(), (
            f"no API page for socialzoo.{name}: add docs/api/{name}.md and list it in mkdocs.yml"
        )
        assert f"::: socialzoo.{name}" in page.read_text(), f"{page} does not render socialzoo.{name}"
        assert f"api/{name}.md" in nav, f"mkdocs.yml's nav does not list api/{name}.md"


def test_every_doc_page_is_in_the_nav():
    nav = (ROOT / "mkdocs.yml").read_text()
    for page in sorted((ROOT / "docs").rglob("*.md")):
        rel = page.relative_to(ROOT / "docs").as_posix()
        assert f": {rel}" in nav, f"docs/{rel} is not in mkdocs.yml's nav"


def test_pages_cite_nothing_outside_the_repository():
    # The docs cited machine factors from ../shared/tools/machine_factor.py, a tool of the
    # development machine that no reader has: a page's figures stand on what the repository holds.
    pages = [
        ROOT / "README.md",
        *sorted((ROOT / "docs").rglob("*.md")),
        *sorted((ROOT / "benchmarks").glob("*.py")),
    ]
    for page in pages:
        text = page.read_text()
        for outside in ("../shared/", "machine_factor", "machine factor"):
            assert outside not in text.lower(), f"{page.relative_to(ROOT)} cites {outside!r}"


def test_site_builds_strict(tmp_path):
    pytest.importorskip("mkdocs", reason="the docs extra: pip install -e '.[docs]'")
    pytest.importorskip("material", reason="the docs extra: pip install -e '.[docs]'")
    pytest.importorskip("mkdocstrings_handlers.python", reason="the docs extra: pip install -e '.[docs]'")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    run = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-4000:]
    assert "WARNING" not in run.stderr, run.stderr[-4000:]
    # The API reference rendered the env classes' docstrings.
    env_page = (tmp_path / "site" / "api" / "env" / "index.html").read_text()
    assert "ActionSelectionEnv" in env_page
    assert "Observation Space" in env_page


# The pages a new user reads first: their commands and Python examples are checked below.
PAGES = ["README.md", "maps/README.md"] + sorted(
    p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").glob("*.md")
)


def _blocks(page: str, language: str) -> list[str]:
    """The page's fenced blocks of `language`, dedented (a block may sit in a list item)."""
    text = (ROOT / page).read_text()
    return [
        textwrap.dedent(b) for b in re.findall(rf"^ *```{language}\n(.*?)^ *```", text, flags=re.S | re.M)
    ]


def _commands() -> list[tuple[str, str]]:
    """(page, command) of every `socialzoo ...` line of the pages' bash blocks."""
    found = []
    for page in PAGES:
        for block in _blocks(page, "bash"):
            for line in block.replace("\\\n", " ").splitlines():
                if line.strip().startswith("socialzoo "):
                    found.append((page, line.strip()))
    return found


@pytest.mark.parametrize(("page", "command"), _commands(), ids=lambda x: x if "/" in x else x[:70])
def test_doc_command_parses(page, command):
    # Every flag and subcommand a page shows exists, and its values are of the right kind.
    words = shlex.split(command, comments=True)[1:]
    try:
        build_parser(words).parse_args(words)
    except SystemExit as err:
        pytest.fail(f"{page}: `{command}` does not parse (exit {err.code})")


# Pages whose examples read the fetched ETH/UCY scenes; blocks that train for minutes (`.learn(`)
# run their imports only, so the names they use still exist.
NEEDS_DATA = ("docs/data.md", "docs/recorded.md")
NEEDS_MODULES = {"torchrl": "torchrl", "stable_baselines3": "stable_baselines3", "supersuit": "supersuit"}


# The guides whose examples are quick (README.md's are test_readme.py's); imitation.md, pips.md and
# reproduce.md show training runs of minutes and fragments of larger scripts.
PYTHON_PAGES = [
    "docs/index.md",
    "docs/tasks.md",
    "docs/recorded.md",
    "docs/data.md",
    "docs/humans.md",
    "docs/crowdnav.md",
    "docs/parallel_env.md",
    "docs/learning.md",
    "docs/guideline_metrics.md",
]


@pytest.mark.parametrize("page", PYTHON_PAGES)
def test_doc_python_examples_run(page, tmp_path, monkeypatch):
    """A page's Python blocks run in order in one namespace, as a reader pastes them."""
    blocks = _blocks(page, "python")
    for name, module in NEEDS_MODULES.items():
        if any(name in b for b in blocks):
            pytest.importorskip(module)
    if page in NEEDS_DATA:
        from socialzoo.data.fetch import SCENES, data_dir

        fetched = data_dir()
        if not all((fetched / f.name).is_file() for files in SCENES.values() for f in files):
            pytest.skip("the ETH/UCY scenes are not fetched (socialzoo data fetch eth-ucy)")
        # The recorded ids write their maps into the data folder: a copy, not the user's cache.
        for f in fetched.glob("*.txt"):
            (tmp_path / f.name).symlink_to(f)
        monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_tracks.txt").write_text(
        "".join(f"{10 * k}\t{p}\t{0.5 * k + p}\t{2.0 * p}\n" for k in range(20) for p in range(3))
    )
    namespace = {"__name__": "__doc__"}
    for block in blocks:
        if ".learn(" in block:
            block = "\n".join(line for line in block.splitlines() if line.startswith(("import ", "from ")))
        exec(compile(block, page, "exec"), namespace)


# The recipes' examples of names a reader adds (docs/architecture.md), not names the package has.
EXAMPLE_NAMES = {"socialzoo.x.y", "socialzoo.train.myalgo", "socialzoo.agents.mine"}
NAMED_PAGES = sorted(
    {*PAGES, "DEVELOPERS.md", "REPRODUCTION.md"}
    | {p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").rglob("*.md")}
)


def _resolve(name: str) -> str | None:
    """None when the dotted name is a module or an attribute path below one; else what is missing."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError as err:
            if err.name and not err.name.startswith("socialzoo"):
                pytest.skip(f"{name} needs {err.name} (an extra)")
            continue
        for k in range(i, len(parts)):
            if not hasattr(obj, parts[k]):
                return f"{'.'.join(parts[:k])} has no {parts[k]!r}"
            obj = getattr(obj, parts[k])
        return None
    return "no such module"


@pytest.mark.parametrize("page", NAMED_PAGES)
def test_doc_names_exist(page):
    # docs/api/bench.md named socialzoo.render.map_plot.save_drive_check_png, which never existed under
    # that name (save_map_check_png(..., drive=...) draws the drive check): a reader looking it up
    # found nothing. Every dotted socialzoo.* name a page gives is a module, or a name in one.
    text = (ROOT / page).read_text()
    names = {m.rstrip(".") for m in re.findall(r"\bsocialzoo(?:\.[A-Za-z_]\w*)+", text)}
    missing = []
    for name in sorted(names - EXAMPLE_NAMES):
        if name.endswith((".py", ".md", ".json", ".txt", ".html", ".safetensors")):
            continue  # a file name such as socialzoo.json
        why = _resolve(name)
        if why is not None:
            missing.append(f"{name} ({why})")
    assert not missing, f"{page} names what the package does not have: {missing}"


# The recipes' example of an id a reader registers (docs/architecture.md).
EXAMPLE_IDS = {"socialzoo/MyFamily-v2"}


@pytest.mark.parametrize("page", NAMED_PAGES)
def test_doc_env_ids_are_registered(page):
    # An id a page names is registered, or it is an earlier version of a registered id (a page's
    # history: gym.make of it raises DeprecatedEnv naming the current one), never an id that does not
    # exist at any version (a misspelt name, a version from the future).
    current: dict[str, int] = {}  # registered name -> its newest version
    for env_id in gym.registry:
        name, _, version = env_id.rpartition("-v")
        if env_id.startswith("socialzoo/") and version.isdigit():
            current[name] = max(current.get(name, -1), int(version))
    named = set(re.findall(r"\bsocialzoo/[A-Z]\w*-v\d+\b", (ROOT / page).read_text())) - EXAMPLE_IDS
    wrong = []
    for env_id in sorted(named):
        name, _, version = env_id.rpartition("-v")
        if env_id not in gym.registry and int(version) >= current.get(name, 0):
            wrong.append(env_id)
    assert not wrong, f"{page} names ids that are not registered at any version: {wrong}"
