"""The notebooks in notebooks/ are stored executed at the reduced size
(``DIFFWEAR_NOTEBOOK_SIZE=small``, by ``docs/execute_notebooks.py``), so that
the site shows their outputs and figures; and they still give those outputs.

* fast: every code cell is stored executed, in order, at the small size, and
  every notebook holds at least one figure;
* ``--long``: each notebook runs top to bottom in a fresh kernel, in a
  temporary folder (the notebooks assert their own numbers, e.g. notebook
  (a): worn volume proportional to k within 5 %; a failing assert fails the
  test), and the numbers it prints match the stored ones.  Skipped when
  nbclient/ipykernel are not installed (the ``test`` extra installs them).
"""

import importlib.util
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
# a wall or compile time ("compile 18.9 s", "run 3.9 s", "120 ms") changes
# from run to run: left out of the comparison
DURATION = re.compile(r"[-+]?\d+\.?\d*(?:[eE][-+]?\d+)?\s*(?:s|ms|min)\b")
RTOL = 1e-3  # printed numbers carry 4-6 digits: a last-digit rounding flip is < 1e-3
# a number at round-off level of its output (e.g. a derivative that is 0 up to
# the tolerance of the solver) compares against the output's largest number
FLOOR = 1e-5


def _code_cells(nb) -> list:
    return [c for c in nb["cells"] if c["cell_type"] == "code"]


def _texts(cell) -> list[str]:
    """A cell's printed outputs: streams and plain-text results, in order."""
    out = []
    for o in cell.get("outputs", []):
        if o["output_type"] == "stream":
            out.append("".join(o["text"]))
        elif "text/plain" in o.get("data", {}):
            out.append("".join(o["data"]["text/plain"]))
    return out


def _numbers(text: str) -> list[float]:
    return [float(x) for x in NUMBER.findall(DURATION.sub(" ", text))]


def test_notebooks_found():
    assert NOTEBOOKS, "no notebooks/*.ipynb"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_is_stored_executed_at_the_small_size(path):
    nb = json.loads(path.read_text())
    cells = _code_cells(nb)
    counts = [c.get("execution_count") for c in cells]
    assert counts == list(range(1, len(cells) + 1)), \
        f"{path.name}: not stored executed top to bottom (execution counts {counts}); " \
        "run docs/execute_notebooks.py"
    errors = [o for c in cells for o in c.get("outputs", []) if o["output_type"] == "error"]
    assert not errors, f"{path.name} is stored with an error: {errors[0].get('ename')}"
    text = "".join(t for c in cells for t in _texts(c))
    assert "small" in text, f"{path.name}: stored at another size than the small one"
    figures = sum("image/png" in o.get("data", {}) for c in cells for o in c.get("outputs", []))
    assert figures >= 1, f"{path.name}: stored without a figure"


def _same(stored: list[float], fresh: list[float]) -> bool:
    if len(stored) != len(fresh):
        return False
    scale = FLOOR * max([abs(x) for x in stored + fresh] + [0.0])
    return all(abs(a - b) <= RTOL * max(abs(a), abs(b)) + scale for a, b in zip(stored, fresh))


def test_number_comparison_tells_a_change_from_rounding():
    """The comparison itself: a last-digit rounding flip and a round-off-level
    entry pass, a change in the third digit or a missing number fails."""
    assert _same(_numbers("lives [ 77511. 116063.]"), _numbers("lives [ 77512. 116063.]"))
    assert _same(_numbers("[[0. 3.00000e-02 8.28997e+03]]"), _numbers("[[0. 0. 8.28997e+03]]"))
    assert _same(_numbers("9 points: compile 18.9 s, run 3.9 s"),
                 _numbers("9 points: compile 25.0 s, run 4.4 s"))
    assert not _same(_numbers("max depth 0.01575"), _numbers("max depth 0.01585"))
    assert not _same(_numbers("k ratio: [1. 2. 3.]"), _numbers("k ratio: [1. 2.]"))


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_small_and_gives_its_stored_numbers(path, tmp_path):
    nbformat = pytest.importorskip("nbformat")
    pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    spec = importlib.util.spec_from_file_location("diffwear_execute_notebooks",
                                                  ROOT / "docs" / "execute_notebooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    stored = nbformat.read(path, as_version=4)
    fresh = module.execute(path, tmp_path)
    for k, (old, new) in enumerate(zip(_code_cells(stored), _code_cells(fresh)), 1):
        old_texts, new_texts = _texts(old), _texts(new)
        assert len(old_texts) == len(new_texts), f"{path.name}, code cell {k}: outputs differ"
        for a, b in zip(old_texts, new_texts):
            assert _same(_numbers(a), _numbers(b)), \
                f"{path.name}, code cell {k}: stored\n{a}\nnow\n{b}\n(docs/execute_notebooks.py)"
