#!/usr/bin/env python3
"""Execute the example notebooks and store them with their outputs.

The site shows ``notebooks/*.ipynb`` as they are stored (mkdocs-jupyter with
``execute: false``): the four notebooks together take minutes even at the
reduced size, too long for every site build.  This script runs each at the
reduced size (``DIFFWEAR_NOTEBOOK_SIZE=small``), top to bottom in a fresh
kernel with the inline matplotlib backend (so the figures are stored as
images), in a temporary folder, and writes it back with its outputs.  Rerun it
after changing a notebook or the library; ``tests/test_notebooks.py``
re-executes the notebooks under ``--long`` and compares their numbers with
the stored ones.

    .venv/bin/python docs/execute_notebooks.py            # every notebook
    .venv/bin/python docs/execute_notebooks.py a_rig_clearance_k_sweep
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"
SIZE = "small"  # the size the notebooks are stored at (and the test runs)
TIMEOUT_S = 900  # per cell; the largest cell at the small size takes ~4 min on 2 loaded cores


def execute(path: Path, folder: Path):
    """Notebook ``path`` executed in ``folder`` at `SIZE`; the executed
    notebook (nbformat node).  The kernel inherits this environment, with the
    source tree first on its path and matplotlib on its inline backend."""
    import nbclient
    import nbformat

    env = {"DIFFWEAR_NOTEBOOK_SIZE": SIZE,
           "PYTHONPATH": os.pathsep.join([str(ROOT / "src"),
                                          *filter(None, [os.environ.get("PYTHONPATH")])])}
    saved = {k: os.environ.get(k) for k in [*env, "MPLBACKEND"]}
    os.environ.update(env)
    os.environ.pop("MPLBACKEND", None)  # the kernel's inline backend stores the figures
    try:
        nb = nbformat.read(path, as_version=4)
        nbclient.NotebookClient(nb, timeout=TIMEOUT_S, kernel_name="python3",
                                record_timing=False,
                                resources={"metadata": {"path": str(folder)}}).execute()
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return nb


def main(argv: list[str]) -> int:
    import nbformat

    paths = ([NOTEBOOKS / f"{name.removesuffix('.ipynb')}.ipynb" for name in argv]
             or sorted(NOTEBOOKS.glob("*.ipynb")))
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        print(f"no such notebook in {NOTEBOOKS}: {', '.join(missing)}", file=sys.stderr)
        return 2
    for path in paths:
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            nb = execute(path, Path(tmp))
        nbformat.write(nb, path)
        print(f"{path.name}: {time.perf_counter() - t0:.0f} s, "
              f"{path.stat().st_size / 1e3:.0f} kB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
