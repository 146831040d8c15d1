"""The wear engine's explicit solvers: one simulated crank cycle extrapolated
over many real ones (`diffwear.wear._engine`; passed to `evolve` as
``method=``, as diffrax takes a solver object).

`Constant` (thesis Eq. 4-19): every simulated cycle stands for A real ones.
`Adaptive` (thesis Eq. 4-20): A grows while the wear increment stays smooth
and shrinks when it changes.  `ErrorControlled`: the profile as an ODE in the
cycle count, integrated by an embedded Heun-Euler pair with step-size control.

Each solver owns its step and the memory it keeps in the engine's state
(`init`); the engine owns the shared bookkeeping (the scan, the status, the
cut at the wall, the history).  Settings are static: a new value recompiles.
"""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jax import lax

from ..choices import METHOD_OF_SOLVER
from ..errors import InputError
from ._engine import AbstractWearSolver, Proposal, Stop, WearState

ADAPTIVE_CRITERIA = ("increment_change", "pressure_jump")


class AbstractExtrapolation(AbstractWearSolver):
    """An explicit rule that extrapolates one simulated cycle over many real ones."""

    name: ClassVar[str]

    def slots(self, stop: Stop, max_slots) -> int:
        if max_slots is None:
            raise InputError(f"method {self.name!r} needs max_dynamic (scan slots)")
        if int(max_slots) < 1:
            raise InputError(f"max_dynamic must be >= 1, got {max_slots}")
        return int(max_slots)

    def init(self, term, state: WearState, stop: Stop) -> WearState:
        return state

    def first_step(self, cycles) -> float:
        """The first extrapolation (real cycles per simulated one) of a run of
        ``cycles`` (a Python number)."""
        raise NotImplementedError


class Constant(AbstractExtrapolation):
    """Every simulated cycle stands for ``a`` real cycles (Eq. 4-19); the last
    one for what is left.  ceil(cycles / a) scan slots (``cycles`` must be a
    Python number)."""

    a: float = eqx.field(default=1.0, static=True)
    name: ClassVar[str] = METHOD_OF_SOLVER["Constant"]

    def __check_init__(self):
        if not (float(self.a) >= 1.0 and math.isfinite(float(self.a))):
            raise InputError(f"extrapolation factor A must be >= 1, got {self.a}")

    def first_step(self, cycles) -> float:
        return float(self.a)

    def slots(self, stop: Stop, max_slots) -> int:
        cycles = stop.cycles
        if float(cycles) <= 0:
            raise InputError(f"cycles must be > 0, got {cycles}")
        return int(math.ceil(float(cycles) / float(self.a) - 1e-9))

    def step(self, term, state: WearState, stop: Stop) -> Proposal:
        a_i = jnp.minimum(float(self.a), jnp.asarray(stop.end, dtype=float) - state.n)
        cw = term.modulate(term.cycle(state.h, state.memory), state.h, state.n, a_i)
        h, ls, memory, ok = term.advance(state.h, cw, a_i)
        return Proposal(h=h, dn=a_i, ok=ok, memory=memory, load_sliding=ls, evaluations=1,
                        solver={})


class Adaptive(AbstractExtrapolation):
    """A changed after every simulated cycle (Eq. 4-20): + ``inc_fraction`` of
    the run while the increment is smooth, - ``dec_fraction`` when it is not.
    Smooth: the increment changed by less than ``change_fraction`` of its peak
    since the last cycle (``criterion="increment_change"``), or the pressure's
    largest jump between neighbouring nodes is under ``p_crit_fraction`` of
    its peak (``"pressure_jump"``).  The thesis gives no constants; these are
    ours.  ``a0``: the first A (default ``a0_fraction`` of the run)."""

    # The thesis (Eq. 4-20) gives no constants; it started at A ~ 3900 and
    # settled near 6000 for 100,000 cycles, i.e. A ~ 4-6 % of the run.  Ours:
    # start at 1 % of the run, grow by 1 % of the run per smooth cycle, shrink
    # by 2 % when it is not, never below 1.  A pressure jump of 25 % of the peak
    # between neighbouring grid points marks a kinked profile (a smooth peak of
    # half-width >= 8 grid cells stays well below it); a 10 % change of the
    # per-cycle wear increment between two consecutive dynamic cycles marks a
    # non-smooth evolution (the steady rig cycles differ by well under 1 %, the
    # start-up transient by more).
    a0: float | None = eqx.field(default=None, static=True)
    a0_fraction: float = eqx.field(default=0.01, static=True)
    inc_fraction: float = eqx.field(default=0.01, static=True)
    dec_fraction: float = eqx.field(default=0.02, static=True)
    criterion: str = eqx.field(default="increment_change", static=True)
    change_fraction: float = eqx.field(default=0.10, static=True)
    p_crit_fraction: float = eqx.field(default=0.25, static=True)
    name: ClassVar[str] = METHOD_OF_SOLVER["Adaptive"]

    def __check_init__(self):
        if self.criterion not in ADAPTIVE_CRITERIA:
            raise InputError(f"adaptive criterion must be 'increment_change' or "
                             f"'pressure_jump', got {self.criterion!r}")

    def first_step(self, cycles) -> float:
        if self.a0 in (None, 1.0):
            return max(round(self.a0_fraction * float(cycles)), 1.0)
        return float(self.a0)

    def init(self, term, state: WearState, stop: Stop) -> WearState:
        end = jnp.asarray(stop.end, dtype=float)
        a0 = (jnp.maximum(jnp.round(self.a0_fraction * end), 1.0)
              if self.a0 in (None, 1.0) else jnp.asarray(self.a0, dtype=float))
        return state.replace(a=a0, dh_prev=jnp.zeros_like(state.h[0]))

    def step(self, term, state: WearState, stop: Stop) -> Proposal:
        ca = jnp.asarray(stop.end, dtype=float)
        a_inc = jnp.maximum(jnp.round(self.inc_fraction * ca), 1.0)
        a_dec = jnp.maximum(jnp.round(self.dec_fraction * ca), 1.0)
        c = state.solver
        a_i = jnp.minimum(c["a"], ca - state.n)
        cw = term.cycle(state.h, state.memory)
        dh = cw.rate[0]
        if self.criterion == "pressure_jump":
            # sliding-weighted mean pressure of the cycle at each node [Pa]
            radius, _, k = term.bushing()
            s_cycle = 2 * jnp.pi * radius  # relative rotation 2 pi per crank cycle
            p = dh / (k * s_cycle)
            jump = jnp.max(jnp.abs(jnp.roll(p, -1) - p))
            smooth = jump < self.p_crit_fraction * jnp.max(p)
        else:
            change = jnp.max(jnp.abs(dh - c["dh_prev"]))
            smooth = change < self.change_fraction * jnp.max(jnp.abs(dh))
        a_next = jnp.where(smooth, c["a"] + a_inc, jnp.maximum(c["a"] - a_dec, 1.0))
        h, ls, memory, ok = term.advance(state.h, cw, a_i)
        return Proposal(h=h, dn=a_i, ok=ok, memory=memory, load_sliding=ls, evaluations=1,
                        solver=dict(a=a_next, dh_prev=dh))


class ErrorControlled(AbstractExtrapolation):
    """dh/dN = wear of one simulated cycle at profile h, integrated in the
    cycle count N by an embedded Heun-Euler (RK2(1)) pair; a step is accepted
    when max_k |h_err| <= ``atol`` + ``rtol`` max_k |h| [m].  Two simulated
    cycles per accepted step, one per retry.  ``dn0``: the first step in
    cycles (default 1 % of the run)."""

    rtol: float = eqx.field(default=1e-2, static=True)
    atol: float = eqx.field(default=1e-7, static=True)
    dn0: float | None = eqx.field(default=None, static=True)
    name: ClassVar[str] = METHOD_OF_SOLVER["ErrorControlled"]

    def first_step(self, cycles) -> float:
        if self.dn0 in (None, 1.0):
            return max(0.01 * float(cycles), 1.0)
        return float(self.dn0)

    def init(self, term, state: WearState, stop: Stop) -> WearState:
        end = jnp.asarray(stop.end, dtype=float)
        dn0 = (jnp.maximum(0.01 * end, 1.0) if self.dn0 in (None, 1.0)
               else jnp.asarray(self.dn0, dtype=float))
        return state.replace(dn=dn0, have_k1=jnp.array(False), k1=jnp.zeros_like(state.h[0]),
                             ls1=jnp.zeros(()))

    def step(self, term, state: WearState, stop: Stop) -> Proposal:
        c = state.solver

        def stage1():
            cw = term.cycle(state.h, state.memory)
            return cw.rate[0], cw.load_sliding[0], cw.memory, cw.ok, 1

        def cached():
            return c["k1"], c["ls1"], state.memory, jnp.array(True), 0

        k1, ls1, memory1, ok1, n1 = lax.cond(c["have_k1"], cached, stage1)
        dn = jnp.minimum(c["dn"], jnp.asarray(stop.end, dtype=float) - state.n)
        h = state.h[0]
        cw2 = term.cycle((h + dn * k1,), memory1)
        k2 = cw2.rate[0]
        h_new = h + 0.5 * dn * (k1 + k2)
        err = 0.5 * dn * jnp.max(jnp.abs(k2 - k1))
        tol = self.atol + self.rtol * jnp.max(jnp.abs(h_new))
        ratio = err / tol
        accept = ratio <= 1.0
        factor = jnp.clip(0.9 * jnp.where(ratio > 0, ratio, 1e-10) ** -0.5, 0.3, 4.0)
        dls = 0.5 * dn * (ls1 + cw2.load_sliding[0])
        return Proposal(
            h=(jnp.where(accept, h_new, h),), dn=jnp.where(accept, dn, 0.0), ok=ok1 & cw2.ok,
            memory=cw2.memory, load_sliding=jnp.where(accept, dls, 0.0)[None],
            evaluations=n1 + 1,
            solver=dict(dn=dn * factor, have_k1=~accept, k1=k1, ls1=ls1))


__all__ = ["AbstractExtrapolation", "Adaptive", "Constant", "ErrorControlled"]
