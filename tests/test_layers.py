"""The layering (DEVELOPERS.md, Layout): no module of socialzoo imports a layer above its own,
and no two modules import each other, directly or round a longer loop.

Every module under socialzoo/ is parsed (ast, never imported): imports at the top, inside
functions and under `if TYPE_CHECKING:` all count, relative imports are resolved, and so are
dotted module strings such as registry entries ("socialzoo.agents.engineered:GoAlone") that are
imported by name at run time. Docstrings are not read. The cycle check follows the import
statements that run (at the top and inside functions; not those under `if TYPE_CHECKING:`, which
never run, nor registry strings, which name the modules that register themselves there).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "socialzoo"

# Rank of each subpackage: a module may import its own subpackage and lower ranks only; equal
# ranks are peers that must not import each other. A new subpackage fails the test until it is
# given a rank here (and in DEVELOPERS.md).
RANKS: dict[str, int] = {
    "core": 0,
    "maps": 1,
    "data": 1,
    "nav": 2,
    "scenarios": 3,
    "humans": 4,
    "render": 4,
    "env": 5,
    "agents": 6,
    "bench": 7,
    "train": 8,
    "studies": 9,
    "reproduce": 10,
    "cli": 11,
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


def _parse(module: str, source: str, is_package: bool) -> tuple[ast.Module, str]:
    """The syntax tree of `source` and the package its relative imports start from."""
    return ast.parse(source), module if is_package else module.rpartition(".")[0]


def _from_target(package: str, node: ast.ImportFrom) -> str:
    """The absolute module of `from X import ...` in `package` (relative imports resolved)."""
    if not node.level:
        return node.module or ""
    parts = package.split(".")
    base = ".".join(parts[: len(parts) - node.level + 1])
    return f"{base}.{node.module}" if node.module else base


def imported_modules(module: str, source: str, *, is_package: bool = False) -> list[tuple[str, int]]:
    """(absolute module name, line) of every socialzoo module that `source` imports or names.

    Args:
        module: the dotted name of the module the source belongs to.
        source: its Python source.
        is_package: the source is the package's __init__.py (relative imports start there).
    """
    tree, package = _parse(module, source, is_package)
    docstrings = _docstrings(tree)
    found: list[tuple[str, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = _from_target(package, node)
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


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    """ids of the nodes under `if TYPE_CHECKING:` (imports for annotations, never run)."""
    found: set[int] = set()
    for node in ast.walk(tree):
        test = node.test if isinstance(node, ast.If) else None
        if (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
            isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
        ):
            found.update(id(inner) for child in node.body for inner in ast.walk(child))
    return found


def run_time_imports(module: str, source: str, *, is_package: bool = False) -> list[tuple[str, int]]:
    """(dotted name, line) of what each import statement of `source` that runs names.

    Statements at the top and inside functions count, those under `if TYPE_CHECKING:` do not;
    `from a.b import c` names "a.b.c", which is module a.b.c or a name defined in module a.b.
    The arguments are those of `imported_modules`.
    """
    tree, package = _parse(module, source, is_package)
    skipped = _type_checking_nodes(tree)
    found: list[tuple[str, int]] = []
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = _from_target(package, node)
            found += [(f"{target}.{alias.name}", node.lineno) for alias in node.names]
    return found


def import_graph(sources: dict[str, tuple[str, bool]]) -> nx.DiGraph:
    """Module -> the modules of `sources` it imports at run time (edge attribute `line`).

    Args:
        sources: dotted module name -> (its source, whether it is a package's __init__.py).
    """
    graph = nx.DiGraph()
    graph.add_nodes_from(sources)
    for module, (source, is_package) in sources.items():
        for name, line in run_time_imports(module, source, is_package=is_package):
            parts = name.split(".")
            while parts and ".".join(parts) not in sources:
                parts.pop()  # "a.b.c" names module a.b.c, or else something defined in a.b
            target = ".".join(parts)
            if target and target != module and not graph.has_edge(module, target):
                graph.add_edge(module, target, line=line)
    return graph


def import_cycles(sources: dict[str, tuple[str, bool]]) -> list[str]:
    """One loop of imports in each group of modules that import each other, as
    "a:LINE imports b, b:LINE imports a" (empty when there is none)."""
    graph = import_graph(sources)
    loops = []
    for group in nx.strongly_connected_components(graph):
        if len(group) > 1:
            edges = nx.find_cycle(graph.subgraph(group))
            loops.append(", ".join(f"{a}:{graph.edges[a, b]['line']} imports {b}" for a, b, *_ in edges))
    return sorted(loops)


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


def test_no_import_cycle():
    sources = {module: (path.read_text(), path.name == "__init__.py") for module, path in _modules()}
    cycles = import_cycles(sources)
    assert cycles == [], "move what both modules need into a module of its own:\n" + "\n".join(cycles)


# ------------------------------------------------------------------ the checker on small sources
@pytest.mark.parametrize(
    ("module", "source", "expected"),
    [
        ("socialzoo.core.world", "from socialzoo.humans.motion import step", "humans (rank 4) is above core"),
        ("socialzoo.core.world", "import socialzoo.env.core as c", "env (rank 5) is above core"),
        ("socialzoo.agents.demos", "def f():\n    from socialzoo.bench import runner", "bench (rank 7)"),
        (
            "socialzoo.agents.base",
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from socialzoo.train.ppo import Args",
            "train (rank 8) is above agents",
        ),
        ("socialzoo.nav.graph", "from ..env import core", "imports socialzoo.env: env (rank 5)"),
        ("socialzoo.nav.graph", "from socialzoo.humans import routes", "humans (rank 4) is above nav"),
        (
            "socialzoo.humans.motion",
            "from socialzoo.render.frames import draw",
            "render and humans are peers",
        ),
        ("socialzoo.env.parallel", "from socialzoo import bench", "imports socialzoo.bench"),
        ("socialzoo.agents.reg", 'POLICIES = {"ppo": "socialzoo.train.ppo:PPOPolicy"}', "train (rank 8)"),
        # Studies sit above the harness and the trainers they compose, below reproduce.
        (
            "socialzoo.bench.runner",
            "from socialzoo.studies.rl_curves import X",
            "studies (rank 9) is above bench",
        ),
        ("socialzoo.train.ppo", "from socialzoo.studies import lfd", "studies (rank 9) is above train"),
        (
            "socialzoo.studies.lfd",
            "from socialzoo.reproduce import plan",
            "reproduce (rank 10) is above studies",
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
        (
            "socialzoo.env.core",
            "from socialzoo.core.state import WorldState\nfrom socialzoo.maps import map_file",
        ),
        ("socialzoo.env.core", "from . import reward\nfrom .world import step_world"),
        ("socialzoo.core.config", "from socialzoo import __version__\nimport socialzoo"),
        ("socialzoo.maps.map_file", 'MAPS_PACKAGE = "socialzoo._maps"'),
        ("socialzoo.core.jit", '"""Used by socialzoo.env.world and socialzoo.bench.runner."""'),
        ("socialzoo.cli.main", "from socialzoo.train import ppo\nfrom socialzoo.bench import runner"),
        ("socialzoo", "from socialzoo.env.registration import register_envs"),
    ],
)
def test_the_checker_accepts_downward_imports(module, source):
    assert upward_imports(module, source) == []


@pytest.mark.parametrize(
    ("sources", "expected"),
    [
        # a function-level import back closes the loop (socialzoo.reproduce.parts and seeds once)
        (
            {
                "socialzoo.r.parts": "from socialzoo.r.seeds import write",
                "socialzoo.r.seeds": "def f():\n    from socialzoo.r.parts import rl_items",
            },
            ["socialzoo.r.parts:1 imports socialzoo.r.seeds, socialzoo.r.seeds:2 imports socialzoo.r.parts"],
        ),
        # `from package import module` and relative imports reach the module; three make a loop too
        (
            {
                "socialzoo.r": "from . import a",
                "socialzoo.r.a": "from socialzoo.r import b",
                "socialzoo.r.b": "import socialzoo.r.c as c",
                "socialzoo.r.c": "from .a import X",
            },
            [
                "socialzoo.r.a:1 imports socialzoo.r.b, socialzoo.r.b:1 imports socialzoo.r.c, "
                "socialzoo.r.c:1 imports socialzoo.r.a"
            ],
        ),
        # imports for annotations only never run
        (
            {
                "socialzoo.n.graph": "from socialzoo.n.attach import attach",
                "socialzoo.n.attach": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                "    from socialzoo.n.graph import Graph",
            },
            [],
        ),
        # a package that imports its modules, which import a name of another module of it
        (
            {
                "socialzoo.t": "from socialzoo.t.ppo import Args",
                "socialzoo.t.ppo": "from socialzoo.t.run import R",
                "socialzoo.t.run": "import numpy",
            },
            [],
        ),
    ],
)
def test_the_checker_finds_import_cycles(sources, expected):
    packages = {"socialzoo.r", "socialzoo.t"}
    assert import_cycles({m: (src, m in packages) for m, src in sources.items()}) == expected
