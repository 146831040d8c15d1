"""Output files: CSV tables and JSON summaries, written without clobbering.

Every writer goes through `OutputDir`, which refuses, before any computation:

* an empty or blank path (it would write into the current folder);
* a folder that holds files diffwear did not write: only a new folder, an
  empty one or a previous diffwear output is written into.  A diffwear
  output is recognised by its manifest (``.diffwear-files``, the names of
  every file the run wrote, kept up to date as it writes); a folder from a
  release without one by its ``summary.json`` listing its files;
* a folder that holds a previous run (``summary.json``) unless asked to
  (``overwrite=True``, which first removes the files that run wrote, and
  only those), so that a mistyped command never destroys results;
* a folder that holds an interrupted run (``checkpoint.npz`` without a
  summary) unless it is resumed or overwritten, so that its checkpoint is
  never thrown away silently, and one holding the files of a run that was
  killed before its summary unless overwritten (never mixed with a new
  run's);
* a folder another diffwear process is writing (its lock file names the
  process; a lock left by a process that no longer runs is taken over);
* a folder that cannot be created or written (the reason, not a traceback
  after the computation).

`release_all` removes this process's locks, and a folder this process
created but never wrote to (an interrupt before the first result).

Files are written under a temporary name and renamed when complete (the
CSV, JSON and text writers; figures and archives name their target through
`OutputDir.file`, and a failed write removes it), so a full disk leaves no
truncated file: the error is an `OutputError` (exit code 4) naming the
file and the folder.  A run stopped before its summary by a failed write or
an interrupt leaves a file ``INCOMPLETE`` saying why (empty where even that
could not be written): the user sees it beside the results, and the next run
into the folder refuses it unless it is overwritten or resumed; the
summary of a finished run removes it.

A refused run leaves the folder as it was: nothing is written into it before
the first result (the manifest is written with the first file; the lock is
removed when the process ends).
"""

from __future__ import annotations

import atexit
import errno
import json
import math
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .errors import InputError, OutputError
from .report import Report, render


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
MANIFEST = ".diffwear-files"   # the names of the files a run wrote, one per line
INCOMPLETE = "INCOMPLETE"      # a run that stopped before its summary, and why
_INCOMPLETE_NOTE = "The files here are those written before the run stopped."
_OWN = {LOCK, MANIFEST}
# names a file manager leaves in any folder: not the user's results
_DESKTOP = {".DS_Store", "Thumbs.db", "desktop.ini"}
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
        if not str(path).strip():
            raise InputError(f"--out {str(path)!r}: empty; allowed: the path of a new folder, "
                             "an empty one or a previous diffwear output")
        self.path = Path(path)
        if self.path.exists() and not self.path.is_dir():
            raise InputError(f"--out {self.path}: exists and is not a directory")
        previous, partial = self._previous_files()
        stopped = self._stopped()
        if (self.path / "summary.json").exists() and not overwrite:
            raise InputError(
                f"--out {self.path}: already holds results (summary.json{stopped}); choose "
                "another folder or pass --overwrite"
            )
        if ((self.path / CHECKPOINT).exists() and not (self.path / "summary.json").exists()
                and not (overwrite or resume)):
            raise InputError(
                f"--out {self.path}: holds an interrupted run ({CHECKPOINT}, no "
                f"summary.json{stopped}); pass --resume {self.path} to continue it, or "
                "--overwrite to start over")
        unfinished = [n for n in previous if n != CHECKPOINT]
        if unfinished and not (self.path / "summary.json").exists() and not (overwrite or resume):
            shown = [n for n in unfinished if n != INCOMPLETE]
            listing = ", ".join(shown[:5]) + (" ..." if len(shown) > 5 else "")
            raise InputError(
                f"--out {self.path}: holds the files of a run that did not finish "
                f"({(listing + stopped) if listing else stopped[2:]}); pass --overwrite to "
                "replace them, or choose another folder")
        existed = self.path.exists()
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise InputError(f"--out {self.path}: cannot create the folder "
                             f"({err.strerror}); allowed: a folder you can write to") from None
        self.created = not existed
        self.files: list[str] = []
        self.finished = False
        self._listed = False  # the manifest written by this run
        self._lock()
        _OPEN.append(self)
        self._remove(partial)
        if resume:  # the interrupted run's files stay; this run adds to its list
            self.files = [n for n in previous
                          if n != INCOMPLETE and (self.path / n).is_file()]
        elif overwrite:
            self._remove(previous)
            self._write_manifest()
        # otherwise the manifest is written with the first file: a run refused
        # before it (a checkpoint of another run) leaves the folder as it was

    def _stopped(self) -> str:
        """'; INCOMPLETE: why' where a previous run here stopped before its
        summary (for the refusals), else ''."""
        marker = self.path / INCOMPLETE
        if not marker.is_file():
            return ""
        try:
            why = marker.read_text(errors="replace").strip().splitlines()
        except OSError:
            why = []
        return f"; {INCOMPLETE}: {why[0] if why else 'it stopped before its summary'}"

    @staticmethod
    def _ours(marker: Path) -> bool:
        """``INCOMPLETE`` as `mark_incomplete` writes it (or empty: a full disk
        took even its words), not a user's file of that name."""
        try:
            text = marker.read_text(errors="replace")
        except OSError:
            return False
        return not text.strip() or _INCOMPLETE_NOTE in text

    def mark_incomplete(self, why: str) -> None:
        """Leave ``INCOMPLETE`` (saying ``why``) in a folder whose run stopped
        before its summary.  Best effort: on a full disk the file may stay
        empty, or not be made at all (the error message says the same)."""
        if self.finished:
            return
        marker = self.path / INCOMPLETE
        try:
            with open(marker, "w", encoding="utf-8") as fh:
                fh.write(f"{why.strip()}\n{_INCOMPLETE_NOTE} Run again with --overwrite "
                         "(or --resume where the run kept a checkpoint).\n")
        except OSError:
            pass

    def _previous_files(self) -> tuple[list[str], set[str]]:
        """(the files a previous diffwear run wrote here: its manifest, or its
        summary's list; the temporary files of writes cut short by a kill);
        `InputError` if the folder holds anything else."""
        if not self.path.is_dir():
            return [], set()
        present = {p.name for p in self.path.iterdir()} - _OWN - _DESKTOP
        # a write cut short by a kill (the rename never happened): ours
        partial = {n for n in present if n.startswith(".") and n.endswith(".partial")}
        present -= partial
        listed: set[str] = set()
        manifest = self.path / MANIFEST
        if manifest.is_file():
            listed = {n for n in manifest.read_text(errors="replace").splitlines() if n}
        else:
            try:
                files = json.loads((self.path / "summary.json").read_text()).get("files", [])
                listed = {str(n) for n in files} | {"summary.json"}
            except (OSError, ValueError, AttributeError):
                pass
        if CHECKPOINT in present:  # an interrupted run's state (listed once it ends)
            listed.add(CHECKPOINT)
        if INCOMPLETE in present and (listed or self._ours(self.path / INCOMPLETE)):
            listed.add(INCOMPLETE)  # a stopped run's marker (written unlisted)
        foreign = sorted(present - listed)
        if foreign:
            shown = ", ".join(foreign[:5]) + (f" and {len(foreign) - 5} more"
                                              if len(foreign) > 5 else "")
            if listed & present:
                raise InputError(
                    f"--out {self.path}: holds files diffwear did not write ({shown}) beside "
                    "a previous run's; --overwrite removes only the files a run wrote "
                    f"(listed in {MANIFEST}), never these, and does not write beside them: "
                    "move them out of the folder and rerun, or choose another folder")
            what = ("files diffwear did not write" if listed or not present
                    else "files that are not a diffwear output")
            raise InputError(f"--out {self.path}: holds {what} ({shown}); allowed: a new "
                             "folder, an empty one or a previous diffwear output")
        return sorted(listed & present), partial

    def _remove(self, names) -> None:
        """Remove the previous run's files (plain files directly in the folder)."""
        for name in names:
            target = self.path / name
            if name in _OWN or Path(name).name != name or not target.is_file():
                continue
            try:
                target.unlink()
            except OSError as err:
                raise InputError(
                    f"--out {self.path}: cannot remove the previous run's {name} "
                    f"({err.strerror}); allowed: a folder you can write to") from None

    def _write_manifest(self) -> None:
        names = "".join(f"{n}\n" for n in dict.fromkeys(self.files))
        self._atomic(MANIFEST, lambda tmp: tmp.write_text(names))
        self._listed = True

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
            if self.created and not self.files:
                (self.path / MANIFEST).unlink(missing_ok=True)
            if self.created and self.path.is_dir() and not any(self.path.iterdir()):
                self.path.rmdir()
        except OSError:
            pass
        if self in _OPEN:
            _OPEN.remove(self)

    def file(self, name: str) -> Path:
        """The path to write ``name`` to, listed in the manifest first (so that
        an interrupted run's files are known and a later --overwrite removes
        them)."""
        if name not in self.files or not self._listed:
            if name not in self.files:
                self.files.append(name)
            self._write_manifest()
        return self.path / name

    def abandon_last(self) -> Path | None:
        """After a write that failed outside the atomic writers: remove the
        file registered last (it may be incomplete); returns its path."""
        if not self.files:
            return None
        target = self.path / self.files[-1]
        target.unlink(missing_ok=True)
        return target

    def _atomic(self, name: str, write) -> Path:
        """``write(tmp)`` to a temporary name, renamed to ``name`` when done;
        a failure leaves neither (`OutputError` naming the file and folder)
        and marks the run `INCOMPLETE`."""
        target = self.path / name
        tmp = self.path / f".{name}.partial"
        try:
            write(tmp)
            os.replace(tmp, target)
        except OSError as err:
            tmp.unlink(missing_ok=True)
            failed = output_error(err, target)
            if name != MANIFEST or self.files:
                self.mark_incomplete(str(failed))
            raise failed from None
        return target

    def csv(self, name: str, columns: Mapping[str, ArrayLike], fmt: str = "%.10g") -> Path:
        """Write a CSV with the given header -> column mapping (equal lengths)."""
        header = ",".join(columns)
        data = np.column_stack([np.asarray(c, dtype=float) for c in columns.values()])
        self.file(name)
        return self._atomic(name, lambda tmp: np.savetxt(
            tmp, data, delimiter=",", header=header, comments="", fmt=fmt))

    def json(self, name: str, payload: Mapping) -> Path:
        self.file(name)
        body = json.dumps(_jsonable(payload), indent=2, sort_keys=False) + "\n"
        target = self._atomic(name, lambda tmp: tmp.write_text(body))
        if name == "summary.json":  # the run is finished: the folder is free again
            self.finished = True
            (self.path / INCOMPLETE).unlink(missing_ok=True)  # a resumed run's earlier stop
            self.release()
        return target

    def text(self, name: str, body: str) -> Path:
        self.file(name)
        return self._atomic(name, lambda tmp: tmp.write_text(body))

    def write(self, outputs: Outputs) -> None:
        """Write every file of ``outputs``, in the order they were gathered."""
        for name, kind, payload in outputs.items:
            if kind == "csv":
                self.csv(name, payload)
            elif kind == "text":
                self.text(name, payload() if callable(payload) else payload)
            elif kind == "json":
                self.json(name, payload)
            elif kind == "report":
                self.text(name, render(payload))
            else:  # a figure draws itself to the path it is given
                payload(self.file(name))


class Outputs:
    """A run's files gathered before any is written (`OutputDir.write`): the
    numbers of every table, figure and report are computed first, then the
    files are written together.  A text's body or a figure may be given as
    a callable (``body()`` -> str, ``draw(path)``), called when written."""

    def __init__(self) -> None:
        self.items: list[tuple[str, str, Any]] = []

    def csv(self, name: str, columns: Mapping[str, ArrayLike]) -> str:
        return self._add(name, "csv", columns)

    def text(self, name: str, body: str | Callable[[], str]) -> str:
        return self._add(name, "text", body)

    def figure(self, name: str, draw: Callable[[Path], object]) -> str:
        return self._add(name, "figure", draw)

    def report(self, name: str, report: Report) -> str:
        """A `Report`, rendered to markdown when written."""
        return self._add(name, "report", report)

    def json(self, name: str, payload: Mapping) -> str:
        """A JSON file; ``summary.json`` gathered last marks the run finished
        once every file before it is written."""
        return self._add(name, "json", payload)

    def extend(self, other: Outputs) -> None:
        self.items += other.items

    @property
    def names(self) -> list[str]:
        return [name for name, _, _ in self.items]

    def _add(self, name: str, kind: str, payload) -> str:
        self.items.append((name, kind, payload))
        return name


def output_error(err: OSError, target: Path) -> OutputError:
    """One line for a failed write: the file, the folder and the reason."""
    full = err.errno in (errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC))
    why = ("the disk holding it is full" if full else err.strerror or str(err))
    return OutputError(f"cannot write {target.name} in {target.parent}: {why}; the "
                       f"incomplete file was removed and the run marked {INCOMPLETE} there "
                       "(free space, then rerun with --overwrite, or --resume where the run "
                       "keeps a checkpoint)")


def release_all() -> list[OutputDir]:
    """`OutputDir.release` every folder this process writes; returns them."""
    folders = list(_OPEN)
    for out in folders:
        out.release()
    return folders
