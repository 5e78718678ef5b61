"""Lines of the package's Python source at one or more commits, split into code, docstrings,
comments and blank lines: the figures behind "fewer lines in socialzoo/" (issue "One world, one
task interface"), read from git so that any commit can be measured without checking it out.

With --without, files matching any of the given glob patterns are left out of the count (for
example the files that exist only for features added after a commit, to compare the same
features).

Run: python tools/line_report.py [--without 'socialzoo/scenarios/suite*.py' ...] REV [REV ...]
"""

from __future__ import annotations

import argparse
import ast
import fnmatch
import subprocess
import sys
from pathlib import Path

# The repository this tool belongs to: git reads it wherever the tool is run from (from tools/, a
# relative --folder matched nothing and every count was 0).
REPO = Path(__file__).resolve().parent.parent


def git(*args: str) -> str:
    """The output of `git args` in REPO; a failure (an unknown revision) ends the run naming it."""
    out = subprocess.run(["git", "-C", str(REPO), *args], capture_output=True, text=True)
    if out.returncode:
        sys.exit(f"line_report: git {' '.join(args)}: {out.stderr.strip()}")
    return out.stdout


def files_at(rev: str, folder: str) -> list[str]:
    """The .py files under `folder` (relative to the repository's root) at commit `rev`."""
    out = git("ls-tree", "-r", "--name-only", rev, "--", folder)
    return [name for name in out.splitlines() if name.endswith(".py")]


def docstring_lines(tree: ast.AST) -> set[int]:
    """Line numbers (1-based) of every module, class and function docstring."""
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                if isinstance(first.value.value, str):
                    lines.update(range(first.lineno, (first.end_lineno or first.lineno) + 1))
    return lines


def count(source: str) -> dict[str, int]:
    """{"code", "docstring", "comment", "blank"} line counts of one file."""
    docs = docstring_lines(ast.parse(source))
    counts = {"code": 0, "docstring": 0, "comment": 0, "blank": 0}
    for number, line in enumerate(source.splitlines(), 1):
        text = line.strip()
        kind = (
            "blank"
            if not text
            else "docstring"
            if number in docs
            else "comment"
            if text[0] == "#"
            else "code"
        )
        counts[kind] += 1
    return counts


def report(rev: str, folder: str, without: list[str]) -> dict[str, int]:
    """Summed counts of the folder's files at `rev`, less those matching `without`."""
    total = {"files": 0, "code": 0, "docstring": 0, "comment": 0, "blank": 0}
    for name in files_at(rev, folder):
        if any(fnmatch.fnmatch(name, pattern) for pattern in without):
            continue
        source = git("show", f"{rev}:{name}")
        total["files"] += 1
        for kind, n in count(source).items():
            total[kind] += n
    return total


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("revs", nargs="+", help="commits to measure")
    p.add_argument("--folder", default="socialzoo", help="relative to the repository's root")
    p.add_argument("--without", action="append", default=[], help="glob of files to leave out (repeatable)")
    args = p.parse_args()
    print(
        f"{'commit':12s} {'files':>6s} {'total':>7s} {'code':>7s} {'docstring':>9s} {'comment':>7s} {'blank':>6s}"
    )
    for rev in args.revs:
        t = report(rev, args.folder, args.without)
        lines = t["code"] + t["docstring"] + t["comment"] + t["blank"]
        print(
            f"{rev[:12]:12s} {t['files']:6d} {lines:7d} {t['code']:7d} {t['docstring']:9d} "
            f"{t['comment']:7d} {t['blank']:6d}"
        )


if __name__ == "__main__":
    main()
