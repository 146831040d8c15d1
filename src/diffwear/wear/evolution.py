"""Wear evolution over many crank cycles (thesis Ch. 4-6, Eq. 4-18..4-20).

The bushing wear profile h(theta_k) [m] is an array carried through
``jax.lax.scan`` over *dynamic* cycles.  Each scan step runs one dynamic cycle
(`wear_cycle`) with the current profile (``eqx.tree_at`` swaps the joint's
``profile``), carries the mechanism state (q, qd, contact-law memory) from the
end of one cycle into the next (no restart transient), and adds A x (wear of
that cycle) to the profile: one simulated cycle stands for A real cycles.

Methods
-------
``"constant"``  fixed A (A = 1: every cycle simulated).
``"adaptive"``  the thesis's scheme (Eq. 4-20): A_{j+1} = A_j + A_inc while the
                wear increment stays smooth, else A_j - A_dec; one integer A per
                cycle.  "Smooth" (``criterion``):
                ``"increment_change"`` (default): the wear increment of this
                cycle differs from the previous cycle's by less than
                ``change_fraction`` of its peak (smooth in cycle count);
                ``"pressure_jump"`` (the thesis's Delta p_ele < p_crit): the
                largest jump of the cycle-mean pressure p_k = dh_k / (k s_cycle)
                between neighbouring grid points stays below
                ``p_crit_fraction`` x max_k p_k.  On an EFM grid the edge of a
                worn pocket is such a jump, so this criterion shrinks A to 1
                once a pocket forms (seen on the rig: A = 1 after ~6 cycles);
                the thesis applied it to FEM element pressures.  The thesis
                gives no constants; ours are `ADAPTIVE_DEFAULTS`.
``"error"``     the profile as a slow ODE in the cycle count N,
                dh/dN = f(h) = wear of one dynamic cycle at profile h, integrated
                by an embedded Heun-Euler (RK2(1)) pair with step-size control on
                max_k |h_err| <= atol + rtol max_k |h|.  Accuracy decides how many
                dynamic cycles are simulated (2 per accepted step, 1 per retry).

Everything is a pure function of arrays (mechanism leaves included), so the
whole evolution jits once and differentiates (reverse or forward mode) w.r.t.
the wear coefficient, clearance, bushing depth and diameter.  Methods
"adaptive" and "error" run a fixed number of scan slots (``max_dynamic``);
slots after the end are skipped with ``lax.cond``.

Failure (bushing worn through, integrator failure) never raises inside jit:
the evolution stops updating, keeps the results so far and reports ``status``;
`EvolutionResult.check` raises `WearLimitError` naming the cycle and depth.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

from ..errors import InputError, SolverError
from ..mechanism import Mechanism
from .cycle import CYCLE_ATOL, CYCLE_RTOL, clearance_element, wear_cycle

STATUS_OK, STATUS_PIERCED, STATUS_SOLVER, STATUS_INCOMPLETE = 0, 1, 2, 3

# Adaptive-A constants (thesis Eq. 4-20 gives none; it started at A ~ 3900 and
# settled near 6000 for 100,000 cycles, i.e. A ~ 4-6 % of the run).  Ours: start
# at 1 % of the run, grow by 1 % of the run per smooth cycle, shrink by 2 % of
# the run when the pressure jump is too large, never below 1.  A jump
# of 25 % of the peak between neighbouring grid points marks a kinked profile
# (a smooth peak of half-width >= 8 grid cells stays well below it).
# "increment_change": a 10 % change of the per-cycle wear increment between two
# consecutive dynamic cycles marks a non-smooth evolution (the steady rig cycles
# differ by well under 1 %, the start-up transient by more).
ADAPTIVE_DEFAULTS = dict(a0_fraction=0.01, inc_fraction=0.01, dec_fraction=0.02,
                         criterion="increment_change", change_fraction=0.10,
                         p_crit_fraction=0.25)


class WearLimitError(SolverError):
    """The wear evolution stopped early; ``.result`` holds the results so far."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


def smooth_max(x: Float[Array, " n"], temperature) -> Float[Array, ""]:
    """Smooth maximum T log(sum exp(x / T)) - T log(n): within T log(n) of max(x)
    and differentiable everywhere (logsumexp with temperature T, units of x)."""
    n = x.shape[0]
    return temperature * (jax.nn.logsumexp(x / temperature) - math.log(n))


def worn_volume(depth_profile, bushing_radius, bushing_depth) -> Float[Array, ""]:
    """Archard volume [m^3]: bushing depth x integral of h R_b dtheta."""
    n = depth_profile.shape[-1]
    return bushing_depth * bushing_radius * (2 * jnp.pi / n) * jnp.sum(depth_profile, axis=-1)


class EvolutionResult(eqx.Module):
    """Final wear profile and state, counters, and per-slot history.

    ``history`` arrays have one entry per scan slot; ``history["valid"]`` marks
    the slots that advanced the profile.
    """

    depth: Float[Array, " n"]           # final wear depth on the grid [m]
    y: Float[Array, " s"]               # mechanism state at the end
    t: Float[Array, ""]                 # simulated time at the end [s]
    cycles: Float[Array, ""]            # real cycles represented
    dynamic_cycles: Array               # dynamic cycles simulated (incl. warm-up)
    load_sliding: Float[Array, ""]      # A-weighted sum of int N ds [N m]
    status: Array                       # 0 ok, 1 worn through, 2 solver failure, 3 out of slots
    fail_cycles: Float[Array, ""]       # real cycles done when it stopped
    fail_depth: Float[Array, ""]        # max depth when it stopped [m]
    history: dict

    def check(self, what: str = "wear evolution") -> "EvolutionResult":
        """Raise `WearLimitError` (carrying this result) if the run stopped early."""
        status = int(self.status)
        if status == STATUS_OK:
            return self
        cyc, dep = float(self.fail_cycles), float(self.fail_depth) * 1e3
        if status == STATUS_PIERCED:
            msg = (f"{what}: the wear reached the bushing wall after {cyc:.0f} cycles "
                   f"(max depth {dep:.4f} mm); stopped, results so far kept")
        elif status == STATUS_INCOMPLETE:
            msg = (f"{what}: all max_dynamic scan slots were used after {cyc:.0f} cycles "
                   f"(max depth {dep:.4f} mm) before reaching the requested cycles; raise "
                   "max_dynamic or loosen the extrapolation tolerances")
        else:
            msg = (f"{what}: the dynamic integration failed after {cyc:.0f} cycles "
                   f"(max depth {dep:.4f} mm); stopped, results so far kept. Tighten "
                   "the cycle tolerances or reduce the extrapolation factor")
        raise WearLimitError(msg, self)


def _with_profile(mech: Mechanism, index: int, clearance):
    return eqx.tree_at(lambda m: m.forces[index].profile.clearance, mech, clearance)


def evolve(
    mech: Mechanism,
    joint: str,
    y0: Float[Array, " s"],
    cycles,
    *,
    period,
    method: str = "constant",
    extrapolation=1.0,
    max_dynamic: int | None = None,
    rtol: float = 1e-2,
    atol: float = 1e-7,
    wall_thickness=None,
    warmup_cycles: int = 1,
    adaptive: dict | None = None,
    cycle_rtol: float = CYCLE_RTOL,
    cycle_atol: float = CYCLE_ATOL,
    adjoint=None,
    max_steps: int = 200_000,
) -> EvolutionResult:
    """Evolve the wear of clearance joint ``joint`` over ``cycles`` real cycles.

    ``period`` [s]: one crank cycle (2 pi / omega).  ``y0``: state at t = 0.
    ``extrapolation``: A for "constant" (static number of scan steps:
    ceil(cycles / A); ``cycles`` must then be a Python number); A_0 for
    "adaptive" (default 1 % of the run).  ``rtol``/``atol`` [m]: tolerance of
    method "error".  ``wall_thickness`` [m]: stop when max depth reaches it.
    ``warmup_cycles`` dynamic cycles are run first and their wear discarded
    (start-up transient of the pin from the centred position; the thesis drops
    its first ~1.3 revolutions too).
    """
    if method not in ("constant", "adaptive", "error"):
        raise InputError(f"method must be 'constant', 'adaptive' or 'error', got {method!r}")
    index, el = clearance_element(mech, joint)
    if method == "constant":
        a_check = float(extrapolation)
        if a_check < 1.0 or not math.isfinite(a_check):
            raise InputError(f"extrapolation factor A must be >= 1, got {a_check}")
        if float(cycles) <= 0:
            raise InputError(f"cycles must be > 0, got {cycles}")
    else:
        _slots(max_dynamic, cycles)
    c_base = el.profile.clearance
    radius, bdepth, k = el.bushing_radius, el.law.depth, el.wear.coefficient
    wall = jnp.inf if wall_thickness is None else jnp.asarray(wall_thickness, dtype=float)
    cycles_arr = jnp.asarray(cycles, dtype=float)

    def run_cycle(h, y, t, n_save=None):
        return wear_cycle(_with_profile(mech, index, c_base + h), joint, y, t, period,
                          rtol=cycle_rtol, atol=cycle_atol, adjoint=adjoint,
                          max_steps=max_steps, n_save=n_save)

    h0 = jnp.zeros_like(c_base)
    y, t = y0, jnp.zeros(())
    warm_ok = jnp.array(True)
    for _ in range(warmup_cycles):
        r = run_cycle(h0, y, t)
        y, t, warm_ok = r.y_end, t + period, warm_ok & r.ok

    base = dict(h=h0, y=y, t=t, n=jnp.zeros(()), dyn=jnp.asarray(warmup_cycles),
                ls=jnp.zeros(()), status=jnp.where(warm_ok, STATUS_OK, STATUS_SOLVER),
                fail_n=jnp.zeros(()), fail_h=jnp.zeros(()))

    def finish(c, h_new, y_new, t_new, dn, dls, ok):
        """Accept a step unless it failed or pierced the wall (then stop, keep old h)."""
        pierced = jnp.max(h_new) >= wall
        bad = (~ok) | pierced
        status = jnp.where(~ok, STATUS_SOLVER, jnp.where(pierced, STATUS_PIERCED, STATUS_OK))
        out = dict(c)
        out["h"] = jnp.where(bad, c["h"], h_new)
        out["y"] = jnp.where(bad, c["y"], y_new)
        out["t"] = jnp.where(bad, c["t"], t_new)
        out["n"] = jnp.where(bad, c["n"], c["n"] + dn)
        out["ls"] = jnp.where(bad, c["ls"], c["ls"] + dls)
        out["status"] = status
        out["fail_n"] = jnp.where(bad, c["n"] + dn, 0.0)
        out["fail_h"] = jnp.where(bad, jnp.max(h_new), 0.0)
        return out

    def record(c, a, valid):
        return dict(cycles=c["n"], max_depth=jnp.max(c["h"]),
                    volume=worn_volume(c["h"], radius, bdepth), extrapolation=a,
                    valid=valid, dynamic_cycles=c["dyn"])

    def active(c):
        return (c["status"] == STATUS_OK) & (c["n"] < cycles_arr - 1e-9)

    # ------------------------------------------------------------ constant A
    if method == "constant":
        a = float(extrapolation)
        if a < 1.0 or not math.isfinite(a):
            raise InputError(f"extrapolation factor A must be >= 1, got {a}")
        n_cycles = float(cycles)
        if n_cycles <= 0:
            raise InputError(f"cycles must be > 0, got {cycles}")
        n_steps = int(math.ceil(n_cycles / a - 1e-9))

        def step(c, _):
            def do(c):
                a_i = jnp.minimum(a, cycles_arr - c["n"])
                r = run_cycle(c["h"], c["y"], c["t"])
                out = finish(c, c["h"] + a_i * r.depth_increment, r.y_end, c["t"] + period,
                             a_i, a_i * r.load_sliding, r.ok)
                out["dyn"] = c["dyn"] + 1
                return out, a_i

            go = active(c)
            c2, a_i = lax.cond(go, do, lambda c: (c, jnp.zeros(())), c)
            return c2, record(c2, a_i, go)

        final, hist = lax.scan(step, base, None, length=n_steps)

    # --------------------------------------------------- adaptive (Eq. 4-20)
    elif method == "adaptive":
        opts = {**ADAPTIVE_DEFAULTS, **(adaptive or {})}
        a0 = (jnp.maximum(jnp.round(opts["a0_fraction"] * cycles_arr), 1.0)
              if extrapolation in (None, 1.0) else jnp.asarray(extrapolation, dtype=float))
        a_inc = jnp.maximum(jnp.round(opts["inc_fraction"] * cycles_arr), 1.0)
        a_dec = jnp.maximum(jnp.round(opts["dec_fraction"] * cycles_arr), 1.0)
        slots = _slots(max_dynamic, cycles)

        def step(c, _):
            def do(c):
                a_i = jnp.minimum(c["a"], cycles_arr - c["n"])
                r = run_cycle(c["h"], c["y"], c["t"])
                dh = r.depth_increment
                if opts["criterion"] == "pressure_jump":
                    # sliding-weighted mean pressure of the cycle at each node [Pa]
                    s_cycle = 2 * jnp.pi * radius  # relative rotation 2 pi per crank cycle
                    p = dh / (k * s_cycle)
                    jump = jnp.max(jnp.abs(jnp.roll(p, -1) - p))
                    smooth = jump < opts["p_crit_fraction"] * jnp.max(p)
                else:
                    change = jnp.max(jnp.abs(dh - c["dh_prev"]))
                    smooth = change < opts["change_fraction"] * jnp.max(jnp.abs(dh))
                out = finish(c, c["h"] + a_i * dh, r.y_end, c["t"] + period, a_i,
                             a_i * r.load_sliding, r.ok)
                out["dyn"] = c["dyn"] + 1
                out["a"] = jnp.where(smooth, c["a"] + a_inc, jnp.maximum(c["a"] - a_dec, 1.0))
                out["dh_prev"] = dh
                return out, a_i

            go = active(c)
            c2, a_i = lax.cond(go, do, lambda c: (c, jnp.zeros(())), c)
            return c2, record(c2, a_i, go)

        if opts["criterion"] not in ("increment_change", "pressure_jump"):
            raise InputError(f"adaptive criterion must be 'increment_change' or "
                             f"'pressure_jump', got {opts['criterion']!r}")
        final, hist = lax.scan(step, {**base, "a": a0, "dh_prev": h0}, None, length=slots)

    # ------------------------------------------ error-controlled (Heun-Euler)
    else:
        slots = _slots(max_dynamic, cycles)
        dn0 = (jnp.maximum(0.01 * cycles_arr, 1.0) if extrapolation in (None, 1.0)
               else jnp.asarray(extrapolation, dtype=float))

        def step(c, _):
            def do(c):
                def stage1(c):
                    r = run_cycle(c["h"], c["y"], c["t"])
                    return r.depth_increment, r.load_sliding, r.y_end, c["t"] + period, r.ok, 1

                def cached(c):
                    return c["k1"], c["ls1"], c["y"], c["t"], jnp.array(True), 0

                k1, ls1, y1, t1, ok1, n1 = lax.cond(c["have_k1"], cached, stage1, c)
                dn = jnp.minimum(c["dn"], cycles_arr - c["n"])
                r2 = run_cycle(c["h"] + dn * k1, y1, t1)
                k2 = r2.depth_increment
                h_new = c["h"] + 0.5 * dn * (k1 + k2)
                err = 0.5 * dn * jnp.max(jnp.abs(k2 - k1))
                tol = atol + rtol * jnp.max(jnp.abs(h_new))
                ratio = err / tol
                accept = ratio <= 1.0
                ok = ok1 & r2.ok
                factor = jnp.clip(0.9 * jnp.where(ratio > 0, ratio, 1e-10) ** -0.5, 0.3, 4.0)
                dls = 0.5 * dn * (ls1 + r2.load_sliding)
                out = finish(c, jnp.where(accept, h_new, c["h"]), r2.y_end, t1 + period,
                             jnp.where(accept, dn, 0.0), jnp.where(accept, dls, 0.0), ok)
                out["dyn"] = c["dyn"] + n1 + 1
                out["dn"] = dn * factor
                out["have_k1"] = ~accept
                out["k1"], out["ls1"] = k1, ls1
                return out, jnp.where(accept, dn, 0.0)

            go = active(c)
            c2, a_i = lax.cond(go, do, lambda c: (c, jnp.zeros(())), c)
            return c2, record(c2, a_i, go & (a_i > 0))

        init = {**base, "dn": dn0, "have_k1": jnp.array(False), "k1": h0,
                "ls1": jnp.zeros(())}
        final, hist = lax.scan(step, init, None, length=slots)

    # all scan slots used before reaching ``cycles``: say so, never return a short run
    short = (final["status"] == STATUS_OK) & (final["n"] < cycles_arr - 1e-6)
    return EvolutionResult(
        depth=final["h"], y=final["y"], t=final["t"], cycles=final["n"],
        dynamic_cycles=final["dyn"], load_sliding=final["ls"],
        status=jnp.where(short, STATUS_INCOMPLETE, final["status"]),
        fail_cycles=jnp.where(short, final["n"], final["fail_n"]),
        fail_depth=jnp.where(short, jnp.max(final["h"]), final["fail_h"]), history=hist,
    )


def _slots(max_dynamic, cycles) -> int:
    if max_dynamic is None:
        raise InputError("methods 'adaptive' and 'error' need max_dynamic (scan slots)")
    if int(max_dynamic) < 1:
        raise InputError(f"max_dynamic must be >= 1, got {max_dynamic}")
    return int(max_dynamic)
