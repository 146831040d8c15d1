"""The dynamic model's check, evaluated beside the fits in a process of its own.

The loop fits the quasi-static model and checks its choices on the dynamic
model: an effect joins only if it lowers the dynamic model's chi-square too,
and the chosen fit is evaluated there at the end.  One dynamic evaluation of a
21,400-cycle campaign costs as much as several refits, while a fit keeps about
one core busy; so the dynamic model runs in a worker process, compiled once,
fed each fit's numbers as soon as the selection may need them (`submit`) and
read when it does (`residual`).

The worker is a `diffwear.worker.WorkerProcess` (a fresh interpreter fed
pickles over pipes; a process, not a thread, as XLA's CPU runtime needs).
Where pipes cannot be passed (Windows) the model is evaluated in this
process instead.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from .. import worker
from ..errors import SolverError
from .dataset import Dataset
from .effects import EffectValues

__all__ = ["DynamicCheck"]

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
    from .model import RigHistory

    reference = settings.with_model(RigHistory).build(data.max_cycles, (), data.fit_cycles)
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


def _setup(data: Dataset, settings):
    """In the worker: compile the dynamic model's residual; its handler
    answers ``(x, strength, log_shape, discrepancy)`` with the residual."""
    reference, residual = _build(data, settings)
    return (lambda request: _evaluate(residual, request),
            _Ready(reference.name, reference.describe()))


class DynamicCheck:
    """The dynamic model of ``data`` (``settings`` with the dynamic model),
    evaluated at fits' numbers in a worker process (module notes)."""

    def __init__(self, data: Dataset, settings, *, in_process: bool = not worker.AVAILABLE):
        self._local = None
        self._worker: worker.WorkerProcess | None = None
        self._ready: _Ready | None = None
        if in_process:
            reference, residual = _build(data, settings)
            self._local = residual
            self._ready = _Ready(reference.name, reference.describe())
        else:
            self._worker = worker.WorkerProcess(_setup, data, settings,
                                                what="dynamic model's worker")
        self._pending: set[int] = set()
        self._results: dict[int, object] = {}
        self._next = 0
        # this check's entry in a fit's notes: its request key, then its residual
        self._note = ("dynamic check", next(_CHECKS))

    @property
    def busy_s(self) -> float:
        """Time the caller waited for the worker."""
        return 0.0 if self._worker is None else self._worker.busy_s

    @property
    def _process(self):
        return None if self._worker is None else self._worker.process

    def _receive(self) -> None:
        """One message from the worker (blocks); a failed build or a dead
        worker is a `SolverError` that says so."""
        assert self._worker is not None
        answer = self._worker.receive()
        if answer is None:
            self._ready = self._worker.info
            return
        key, r = answer
        self._pending.discard(key)
        self._results[key] = r

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
        assert self._worker is not None
        self._worker.send(key, request)
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
        if isinstance(r, SolverError):  # "the dynamic model's worker failed: ..."
            raise r
        assert isinstance(r, np.ndarray)
        fit.notes[self._note] = r
        return r

    def close(self) -> None:
        """Stop the worker (pending evaluations are dropped)."""
        if self._worker is not None:
            self._worker.close(kill=bool(self._pending))  # mid-evaluation: nothing to save
