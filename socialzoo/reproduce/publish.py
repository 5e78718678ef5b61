"""Publishing a reproduction into the repository: DIR's small results, tables and figures go to results/reproduction/
and the report to REPRODUCTION.md at the root, with links into that folder."""

from __future__ import annotations

import shutil
from pathlib import Path

from socialzoo.reproduce.report import FIGURES_DIR, REPORT_NAME, TABLES_DIR, render_reproduction
from socialzoo.reproduce.results import RESULTS_DIR, load

PUBLISHED_DIR = "results/reproduction"


def regenerate_report(base_dir: str | Path, prefix: str = "") -> str:
    """The report of the results in base_dir/results/, linking the figures present in
    base_dir/figures/ through `prefix` (the path from the report to base_dir).

    It needs that folder alone; the tests compare it with the committed REPRODUCTION.md, so the
    committed numbers are those of the committed results.
    """
    base = Path(base_dir)
    figures = {p.stem for p in (base / FIGURES_DIR).glob("*.png")}
    return render_reproduction(load(base / RESULTS_DIR), prefix, figures)


def publish(out_dir: str | Path, repo_root: str | Path) -> Path:
    """Copy DIR/results, DIR/tables and DIR/figures into repo_root/results/reproduction/ (replacing
    what was there) and write repo_root/REPRODUCTION.md; returns the report's path."""
    source, root = Path(out_dir), Path(repo_root)
    target = root / PUBLISHED_DIR
    for name in (RESULTS_DIR, TABLES_DIR, FIGURES_DIR):
        if (target / name).exists():
            shutil.rmtree(target / name)
        if (source / name).is_dir():
            shutil.copytree(source / name, target / name)
    path = root / REPORT_NAME
    path.write_text(regenerate_report(target, PUBLISHED_DIR + "/"))
    return path


def redraw_published(repo_root: str | Path) -> Path:
    """Draw repo_root/results/reproduction/'s tables and figures again from its results, and write
    repo_root/REPRODUCTION.md (after rows of it were replaced: socialzoo.reproduce.rerun_rows);
    returns the report's path."""
    from socialzoo.reproduce.figures import draw_figures
    from socialzoo.reproduce.tables import build_tables, write_tables

    root = Path(repo_root)
    base = root / PUBLISHED_DIR
    results = load(base / RESULTS_DIR)
    write_tables(build_tables(results), base / TABLES_DIR)
    draw_figures(results, base / FIGURES_DIR)
    path = root / REPORT_NAME
    path.write_text(regenerate_report(base, PUBLISHED_DIR + "/"))
    return path
