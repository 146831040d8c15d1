"""Work in other processes: fresh interpreters fed pickles over pipes.

A `WorkerProcess` is ``python -m diffwear._worker_entry`` (a fresh
interpreter: JAX is not fork-safe, and multiprocessing's spawn would re-run a
caller's unguarded script) with the caller's import path, sent
``setup(*args)`` once, which returns the
handler its requests are answered with (and what the parent is told once it
is ready).  It ignores Ctrl-C (the parent
decides) and ends when the parent sends ``None``, closes it, or dies (its
pipe ends).  A process, not a thread: the CPU backend does not run two XLA
programs at once from two threads of one process (docs/notes/cpu-sweeps.md).

`run_pool` shares tasks over several workers, each given the next task as
it answers.  Where pipes cannot be passed to a child (Windows), `AVAILABLE`
is False and callers compute in their own process.
"""

from __future__ import annotations

import os
import pickle
import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable
from typing import Any

from .errors import SolverError

__all__ = ["AVAILABLE", "WorkerProcess", "run_pool", "serve"]

AVAILABLE = os.name != "nt"
ENTRY = "diffwear._worker_entry"  # run with -m


def serve(read_fd: int, write_fd: int) -> None:
    """The worker's side: read the import path and ``(setup, args)``; with
    ``(handler, info) = setup(*args)`` answer ``("ready", info)`` (or
    ``("failed", message)``), then answer each ``(key, payload)`` with
    ``(key, ("ok", handler(payload)))`` or ``(key, ("error", message))``
    until ``None`` or the end of the pipe."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    import jax

    jax.config.update("jax_enable_x64", True)  # diffwear computes in float64
    with os.fdopen(read_fd, "rb") as rd, os.fdopen(write_fd, "wb") as wr:
        def send(message) -> None:
            pickle.dump(message, wr, protocol=pickle.HIGHEST_PROTOCOL)
            wr.flush()

        try:
            # the parent's import path first, so that what it sends unpickles
            sys.path[:] = pickle.load(rd)
            setup, args = pickle.load(rd)
            handler, info = setup(*args)
        except Exception as err:  # noqa: BLE001 - reported to the parent, which decides
            send(("failed", f"{type(err).__name__}: {err}"))
            return
        send(("ready", info))
        while True:
            try:
                request = pickle.load(rd)
            except (EOFError, OSError):
                return
            if request is None:
                return
            key, payload = request
            try:
                answer: tuple = ("ok", handler(payload))
            except Exception as err:  # noqa: BLE001
                answer = ("error", f"{type(err).__name__}: {err}")
            try:
                send((key, answer))
            except (BrokenPipeError, OSError):
                return


class WorkerProcess:
    """A worker answering requests with the handler of ``setup(*args)``
    (module notes); ``what`` names it in errors.  ``setup`` and ``args`` must
    pickle."""

    def __init__(self, setup: Callable, *args, what: str = "worker"):
        self.what = what
        from_parent, to_child = os.pipe()
        from_child, to_parent = os.pipe()
        self.process = subprocess.Popen(
            [sys.executable, "-m", ENTRY, str(from_parent), str(to_parent)],
            pass_fds=(from_parent, to_parent), stdin=subprocess.DEVNULL,
            start_new_session=True)  # a Ctrl-C in the terminal is the parent's
        os.close(from_parent)
        os.close(to_parent)
        self._out = os.fdopen(to_child, "wb")
        self._in = os.fdopen(from_child, "rb")
        self.ready = False
        self.info: Any = None   # what setup returned beside its handler, once ready
        self.busy_s = 0.0   # time the caller waited for it
        self.send_raw(list(sys.path))
        self.send_raw((setup, args))

    def send_raw(self, message) -> None:
        try:
            pickle.dump(message, self._out, protocol=pickle.HIGHEST_PROTOCOL)
            self._out.flush()
        except (BrokenPipeError, OSError):
            raise self.ended() from None

    def send(self, key, payload) -> None:
        """Queue ``handler(payload)`` under ``key``."""
        self.send_raw((key, payload))

    def receive(self) -> tuple[Any, Any] | None:
        """The next answer, ``(key, value)`` (blocks); None for the ready
        message; a failed setup or a dead worker is a `SolverError`, a failed
        request's answer is ``(key, SolverError)``."""
        t0 = time.perf_counter()
        try:
            message = pickle.load(self._in)
        except (EOFError, OSError, ValueError, pickle.UnpicklingError):  # ended, or closed
            raise self.ended() from None
        finally:
            self.busy_s += time.perf_counter() - t0
        if message[0] == "ready":
            self.ready, self.info = True, message[1]
            return None
        if message[0] == "failed":
            raise SolverError(f"the {self.what} could not start: {message[1]}")
        key, (status, value) = message
        if status == "error":
            return key, SolverError(f"the {self.what} failed: {value}")
        return key, value

    def ended(self) -> SolverError:
        try:
            code = self.process.wait(timeout=1.0)
        except subprocess.TimeoutExpired:
            code = None
        return SolverError(f"the {self.what} process ended (exit code {code})")

    def close(self, *, kill: bool = False) -> None:
        """Stop the worker (``kill``: at once, dropping what it computes)."""
        if kill:
            self.process.kill()
        try:
            self.send_raw(None)
        except SolverError:
            pass
        for f in (self._out, self._in):
            try:
                f.close()
            except OSError:
                pass
        try:
            self.process.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


def run_pool(workers: int, setup: Callable, args_of: Callable[[int], tuple], tasks: Iterable,
             on_result: Callable[[int, Any], None], *, what: str = "worker") -> None:
    """``handler(task)`` for every task over ``workers`` processes (worker i
    set up with ``setup(*args_of(i))``), each sent the next task as it
    answers; ``on_result(task_index, value)`` as answers come, in this
    thread.  A failed task raises its `SolverError` (the rest are dropped).
    Each worker's answers are read by a thread of its own (reading only: the
    computing is in the processes)."""
    pending = list(enumerate(tasks))[::-1]
    pool = [WorkerProcess(setup, *args_of(i), what=what)
            for i in range(min(workers, len(pending)))]
    answers: queue.Queue = queue.Queue()

    def read(w: WorkerProcess) -> None:
        while True:
            try:
                answer = w.receive()
            except SolverError as err:  # a failed start, or the process ended
                answers.put((w, err))
                return
            if answer is not None:
                answers.put((w, answer))

    finished = False
    try:
        for w in pool:
            w.send(*pending.pop())
            threading.Thread(target=read, args=(w,), daemon=True).start()
        busy = len(pool)
        while busy:
            w, answer = answers.get()
            if isinstance(answer, SolverError):
                raise answer
            key, value = answer
            if isinstance(value, SolverError):
                raise value
            on_result(key, value)
            if pending:
                w.send(*pending.pop())
            else:
                busy -= 1
        finished = True
    finally:
        for w in pool:
            w.close(kill=not finished)
