"""How the wear evolution extrapolates one simulated crank cycle over many
real ones: strategy objects passed to `evolve` / `Evolver` as ``method=``, as
diffrax takes a solver object.

`Constant` (thesis Eq. 4-19): every simulated cycle stands for A real ones.
`Adaptive` (thesis Eq. 4-20): A grows while the wear increment stays smooth
and shrinks when it changes.  `ErrorControlled`: the profile as an ODE in the
cycle count, integrated by an embedded Heun-Euler pair with step-size control.

Each strategy owns its scan step and the memory it keeps in the evolution
state (`init`); `Evolver` owns the shared bookkeeping (`run_cycle`, `finish`,
`record`, `when_active`).  The names ``"constant"``, ``"adaptive"`` and
``"error"`` (the command line's ``--method``) map onto them through
`extrapolation_method`.  Settings are static: a new value recompiles.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar, Protocol

import equinox as eqx
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array

from ..choices import WEAR_METHODS
from ..errors import InputError
from .state import EvolutionState


class EvolutionDriver(Protocol):
    """What a strategy uses of the evolution that drives it
    (`diffwear.wear.evolution.Evolver`)."""

    cycles_arr: Array
    period: Any
    radius: Any
    k: Any

    def run_cycle(self, h, y, t, n_save=None) -> Any: ...

    def advance(self, c: EvolutionState, a) -> tuple: ...

    def finish(self, c: EvolutionState, h_new, y_new, t_new, dn, dls, ok
               ) -> EvolutionState: ...

    def record(self, c: EvolutionState, a, valid) -> dict: ...

    def when_active(self, do, c: EvolutionState) -> tuple: ...


ADAPTIVE_CRITERIA = ("increment_change", "pressure_jump")


class AbstractExtrapolation(eqx.Module):
    """A rule that advances the evolution by one scan slot."""

    name: ClassVar[str]

    def slots(self, cycles, max_dynamic) -> int:
        """Scan slots the evolution over ``cycles`` needs (static)."""
        if max_dynamic is None:
            raise InputError(f"method {self.name!r} needs max_dynamic (scan slots)")
        if int(max_dynamic) < 1:
            raise InputError(f"max_dynamic must be >= 1, got {max_dynamic}")
        return int(max_dynamic)

    def init(self, ev: EvolutionDriver, c: EvolutionState) -> EvolutionState:
        """The strategy's memory added to the initial evolution state."""
        return c

    def step(self, ev: EvolutionDriver, c: EvolutionState, _):
        """One scan slot: (new state, history entry)."""
        raise NotImplementedError


class Constant(AbstractExtrapolation):
    """Every simulated cycle stands for ``a`` real cycles (Eq. 4-19); the last
    one for what is left.  ceil(cycles / a) scan slots (``cycles`` must be a
    Python number)."""

    a: float = eqx.field(default=1.0, static=True)
    name: ClassVar[str] = "constant"

    def __check_init__(self):
        if not (float(self.a) >= 1.0 and math.isfinite(float(self.a))):
            raise InputError(f"extrapolation factor A must be >= 1, got {self.a}")

    def slots(self, cycles, max_dynamic) -> int:
        if float(cycles) <= 0:
            raise InputError(f"cycles must be > 0, got {cycles}")
        return int(math.ceil(float(cycles) / float(self.a) - 1e-9))

    def step(self, ev: EvolutionDriver, c: EvolutionState, _):
        def do(c):
            a_i = jnp.minimum(float(self.a), ev.cycles_arr - c.n)
            step, ls, y_end, ok, memory = ev.advance(c, a_i)
            out = ev.finish(c, c.h + step, y_end, c.t + ev.period, a_i, ls, ok)
            return out.replace(dyn=c.dyn + 1, **memory), a_i

        c2, a_i, go = ev.when_active(do, c)
        return c2, ev.record(c2, a_i, go)


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
    name: ClassVar[str] = "adaptive"

    def __check_init__(self):
        if self.criterion not in ADAPTIVE_CRITERIA:
            raise InputError(f"adaptive criterion must be 'increment_change' or "
                             f"'pressure_jump', got {self.criterion!r}")

    def init(self, ev: EvolutionDriver, c: EvolutionState) -> EvolutionState:
        a0 = (jnp.maximum(jnp.round(self.a0_fraction * ev.cycles_arr), 1.0)
              if self.a0 in (None, 1.0) else jnp.asarray(self.a0, dtype=float))
        return c.replace(a=a0, dh_prev=jnp.zeros_like(c.h))

    def step(self, ev: EvolutionDriver, c: EvolutionState, _):
        ca = ev.cycles_arr
        a_inc = jnp.maximum(jnp.round(self.inc_fraction * ca), 1.0)
        a_dec = jnp.maximum(jnp.round(self.dec_fraction * ca), 1.0)

        def do(c):
            a_i = jnp.minimum(c.memory["a"], ca - c.n)
            r = ev.run_cycle(c.h, c.y, c.t)
            dh = r.depth_increment
            if self.criterion == "pressure_jump":
                # sliding-weighted mean pressure of the cycle at each node [Pa]
                s_cycle = 2 * jnp.pi * ev.radius  # relative rotation 2 pi per crank cycle
                p = dh / (ev.k * s_cycle)
                jump = jnp.max(jnp.abs(jnp.roll(p, -1) - p))
                smooth = jump < self.p_crit_fraction * jnp.max(p)
            else:
                change = jnp.max(jnp.abs(dh - c.memory["dh_prev"]))
                smooth = change < self.change_fraction * jnp.max(jnp.abs(dh))
            out = ev.finish(c, c.h + a_i * dh, r.y_end, c.t + ev.period, a_i,
                            a_i * r.load_sliding, r.ok)
            return out.replace(
                dyn=c.dyn + 1, dh_prev=dh,
                a=jnp.where(smooth, c.memory["a"] + a_inc,
                            jnp.maximum(c.memory["a"] - a_dec, 1.0))), a_i

        c2, a_i, go = ev.when_active(do, c)
        return c2, ev.record(c2, a_i, go)


class ErrorControlled(AbstractExtrapolation):
    """dh/dN = wear of one simulated cycle at profile h, integrated in the
    cycle count N by an embedded Heun-Euler (RK2(1)) pair; a step is accepted
    when max_k |h_err| <= ``atol`` + ``rtol`` max_k |h| [m].  Two simulated
    cycles per accepted step, one per retry.  ``dn0``: the first step in
    cycles (default 1 % of the run)."""

    rtol: float = eqx.field(default=1e-2, static=True)
    atol: float = eqx.field(default=1e-7, static=True)
    dn0: float | None = eqx.field(default=None, static=True)
    name: ClassVar[str] = "error"

    def init(self, ev: EvolutionDriver, c: EvolutionState) -> EvolutionState:
        dn0 = (jnp.maximum(0.01 * ev.cycles_arr, 1.0) if self.dn0 in (None, 1.0)
               else jnp.asarray(self.dn0, dtype=float))
        return c.replace(dn=dn0, have_k1=jnp.array(False), k1=jnp.zeros_like(c.h),
                         ls1=jnp.zeros(()))

    def step(self, ev: EvolutionDriver, c: EvolutionState, _):
        period, rtol, atol = ev.period, self.rtol, self.atol

        def do(c):
            def stage1(c):
                r = ev.run_cycle(c.h, c.y, c.t)
                return r.depth_increment, r.load_sliding, r.y_end, c.t + period, r.ok, 1

            def cached(c):
                return c.memory["k1"], c.memory["ls1"], c.y, c.t, jnp.array(True), 0

            k1, ls1, y1, t1, ok1, n1 = lax.cond(c.memory["have_k1"], cached, stage1, c)
            dn = jnp.minimum(c.memory["dn"], ev.cycles_arr - c.n)
            r2 = ev.run_cycle(c.h + dn * k1, y1, t1)
            k2 = r2.depth_increment
            h_new = c.h + 0.5 * dn * (k1 + k2)
            err = 0.5 * dn * jnp.max(jnp.abs(k2 - k1))
            tol = atol + rtol * jnp.max(jnp.abs(h_new))
            ratio = err / tol
            accept = ratio <= 1.0
            ok = ok1 & r2.ok
            factor = jnp.clip(0.9 * jnp.where(ratio > 0, ratio, 1e-10) ** -0.5, 0.3, 4.0)
            dls = 0.5 * dn * (ls1 + r2.load_sliding)
            out = ev.finish(c, jnp.where(accept, h_new, c.h), r2.y_end, t1 + period,
                            jnp.where(accept, dn, 0.0), jnp.where(accept, dls, 0.0), ok)
            out = out.replace(dyn=c.dyn + n1 + 1, dn=dn * factor, have_k1=~accept, k1=k1,
                              ls1=ls1)
            return out, jnp.where(accept, dn, 0.0)

        c2, a_i, go = ev.when_active(do, c)
        return c2, ev.record(c2, a_i, go & (a_i > 0))


def extrapolation_method(method, *, extrapolation=1.0, rtol=1e-2, atol=1e-7,
                         adaptive: dict | None = None) -> AbstractExtrapolation:
    """A strategy object as given, or one built from its name (``"constant"``
    with A = ``extrapolation``; ``"adaptive"`` with A_0 = ``extrapolation``
    and the ``adaptive`` settings; ``"error"`` with ``rtol``/``atol`` [m] and
    the first step ``extrapolation``)."""
    if isinstance(method, AbstractExtrapolation):
        return method
    if method not in WEAR_METHODS:
        raise InputError(f"method must be one of {', '.join(map(repr, WEAR_METHODS))} "
                         f"or an extrapolation object, got {method!r}")
    ex = None if extrapolation is None else float(extrapolation)
    if method == "constant":
        return Constant(1.0 if ex is None else ex)
    if method == "adaptive":
        opts = dict(adaptive or {})
        # A_0 comes from ``extrapolation``, not from the settings
        unknown = sorted(set(opts) - set(Adaptive.__dataclass_fields__) - {"name", "a0"})
        if unknown:
            raise InputError(f"adaptive settings {unknown}; allowed: a0_fraction, "
                             "inc_fraction, dec_fraction, criterion, change_fraction, "
                             "p_crit_fraction")
        return Adaptive(a0=ex, **opts)
    return ErrorControlled(rtol=float(rtol), atol=float(atol), dn0=ex)


__all__ = ["AbstractExtrapolation", "Adaptive", "Constant", "ErrorControlled",
           "extrapolation_method"]
