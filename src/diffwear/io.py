"""Output files: CSV tables and JSON summaries, written without clobbering.

Every writer goes through `OutputDir`, which refuses, before any computation:

* a folder that holds a previous run (``summary.json``) unless asked to
  (``overwrite=True``), so that a mistyped command never destroys results;
* a folder that holds an interrupted run (``checkpoint.npz`` without a
  summary) unless it is resumed or overwritten, so that its checkpoint is
  never thrown away silently;
* a folder another diffwear process is writing (its lock file names the
  process; a lock left by a process that no longer runs is taken over);
* a folder that cannot be created or written (the reason, not a traceback
  after the computation).

`release_all` removes this process's locks, and a folder this process
created but never wrote to (an interrupt before the first result).
"""

from __future__ import annotations

import atexit
import json
import math
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

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


CHECKPOINT = "checkpoint.npz"  # an interrupted wear study's state (`studies._wear_common`)
LOCK = ".diffwear-lock"        # holds the pid of the process writing the folder
_OPEN: list[OutputDir] = []    # folders this process writes (for `release_all`)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        return True
    return True


class OutputDir:
    """A results folder.  ``summary.json`` marks a finished run; see the module
    notes for what is refused.  ``resume``: the caller continues the
    interrupted run whose checkpoint is there."""

    def __init__(self, path: str | Path, *, overwrite: bool = False, resume: bool = False):
        self.path = Path(path)
        if self.path.exists() and not self.path.is_dir():
            raise InputError(f"--out {self.path}: exists and is not a directory")
        if (self.path / "summary.json").exists() and not overwrite:
            raise InputError(
                f"--out {self.path}: already holds results (summary.json); choose another "
                "folder or pass --overwrite"
            )
        if ((self.path / CHECKPOINT).exists() and not (self.path / "summary.json").exists()
                and not (overwrite or resume)):
            raise InputError(
                f"--out {self.path}: holds an interrupted run ({CHECKPOINT}, no summary.json); "
                f"pass --resume {self.path} to continue it, or --overwrite to start over")
        existed = self.path.exists()
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise InputError(f"--out {self.path}: cannot create the folder "
                             f"({err.strerror}); allowed: a folder you can write to") from None
        self.created = not existed
        self.files: list[str] = []
        self._lock()
        _OPEN.append(self)

    def _lock(self) -> None:
        lock = self.path / LOCK
        try:
            pid = int(lock.read_text().strip() or 0) if lock.exists() else 0
        except (OSError, ValueError):
            pid = 0
        if pid and pid != os.getpid() and _alive(pid):
            raise InputError(f"--out {self.path}: another diffwear run (process {pid}) is "
                             "writing there; wait for it to finish or choose another folder")
        try:
            lock.write_text(f"{os.getpid()}\n")
        except OSError as err:
            raise InputError(f"--out {self.path}: cannot write there ({err.strerror}); "
                             "allowed: a folder you can write to") from None
        atexit.register(self.release)

    def release(self) -> None:
        """Remove this process's lock; remove the folder if this run created it
        and wrote nothing into it."""
        lock = self.path / LOCK
        try:
            if lock.exists() and lock.read_text().strip() == str(os.getpid()):
                lock.unlink()
            if self.created and self.path.is_dir() and not any(self.path.iterdir()):
                self.path.rmdir()
        except OSError:
            pass
        if self in _OPEN:
            _OPEN.remove(self)

    def file(self, name: str) -> Path:
        self.files.append(name)
        return self.path / name

    def csv(self, name: str, columns: Mapping[str, ArrayLike], fmt: str = "%.10g") -> Path:
        """Write a CSV with the given header -> column mapping (equal lengths)."""
        header = ",".join(columns)
        data = np.column_stack([np.asarray(c, dtype=float) for c in columns.values()])
        target = self.file(name)
        np.savetxt(target, data, delimiter=",", header=header, comments="", fmt=fmt)
        return target

    def json(self, name: str, payload: Mapping) -> Path:
        target = self.file(name)
        target.write_text(json.dumps(_jsonable(payload), indent=2, sort_keys=False) + "\n")
        if name == "summary.json":  # the run is finished: the folder is free again
            self.release()
        return target

    def text(self, name: str, body: str) -> Path:
        target = self.file(name)
        target.write_text(body)
        return target


def release_all() -> list[OutputDir]:
    """`OutputDir.release` every folder this process writes; returns them."""
    folders = list(_OPEN)
    for out in folders:
        out.release()
    return folders
