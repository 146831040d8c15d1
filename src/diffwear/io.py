"""Output files: CSV tables and JSON summaries, written without clobbering.

Every writer goes through `OutputDir`, which refuses to write into a folder
that holds a previous run unless asked to (``overwrite=True``), so that a
mistyped command never destroys earlier results.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .errors import InputError


def _jsonable(value):
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if hasattr(value, "tolist"):
        return _jsonable(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


class OutputDir:
    """A results folder.  ``summary.json`` marks a finished run."""

    def __init__(self, path: str | Path, *, overwrite: bool = False):
        self.path = Path(path)
        if self.path.exists() and not self.path.is_dir():
            raise InputError(f"--out {self.path}: exists and is not a directory")
        if (self.path / "summary.json").exists() and not overwrite:
            raise InputError(
                f"--out {self.path}: already holds results (summary.json); choose another "
                "folder or pass --overwrite"
            )
        self.path.mkdir(parents=True, exist_ok=True)
        self.files: list[str] = []

    def file(self, name: str) -> Path:
        self.files.append(name)
        return self.path / name

    def csv(self, name: str, columns: Mapping[str, Sequence[float]], fmt: str = "%.10g") -> Path:
        """Write a CSV with the given header -> column mapping (equal lengths)."""
        header = ",".join(columns)
        data = np.column_stack([np.asarray(c, dtype=float) for c in columns.values()])
        target = self.file(name)
        np.savetxt(target, data, delimiter=",", header=header, comments="", fmt=fmt)
        return target

    def json(self, name: str, payload: Mapping) -> Path:
        target = self.file(name)
        target.write_text(json.dumps(_jsonable(payload), indent=2, sort_keys=False) + "\n")
        return target

    def text(self, name: str, body: str) -> Path:
        target = self.file(name)
        target.write_text(body)
        return target
