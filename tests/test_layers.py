"""The layering (DEVELOPERS.md, Layout): no module of socialzoo imports a layer above its own.

Every module under socialzoo/ is parsed (ast, never imported): imports at the top, inside
functions and under `if TYPE_CHECKING:` all count, relative imports are resolved, and so are
dotted module strings such as registry entries ("socialzoo.agents.engineered:GoAlone") that are
imported by name at run time. Docstrings are not read.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "socialzoo"

# Rank of each subpackage: a module may import its own subpackage and lower ranks only; equal
# ranks are peers that must not import each other. A new subpackage fails the test until it is
# given a rank here (and in DEVELOPERS.md).
RANKS: dict[str, int] = {
    "core": 0,
    "humans": 1,
    "nav": 1,
    "render": 2,
    "env": 3,
    "agents": 4,
    "bench": 5,
    "train": 6,
    "studies": 7,
    "reproduce": 8,
    "cli": 9,
}
# Subpackages that hold data only: anyone may name them.
DATA = {"_maps"}
# Top-level modules and the subpackages each may import.
TOP_LEVEL: dict[str, set[str]] = {
    "socialzoo": {"env"},  # importing socialzoo registers the Gymnasium ids
    "socialzoo.__main__": {"cli"},  # python -m socialzoo
}

_MODULE_STRING = re.compile(r"socialzoo(\.[A-Za-z_]\w*)+(:[A-Za-z_]\w*)?")


def _docstrings(tree: ast.AST) -> set[int]:
    """ids of the docstring constants of the module, its classes and functions."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                found.add(id(body[0].value))
    return found


def imported_modules(module: str, source: str, *, is_package: bool = False) -> list[tuple[str, int]]:
    """(absolute module name, line) of every socialzoo module that `source` imports or names.

    Args:
        module: the dotted name of the module the source belongs to.
        source: its Python source.
        is_package: the source is the package's __init__.py (relative imports start there).
    """
    tree = ast.parse(source)
    package = module if is_package else module.rpartition(".")[0]
    docstrings = _docstrings(tree)
    found: list[tuple[str, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1])
                target = f"{base}.{node.module}" if node.module else base
            else:
                target = node.module or ""
            # `from socialzoo import env` imports the subpackage; `from socialzoo import __version__`
            # reads the top-level package only.
            if target == "socialzoo":
                found += [
                    (f"socialzoo.{a.name}" if a.name in RANKS or a.name in DATA else "socialzoo", node.lineno)
                    for a in node.names
                ]
            else:
                found.append((target, node.lineno))
        elif (
            isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and id(node) not in docstrings
            and _MODULE_STRING.fullmatch(node.value)
        ):
            found.append((node.value.partition(":")[0], node.lineno))
    return [(name, line) for name, line in found if name == "socialzoo" or name.startswith("socialzoo.")]


def _layer(module: str, is_package: bool) -> str | None:
    """The subpackage of a dotted module name, or None for a top-level module (socialzoo/*.py)."""
    parts = module.split(".")
    if len(parts) == 1 or (len(parts) == 2 and not is_package):
        return None
    return parts[1]


def upward_imports(module: str, source: str, *, is_package: bool = False) -> list[str]:
    """What is wrong with the imports of `module` (empty when it respects the layering)."""
    own = _layer(module, is_package)
    problems = []
    if own is None:
        allowed = TOP_LEVEL.get(module)
        if allowed is None:
            return [f"{module}: a top-level module not listed in TOP_LEVEL"]
    elif own not in RANKS:
        return [f"{module}: subpackage {own!r} has no rank in RANKS"]
    for target, line in imported_modules(module, source, is_package=is_package):
        layer = target.split(".")[1] if "." in target else None
        if layer is None or layer in DATA or layer == own:
            continue  # the top-level package itself (e.g. __version__), data, or its own layer
        where = f"{module}:{line} imports {target}"
        if layer not in RANKS:
            problems.append(f"{where}: subpackage {layer!r} has no rank in RANKS")
        elif own is None:
            if layer not in allowed:
                problems.append(f"{where}: the top-level module may import only {sorted(allowed)}")
        elif RANKS[layer] > RANKS[own]:
            problems.append(f"{where}: {layer} (rank {RANKS[layer]}) is above {own} (rank {RANKS[own]})")
        elif RANKS[layer] == RANKS[own]:
            problems.append(f"{where}: {layer} and {own} are peers (rank {RANKS[own]})")
    return problems


def _modules() -> list[tuple[str, Path]]:
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out.append((".".join(parts), path))
    return out


def test_every_subpackage_has_a_rank():
    subpackages = {
        p.parent.relative_to(PACKAGE).parts[0] for p in PACKAGE.rglob("*.py") if p.parent != PACKAGE
    }
    assert subpackages - set(RANKS) - DATA == set(), "give the new subpackage a rank in RANKS"
    assert set(RANKS) - {"train"} <= subpackages  # the ranks name real subpackages (train comes next)


def test_no_module_imports_a_higher_layer():
    modules = _modules()
    assert len(modules) > 50
    problems = [
        problem
        for module, path in modules
        for problem in upward_imports(module, path.read_text(), is_package=path.name == "__init__.py")
    ]
    assert problems == [], "\n".join(problems)


# ------------------------------------------------------------------ the checker on small sources
@pytest.mark.parametrize(
    ("module", "source", "expected"),
    [
        ("socialzoo.core.world", "from socialzoo.humans.motion import step", "humans (rank 1) is above core"),
        ("socialzoo.core.world", "import socialzoo.env.core as c", "env (rank 3) is above core"),
        ("socialzoo.agents.demos", "def f():\n    from socialzoo.bench import runner", "bench (rank 5)"),
        (
            "socialzoo.agents.base",
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from socialzoo.train.ppo import Args",
            "train (rank 6) is above agents",
        ),
        ("socialzoo.nav.graph", "from ..env import core", "imports socialzoo.env: env (rank 3)"),
        ("socialzoo.nav.graph", "from socialzoo.humans import routes", "humans and nav are peers"),
        ("socialzoo.humans.motion", "from socialzoo.nav.maps import Map", "nav and humans are peers"),
        ("socialzoo.env.parallel", "from socialzoo import bench", "imports socialzoo.bench"),
        ("socialzoo.agents.reg", 'POLICIES = {"ppo": "socialzoo.train.ppo:PPOPolicy"}', "train (rank 6)"),
        # Studies sit above the harness and the trainers they compose, below reproduce.
        (
            "socialzoo.bench.runner",
            "from socialzoo.studies.rl_curves import X",
            "studies (rank 7) is above bench",
        ),
        ("socialzoo.train.ppo", "from socialzoo.studies import lfd", "studies (rank 7) is above train"),
        (
            "socialzoo.studies.lfd",
            "from socialzoo.reproduce import plan",
            "reproduce (rank 8) is above studies",
        ),
        ("socialzoo.core.state", "from socialzoo.sim import step", "'sim' has no rank"),
        ("socialzoo.sim.step", "import numpy", "'sim' has no rank"),
        ("socialzoo", "from socialzoo.bench import runner", "may import only ['env']"),
        ("socialzoo.extras", "import numpy", "top-level module not listed"),
    ],
)
def test_the_checker_catches_an_upward_import(module, source, expected):
    problems = upward_imports(module, source)
    assert len(problems) == 1 and expected in problems[0], problems


@pytest.mark.parametrize(
    ("module", "source"),
    [
        ("socialzoo.env.core", "from socialzoo.core.state import WorldState\nfrom socialzoo.nav import maps"),
        ("socialzoo.env.core", "from . import reward\nfrom .world import step_world"),
        ("socialzoo.core.config", "from socialzoo import __version__\nimport socialzoo"),
        ("socialzoo.nav.maps", 'MAPS_PACKAGE = "socialzoo._maps"'),
        ("socialzoo.core.jit", '"""Used by socialzoo.env.world and socialzoo.bench.runner."""'),
        ("socialzoo.cli.main", "from socialzoo.train import ppo\nfrom socialzoo.bench import runner"),
        ("socialzoo", "from socialzoo.env.registration import register_envs"),
    ],
)
def test_the_checker_accepts_downward_imports(module, source):
    assert upward_imports(module, source) == []
