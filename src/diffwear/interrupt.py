"""Ctrl-C that is never lost.

Python raises `KeyboardInterrupt` in whatever frame runs when SIGINT
arrives.  Inside one of JAX's garbage-collection callbacks it is printed as
"Exception ignored" and lost, and the run goes on to the end.  The
``diffwear`` command installs `install`'s handler, which records the
interrupt before raising it, so that the next `check` raises it again: the
wear loop checks between chunks (after the checkpoint is saved, so the run
resumes from there), and the command once it returns.
"""

from __future__ import annotations

import signal
import threading

__all__ = ["check", "install", "requested", "restore"]

_requested = threading.Event()


def _handler(signum, frame):
    _requested.set()
    raise KeyboardInterrupt


def install():
    """Handle SIGINT with the recording handler (main thread only); returns
    the previous handler for `restore` (None where it cannot be set)."""
    _requested.clear()
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGINT, _handler)


def restore(previous) -> None:
    if previous is not None and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, previous)


def requested() -> bool:
    """Whether Ctrl-C was pressed since `install`."""
    return _requested.is_set()


def check() -> None:
    """Raise `KeyboardInterrupt` if Ctrl-C was pressed (and perhaps lost)."""
    if _requested.is_set():
        raise KeyboardInterrupt
