"""The linearly implicit Euler solvers of the wear engine: steps chosen in depth.

The profile ODE dh/dN = w(h) is stiff: a node worn deeper than its
neighbours loses pressure, so its rate falls at lambda ~ k k_f s per cycle
(k the wear coefficient, k_f the foundation stiffness, s the sliding distance
per cycle: up to 4.5e-3 per cycle on the Ch. 7 rig, against lives of 1e4-1e6
cycles).  Both solvers take the linearly implicit (Rosenbrock) Euler step
with the response A = -dw/dh of the term,

    (I + dN A) dh = dN w(h),     h+ = h + dh,

first order for any A, stable when A holds the stiff part, and exact in the
two limits of a nearly affine w (the groove's shape settles at once, the pin
sinks in at a constant rate).  They differ in how dN is chosen:

* `LinearlyImplicitEuler` (smooth lives and runs, the quasi-static model):
  dN = dm / peak(w(h)) with the smooth peak depth (`diffwear.wear.peak`);
  dm = limit / steps for a life, peak(w(h0)) N / steps for a run of N cycles
  (the last step cut to land on N; a run that would wear through its wall is
  stepped as a life to it).  The rate at the step's end is kept for the next
  step (first same as last), and the life is the root of the cubic Hermite
  interpolant of the peak depth with the exact slopes at both ends: C1 in N.
* `DepthGain` (the dynamic model's life): the dN at which the deepest node of
  the fastest-wearing joint gains exactly limit / steps under the explicit
  step, min over nodes (limit / steps - (h_k - max h)) / w_k; the response A
  comes from the same cycle (``implicit=True``) or is left out
  (``implicit=False``).  The crossing is interpolated linearly in the maximum depth.
* `CycleGrid` (the calibration's histories): steps between given cycle
  counts, each from the rate at its start modulated over the step.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

from ..errors import InputError
from ._engine import (
    AbstractWearSolver,
    Proposal,
    Stop,
    WearState,
    hermite_root,
    linearly_implicit_step,
    peaks,
    per_joint,
)
from .peak import peak_depth
from .status import RESULTS

# A peak wear rate below this [m per cycle] (1 nm per 1e9 cycles) means the
# joint does not wear: it sets no step, and a life is never reached.
NO_WEAR_RATE = 1e-18
_WALL_NEWTON = 6
# cap on dN [cycles] when no active joint wears at all
_MAX_STEP_CYCLES = 1e12


def _step_all(h, rate, response, dn):
    return tuple(linearly_implicit_step(x, w, a, dn) for x, w, a in zip(h, rate, response))


class LinearlyImplicitEuler(AbstractWearSolver):
    """The linearly implicit Euler step with dN = dm / peak(w) (module notes).

    ``steps``: the accuracy knob (dm = limit / steps, or the run's first
    rate x N / steps); ``extrapolate``: Richardson extrapolation of two half
    steps (second order; one more cycle per step)."""

    steps: int
    extrapolate: bool = False

    def __check_init__(self):
        if int(self.steps) < 1:
            raise InputError(f"steps must be >= 1, got {self.steps}")

    def peak(self, h):
        return peak_depth(h)

    def _slopes(self, h, rate):
        return jnp.stack([jax.jvp(peak_depth, (x,), (w,))[1] for x, w in zip(h, rate)])

    def init(self, term, state: WearState, stop: Stop) -> WearState:
        cw = term.cycle(state.h, state.memory)
        j = len(state.h)
        end = jnp.asarray(stop.end, dtype=float)
        walls = jnp.stack(per_joint(stop.wall, j))
        # a run that would wear through its wall is stepped as a life to it
        dm = jnp.minimum(peaks(cw.rate, peak_depth) * end, walls) / self.steps
        if stop.limit is not None:  # a life's steps: limit / steps of depth
            limit = jnp.where(stop.has_limit, jnp.asarray(stop.limit, dtype=float), 0.0)
            dm = jnp.where(stop.has_limit, limit / self.steps, dm)
        return state.replace(
            memory=cw.memory, evaluations=state.evaluations + 1,
            status=RESULTS.where(cw.ok, state.status, RESULTS.cycle_model_failed),
            rate=cw.rate, response=cw.response, dm=dm)

    def step(self, term, state: WearState, stop: Stop) -> Proposal:
        c = state.solver
        end = jnp.asarray(stop.end, dtype=float)
        speed = peaks(c["rate"], peak_depth)
        dn_joint = jnp.where(speed > NO_WEAR_RATE, c["dm"] / jnp.maximum(speed, NO_WEAR_RATE),
                             end)
        dn = jnp.min(jnp.where(state.done, jnp.inf, dn_joint))
        dn = jnp.minimum(dn, end - state.n)
        h = _step_all(state.h, c["rate"], c["response"], dn)
        ok_mid, evaluations = jnp.asarray(True), 1
        if self.extrapolate:
            half = 0.5 * dn
            mid = _step_all(state.h, c["rate"], c["response"], half)
            cm = term.cycle(mid, state.memory)
            h2 = _step_all(mid, cm.rate, cm.response, half)
            h = tuple(2.0 * b - a for a, b in zip(h, h2))
            ok_mid, evaluations = cm.ok, 2
        cw = term.cycle(h, state.memory)
        joints = len(h)
        return Proposal(
            h=h, dn=dn, ok=cw.ok & ok_mid, memory=cw.memory, load_sliding=jnp.zeros(joints),
            evaluations=evaluations,
            solver=dict(rate=cw.rate, response=cw.response, dm=c["dm"]),
            peak_rates=(self._slopes(state.h, c["rate"]), self._slopes(h, cw.rate)))

    def cut(self, term, state: WearState, proposal: Proposal, stop: Stop, peak):
        """The step cut back to where the first joint's peak depth meets its
        wall: Newton on the length of the same linearly implicit step, from the
        Hermite crossing.  A run stopped at its wall reports the cycles and
        profile there, not a depth beyond it."""
        c = state.solver
        dn = proposal.dn
        walls = jnp.stack(per_joint(stop.wall, len(state.h)))

        def excess(length):
            h = _step_all(state.h, c["rate"], c["response"], length)
            return jnp.max(peaks(h, peak_depth) - walls)

        def newton(_, length):
            f, df = jax.jvp(excess, (length,), (jnp.ones_like(length),))
            ok = df > 0.0
            return jnp.clip(length - jnp.where(ok, f, 0.0) / jnp.where(ok, df, 1.0), 0.0, dn)

        m0 = peaks(state.h, peak_depth)
        m1 = peaks(proposal.h, peak_depth)
        s0, s1 = proposal.peak_rates
        first = jnp.argmax(m1 - walls)
        start = hermite_root(m0[first], m1[first], s0[first], s1[first], dn, walls[first]) * dn
        length = lax.fori_loop(0, _WALL_NEWTON, newton, start)
        fraction = jnp.where(dn > 0, length / jnp.where(dn > 0, dn, 1.0), 0.0)
        return fraction, _step_all(state.h, c["rate"], c["response"], length)

    def slots(self, stop: Stop, max_slots: int | None) -> int:
        return 4 * int(self.steps) + 8 if max_slots is None else int(max_slots)


def _cycles_to_gain(h, rate, target):
    """The dN at which max_k (h_k + dN w_k) first reaches ``target`` (>= max h):
    min over wearing nodes of (target - h_k) / w_k (exact: the maximum of lines
    is reached first by the line that gets there first)."""
    wearing = rate > NO_WEAR_RATE
    safe = jnp.where(wearing, rate, 1.0)  # double where: no 1/0 in the gradient
    return jnp.min(jnp.where(wearing, (target - h) / safe, _MAX_STEP_CYCLES))


class DepthGain(AbstractWearSolver):
    """The dynamic life's step (module notes): dN from the exact gain of the
    deepest node, the profile by the linearly implicit step with the cycle's
    response (``implicit``) or the explicit one.  ``steps``: slots the fastest
    joint takes to the limit (error ~ 1 / steps)."""

    steps: int
    implicit: bool = True

    def __check_init__(self):
        if int(self.steps) < 1:
            raise InputError(f"steps must be >= 1, got {self.steps}")

    def init(self, term, state: WearState, stop: Stop) -> WearState:
        return state

    def step(self, term, state: WearState, stop: Stop) -> Proposal:
        cw = term.cycle(state.h, state.memory)
        target = jnp.asarray(stop.limit, dtype=float) / self.steps
        m_old = peaks(state.h, jnp.max)
        dn_joint = jnp.stack([_cycles_to_gain(h, w, m + target)
                              for h, w, m in zip(state.h, cw.rate, m_old)])
        dn = jnp.min(jnp.where(state.done, _MAX_STEP_CYCLES, dn_joint))
        response = cw.response if self.implicit else (None,) * len(state.h)
        h = _step_all(state.h, cw.rate, response, dn)
        return Proposal(h=h, dn=dn, ok=cw.ok, memory=cw.memory,
                        load_sliding=jnp.zeros(len(h)), evaluations=1, solver={})

    def slots(self, stop: Stop, max_slots: int | None) -> int:
        # the implicit gain per slot is below limit / steps, and the slowest
        # joint carries on once the fastest is done
        return 3 * int(self.steps) + 4 if max_slots is None else int(max_slots)


class CycleGrid(AbstractWearSolver):
    """The linearly implicit step between given real cycle counts ``grid``
    (0 = N_0 < N_1 < ...; one step per interval), the rate taken at the
    step's start and modulated over it (`AbstractWearTerm.modulate`)."""

    grid: Float[Array, " K"]

    def init(self, term, state: WearState, stop: Stop) -> WearState:
        return state

    def step(self, term, state: WearState, stop: Stop) -> Proposal:
        k = jnp.minimum(state.steps, self.grid.shape[0] - 2)
        n0, dn = self.grid[k], self.grid[k + 1] - self.grid[k]
        cw = term.modulate(term.cycle(state.h, state.memory), state.h, n0, dn)
        h = _step_all(state.h, cw.rate, cw.response, dn)
        return Proposal(h=h, dn=dn, ok=cw.ok, memory=cw.memory,
                        load_sliding=jnp.zeros(len(h)), evaluations=1, solver={})

    def slots(self, stop: Stop, max_slots: int | None) -> int:
        return self.grid.shape[0] - 1


__all__ = ["LinearlyImplicitEuler", "DepthGain", "CycleGrid", "NO_WEAR_RATE"]
