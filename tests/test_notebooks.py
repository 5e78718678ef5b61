"""The notebooks run top to bottom in a Jupyter kernel (quick mode), and are committed without outputs."""

import json
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
# Every notebook reads this in its first code cell and shrinks its runs (episodes, training steps).
QUICK_ENV = "SOCIALZOO_QUICK"
# Notebooks that only draw stored results (nothing to shrink); tests/reproduce runs this one on the
# output of `socialzoo reproduce --quick`, and here it draws the committed results/reproduction.
DRAW_STORED_RESULTS = {"reproduce_paper.ipynb"}


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path, monkeypatch, tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    monkeypatch.setenv(QUICK_ENV, "1")  # the kernel inherits the environment
    monkeypatch.setenv("MPLBACKEND", "Agg")
    # A temp folder of its own: an SB3 model learning without a logger leaves an empty SB3-<date>
    # folder there (the quickstart's PPO left one in /tmp on every run).
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    notebook = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    )
    client.execute()  # raises CellExecutionError naming the cell on any error
    assert any(cell.get("outputs") for cell in notebook.cells if cell.cell_type == "code")
    assert list(tmp_path.glob("SB3-*")) == []


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_reads_quick_mode_first(path):
    if path.name in DRAW_STORED_RESULTS:
        pytest.skip(f"{path.name} draws stored results only")
    cells = [c for c in json.loads(path.read_text())["cells"] if c["cell_type"] == "code"]
    assert cells and QUICK_ENV in "".join(cells[0]["source"]), (
        f"{path.name}: read {QUICK_ENV} in the first code cell"
    )


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_is_stripped(path):
    """Committed notebooks hold no outputs (run `nbstripout notebooks/*.ipynb` before committing)."""
    for cell in json.loads(path.read_text())["cells"]:
        if cell["cell_type"] == "code":
            assert cell.get("outputs") == [], f"{path.name}, cell {cell.get('id')}: outputs not stripped"
            assert cell.get("execution_count") is None, f"{path.name}, cell {cell.get('id')}: execution count"


def test_there_is_a_notebook():
    assert NOTEBOOKS


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_is_stored_without_outputs(path):
    for cell in json.loads(path.read_text())["cells"]:
        if cell["cell_type"] == "code":
            assert cell["outputs"] == [] and cell["execution_count"] is None, cell["source"][:1]
