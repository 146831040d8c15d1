"""Every notebook in notebooks/ runs top to bottom at the reduced size
(``DIFFWEAR_NOTEBOOK_SIZE=small``), in a fresh kernel, in a temporary folder.

The notebooks assert their own numbers (e.g. notebook (a): worn volume
proportional to k within 5 %); a failing assert fails the test.  Skipped when
nbclient/ipykernel are not installed (the ``test`` extra installs them).
"""

import os
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
SRC = Path(__file__).resolve().parents[1] / "src"


def test_notebooks_found():
    assert NOTEBOOKS, "no notebooks/*.ipynb"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_small(path, tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    nb = nbformat.read(path, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), \
        f"{path.name} is saved with outputs; clear them"
    monkeypatch.setenv("DIFFWEAR_NOTEBOOK_SIZE", "small")
    # the kernel is a child process: make the source tree importable there too
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [str(SRC), *filter(None, [os.environ.get("PYTHONPATH")])]))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []))
    assert "small" in text
