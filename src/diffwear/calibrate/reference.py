"""The dynamic model's check, evaluated beside the fits in a process of its own.

The loop fits the quasi-static model and checks its choices on the dynamic
model: an effect joins only if it lowers the dynamic model's chi-square too,
and the chosen fit is evaluated there at the end.  One dynamic evaluation of a
21,400-cycle campaign costs as much as several refits, while a fit keeps about
one core busy; so the dynamic model runs in a worker process, compiled once,
fed each fit's numbers as soon as the selection may need them (`submit`) and
read when it does (`residual`).

A process, not a thread: two XLA programs executing at once from two threads
of one process were seen to hang on the CPU backend.  The worker is a fresh
interpreter (``python -m diffwear.calibrate._dynamic_worker``: JAX is not fork-safe,
and multiprocessing's spawn would re-run a caller's unguarded script), talks
pickles over two pipes, ignores Ctrl-C (the parent decides) and ends when the
parent closes it or dies (its pipe ends).  Where pipes cannot be passed
(Windows) the model is evaluated in this process instead.
"""

from __future__ import annotations

import itertools
import os
import pickle
import signal
import subprocess
import sys
import time
from dataclasses import dataclass

import numpy as np

from ..errors import SolverError
from .dataset import Dataset
from .effects import EffectValues

__all__ = ["DynamicCheck"]

WORKER = "diffwear.calibrate._dynamic_worker"  # its entry point (run with -m)
_CHECKS = itertools.count()  # one entry per check in a fit's notes


@dataclass(frozen=True)
class _Ready:
    name: str
    description: str


def _build(data: Dataset, settings):
    """(the dynamic model, its compiled residual(x, EffectValues))."""
    import jax
    import jax.numpy as jnp

    from .fit import Problem

    reference = settings.with_model("dynamic").build(data.max_cycles)
    problem = Problem.from_dataset(data, settings).with_model(reference)
    x = jax.ShapeDtypeStruct((problem.n_base,), jnp.float64)
    effects = jax.tree.map(lambda a: jax.ShapeDtypeStruct(a.shape, a.dtype),
                           EffectValues.zero())
    return reference, jax.jit(problem.residual).lower(x, effects).compile()


def _evaluate(residual, request) -> np.ndarray:
    import jax.numpy as jnp

    xv, s, g, d = request
    return np.asarray(residual(jnp.asarray(xv), EffectValues(
        jnp.asarray(s), jnp.asarray(g), jnp.asarray(d))))


def _serve(read_fd: int, write_fd: int) -> None:
    """The worker: read (data, settings), compile the dynamic model's
    residual, then answer ``(key, x, strength, log_shape, discrepancy)`` with
    ``(key, residual)`` (or ``(key, message)`` when it fails) until ``None``
    or the end of the pipe."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    import jax

    jax.config.update("jax_enable_x64", True)
    with os.fdopen(read_fd, "rb") as rd, os.fdopen(write_fd, "wb") as wr:
        def send(message) -> None:
            pickle.dump(message, wr, protocol=pickle.HIGHEST_PROTOCOL)
            wr.flush()

        try:
            data, settings = pickle.load(rd)
            reference, residual = _build(data, settings)
        except Exception as err:  # noqa: BLE001 - reported to the parent, which decides
            send(f"{type(err).__name__}: {err}")
            return
        send(_Ready(reference.name, reference.describe()))
        while True:
            try:
                request = pickle.load(rd)
            except (EOFError, OSError):
                return
            if request is None:
                return
            key, *numbers = request
            r: np.ndarray | str
            try:
                r = _evaluate(residual, numbers)
            except Exception as err:  # noqa: BLE001
                r = f"{type(err).__name__}: {err}"
            try:
                send((key, r))
            except (BrokenPipeError, OSError):
                return


class DynamicCheck:
    """The dynamic model of ``data`` (``settings`` with the dynamic model),
    evaluated at fits' numbers in a worker process (module notes)."""

    def __init__(self, data: Dataset, settings, *, in_process: bool = os.name == "nt"):
        self._local = None
        self._process: subprocess.Popen | None = None
        if in_process:
            reference, residual = _build(data, settings)
            self._local = residual
            self._ready: _Ready | None = _Ready(reference.name, reference.describe())
        else:
            from_parent, to_child = os.pipe()
            from_child, to_parent = os.pipe()
            self._process = subprocess.Popen(
                [sys.executable, "-m", WORKER, str(from_parent), str(to_parent)],
                pass_fds=(from_parent, to_parent), stdin=subprocess.DEVNULL,
                start_new_session=True)  # a Ctrl-C in the terminal is the parent's
            os.close(from_parent)
            os.close(to_parent)
            self._out = os.fdopen(to_child, "wb")
            self._in = os.fdopen(from_child, "rb")
            self._ready = None
            self._send((data, settings))
        self._pending: set[int] = set()
        self._results: dict[int, object] = {}
        self._next = 0
        # this check's entry in a fit's notes: its request key, then its residual
        self._note = ("dynamic check", next(_CHECKS))
        self.busy_s = 0.0   # time the caller waited for the worker

    def _send(self, message) -> None:
        try:
            pickle.dump(message, self._out, protocol=pickle.HIGHEST_PROTOCOL)
            self._out.flush()
        except (BrokenPipeError, OSError):
            raise self._ended() from None

    def _receive(self) -> None:
        """One message from the worker (blocks); a dead worker is an error."""
        t0 = time.perf_counter()
        try:
            message = pickle.load(self._in)
        except (EOFError, OSError, pickle.UnpicklingError):
            raise self._ended() from None
        finally:
            self.busy_s += time.perf_counter() - t0
        if isinstance(message, _Ready):
            self._ready = message
        elif isinstance(message, str):
            raise SolverError(f"the dynamic model could not be built: {message}")
        else:
            key, r = message
            self._pending.discard(key)
            self._results[key] = r

    def _ended(self) -> SolverError:
        code = None
        if self._process is not None:
            try:
                code = self._process.wait(timeout=1.0)
            except subprocess.TimeoutExpired:
                pass
        return SolverError(f"the dynamic model's worker process ended (exit code {code})")

    @property
    def ready(self) -> _Ready:
        while self._ready is None:
            self._receive()
        return self._ready

    @property
    def name(self) -> str:
        return self.ready.name

    def describe(self) -> str:
        return self.ready.description

    def submit(self, fit) -> None:
        """Queue the dynamic model's evaluation at ``fit``'s numbers (once)."""
        if self._note in fit.notes:
            return
        key = self._next
        self._next += 1
        fit.notes[self._note] = key
        e = fit.effect_values()
        request = (np.asarray(fit.notes["x"]), np.asarray(e.strength),
                   np.asarray(e.log_shape), np.asarray(e.discrepancy))
        if self._local is not None:  # evaluated when read
            self._results[key] = request
            return
        self._send((key, *request))
        self._pending.add(key)

    def residual(self, fit) -> np.ndarray:
        """All normalised residuals of the dynamic model at ``fit``'s numbers
        (evaluated, not refitted; non-finite where its integration failed);
        kept in the fit's notes under this check's own entry."""
        self.submit(fit)
        entry = fit.notes[self._note]
        if isinstance(entry, np.ndarray):
            return entry
        while entry not in self._results:
            self._receive()
        r = self._results.pop(entry)
        if self._local is not None:
            r = _evaluate(self._local, r)
        if not isinstance(r, np.ndarray):  # the worker's message
            raise SolverError(f"the dynamic model's evaluation failed: {r}")
        fit.notes[self._note] = r
        return r

    def close(self) -> None:
        """Stop the worker (pending evaluations are dropped)."""
        if self._process is None:
            return
        if self._pending:  # mid-evaluation: it has nothing to save
            self._process.kill()
        try:
            self._send(None)
        except SolverError:
            pass
        for f in (self._out, self._in):
            try:
                f.close()
            except OSError:
                pass
        try:
            self._process.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
