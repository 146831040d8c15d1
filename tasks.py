#!/usr/bin/env python3
"""One-file bootstrap: the two commands of the README.

    python3 tasks.py study   # main job: the Ch. 7 rig study, report + plots in out/rig-21400
    python3 tasks.py test    # the test suite (what CI runs)

Each creates ``.venv`` (stdlib ``venv``) on first use, installs the package with
its test extras, then runs.  Only Python >= 3.11 and pip are needed beforehand.
Extra arguments after the command are passed through (to ``pytest`` or to
``diffwear study``).  ``test`` runs pytest on every core (pytest-xdist,
``-n auto --dist loadfile``) unless the arguments choose ``-n`` / ``--dist``
/ ``-p`` themselves (``-p no:xdist`` or ``-n 0`` for a serial run).
"""

from __future__ import annotations

import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
PY = BIN / ("python.exe" if os.name == "nt" else "python")
STAMP = VENV / ".diffwear-installed"


def _run(*cmd: str | Path) -> int:
    print("+", " ".join(str(c) for c in cmd), flush=True)
    return subprocess.call([str(c) for c in cmd], cwd=ROOT)


def ensure_env() -> None:
    """Create the venv and (re)install when pyproject.toml is newer than the stamp."""
    if not PY.exists():
        venv.EnvBuilder(with_pip=True, clear=False).create(VENV)
    pyproject = ROOT / "pyproject.toml"
    if STAMP.exists() and STAMP.stat().st_mtime >= pyproject.stat().st_mtime:
        return
    print("tasks.py: installing diffwear and its dependencies into .venv "
          "(about a minute; once)", flush=True)
    for cmd in (
        (PY, "-m", "pip", "install", "--quiet", "--upgrade", "pip"),
        (PY, "-m", "pip", "install", "--quiet", "-e", f"{ROOT}[test]"),
    ):
        if _run(*cmd) != 0:
            sys.exit("tasks.py: installing dependencies failed (see pip output above)")
    STAMP.touch()


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in {"study", "test"}:
        print(__doc__)
        return 2
    ensure_env()
    cmd, rest = argv[0], argv[1:]
    if cmd == "test":
        # One pytest worker per core, whole files per worker (a file's module
        # fixtures compile once).  Most of the suite is single-threaded XLA
        # compilation and small-array loops, so a serial run leaves cores idle.
        # One BLAS thread per worker: the FEM tests' Cholesky factorisations
        # ran up to 100x slower with OpenBLAS threads oversubscribing the cores.
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
        chosen = any(a.startswith(("-n", "--numprocesses", "--dist", "-p")) for a in rest)
        parallel = [] if chosen else ["-n", "auto", "--dist", "loadfile"]
        return _run(PY, "-m", "pytest", *parallel, *rest)
    # the main job reruns into its own folder (--overwrite); a user's --out wins
    out = [] if any(a.startswith("--out") for a in rest) else [
        "--out", ROOT / "out" / "rig-21400", "--overwrite"]
    return _run(BIN / "diffwear", "study", "rig-21400", *out, *rest)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
