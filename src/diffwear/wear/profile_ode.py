"""The wear profile as an ODE in the cycle count, dh/dN = w(h), for one joint
given as a plain function: `integrate_profile`, the wear engine
(`diffwear.wear._engine`) with the `LinearlyImplicitEuler` solver.

w(h) is the wear of one crank cycle at profile h (any cycle model); A(h) =
-dw/dh its response to the profile.  The solver's notes
(`diffwear.wear.implicit`) give the step, its size in depth and the Hermite
crossing of the life.
"""

from __future__ import annotations

from typing import Any, Callable

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from ._engine import (
    MAX_CYCLES,
    AbstractWearSolver,
    AbstractWearTerm,
    CycleWear,
    Stop,
    WearState,
    integrate,
)
from .implicit import NO_WEAR_RATE, LinearlyImplicitEuler
from .solution import WearSolution
from .status import stack

__all__ = ["ProfileHistory", "integrate_profile", "solve_profile", "NO_WEAR_RATE"]


class ProfileHistory(eqx.Module):
    """Per step (index 0 = the start): real cycles N, peak depth [m], the
    profile [m] (None where the integration does not keep them), and whether
    the step was taken."""

    cycles: Float[Array, " K"]
    peak: Float[Array, " K"]
    depth: Float[Array, "K n"] | None
    valid: Bool[Array, " K"]

    @classmethod
    def from_slots(cls, h0, peak0, cycles, peak, valid, depth=None) -> "ProfileHistory":
        """The start (no cycles, the profile ``h0`` of peak depth ``peak0``),
        then one entry per scan slot of an integration's record: its
        ``cycles``, ``peak`` depths, ``valid`` flags and, where kept, profiles
        ``depth`` (else the history keeps none)."""
        return cls(cycles=jnp.concatenate([jnp.zeros(1), cycles]),
                   peak=jnp.concatenate([jnp.reshape(jnp.asarray(peak0, dtype=float), (1,)),
                                         peak]),
                   depth=None if depth is None else jnp.concatenate([h0[None], depth]),
                   valid=jnp.concatenate([jnp.ones(1, bool), valid]))


class _Function(AbstractWearTerm):
    """A cycle model given as ``evaluate(h, memory) -> (w, ok, A, memory)``."""

    evaluate: Callable = eqx.field(static=True)

    def cycle(self, h, memory) -> CycleWear:
        w, ok, a, memory = self.evaluate(h[0], memory)
        return CycleWear(rate=(w,), ok=ok, memory=memory, response=(a,))


def integrate_profile(
    evaluate: Callable,
    h0: Float[Array, " n"],
    *,
    steps: int,
    cycles=None,
    limit=None,
    max_steps: int | None = None,
    max_cycles=MAX_CYCLES,
    wall=jnp.inf,
    extrapolate: bool = False,
    memory: Any = None,
) -> WearSolution:
    """Integrate dh/dN = w(h) from ``h0`` over ``cycles`` real cycles, or until
    the peak depth reaches ``limit`` [m], or to whichever comes first (`Stop`).

    ``evaluate(h) -> (w, ok, A)``: the cycle model (wear per cycle), a
    success flag and the response matrix A = -dw/dh; with ``memory`` given,
    ``evaluate(h, memory) -> (w, ok, A, memory)`` also carries a pytree from
    one evaluation to the next (a solver's warm start: it must not change the
    answer, only its cost).  ``steps``: the accuracy knob
    (`LinearlyImplicitEuler`); ``max_steps`` scan slots (default 4 steps + 8).
    ``wall`` [m]: stop when the peak depth reaches it (`RESULTS.wall_reached`; ``cycles``
    and ``depth`` are then those at the wall).  Returns the joint's
    `WearSolution`.  Pure, jit-able and differentiable (forward and reverse
    mode).
    """
    if memory is None:
        plain = evaluate

        def evaluate(h, memory):
            return (*plain(h), memory)

        memory = jnp.zeros(())
    solver = LinearlyImplicitEuler(int(steps), extrapolate=extrapolate)
    stop = Stop(cycles=cycles, limit=limit, wall=wall, max_cycles=max_cycles)
    return solve_profile(_Function(evaluate), solver, h0, memory, stop,
                         solver.slots(stop, max_steps))


def solve_profile(term: AbstractWearTerm, solver: AbstractWearSolver, h0: Float[Array, " n"],
                  memory: Any, stop: Stop, slots: int) -> WearSolution:
    """One joint's profile from ``h0`` with ``term`` and ``solver`` until
    ``stop``, in ``slots`` scan slots: its `WearSolution` (the history with
    every slot's profile; no contact margins, no engine state)."""
    s, history = integrate(term, solver, WearState.initial((h0,), memory), stop=stop, slots=slots,
                           keep_profiles=True)
    nan = jnp.full(1, jnp.nan)
    return WearSolution(
        depth=(s.h[0],), joint_cycles=s.n[None], life=s.life, result=s.status,
        joint_result=stack([s.status]), contact_margin=nan, contact_margin_worn=nan,
        stats={"steps": s.steps[None], "evaluations": s.evaluations},
        history=(ProfileHistory.from_slots(h0, solver.peak(h0), history["cycles"],
                                           history["max_depth"][:, 0], history["valid"],
                                           history["depth"][0]),))
