"""Ctrl-C that is never lost.

Python raises `KeyboardInterrupt` in whatever frame runs when SIGINT
arrives.  Inside one of JAX's garbage-collection callbacks it is printed as
"Exception ignored" (with a traceback) and lost, and the run goes on to the
end.  The ``diffwear`` command installs `install`'s handler, which records
the interrupt before raising it, so that the next `check` raises it again:
the wear loop checks between chunks (after the checkpoint is saved, so the
run resumes from there), and the command once it returns.  While installed,
an interrupt lost that way is not printed (the command says it was
interrupted in its own one line); other lost exceptions still are.

A process started with SIGINT ignored (``nohup``, a background job of a
script) keeps ignoring it, as Python itself does: neither `install` nor
`hold` sets a handler there.
"""

from __future__ import annotations

import signal
import sys
import threading

__all__ = ["check", "hold", "install", "requested", "restore"]

_requested = threading.Event()


def _handler(signum, frame):
    _requested.set()
    raise KeyboardInterrupt


def _record(signum, frame):
    _requested.set()


def _unraisable(hook):
    def unraisable(info):
        if not (isinstance(info.exc_value, KeyboardInterrupt) and _requested.is_set()):
            hook(info)
    unraisable.wrapped = hook  # type: ignore[attr-defined]
    return unraisable


def install():
    """Handle SIGINT with the recording handler (main thread only); returns
    what `restore` puts back (None where it cannot be set)."""
    _requested.clear()
    if threading.current_thread() is not threading.main_thread():
        return None
    hook = sys.unraisablehook
    sys.unraisablehook = _unraisable(hook)
    previous = signal.getsignal(signal.SIGINT)
    if previous is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, _handler)
    return previous, hook


def restore(previous) -> None:
    if previous is not None and threading.current_thread() is threading.main_thread():
        handler, hook = previous
        signal.signal(signal.SIGINT, handler)
        sys.unraisablehook = hook


def hold() -> None:
    """From here on a Ctrl-C is recorded, never raised: for a process whose
    work is over and that is ending (main thread only)."""
    _requested.clear()
    if (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is not signal.SIG_IGN):
        signal.signal(signal.SIGINT, _record)


def requested() -> bool:
    """Whether Ctrl-C was pressed since `install`."""
    return _requested.is_set()


def check() -> None:
    """Raise `KeyboardInterrupt` if Ctrl-C was pressed (and perhaps lost)."""
    if _requested.is_set():
        raise KeyboardInterrupt
