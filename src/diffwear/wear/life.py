"""Wear life: crank cycles until each wearing joint reaches a wear-depth limit.

`cycles_to_limit` evolves the bushing profiles of several clearance joints
together (one dynamic integration per scan slot carries all of them, so the
joints interact through the dynamics) and returns, per joint, the real cycle
count N_j at which its maximum wear depth reaches ``limit``.

Stepping in depth, not in cycles
--------------------------------
The cycle count to a depth limit varies by an order of magnitude across a
design space, so a fixed cycle grid would waste slots on long-lived designs or
miss the limit on short-lived ones.  Instead each slot runs one dynamic cycle
at the current profiles, takes the per-cycle wear increments dh_j(theta) and
advances the real cycle count by

    dN = min over joints j not yet at the limit of the dN at which
         max_theta (h_j + dN dh_j) = max_theta h_j + limit / steps,

so the fastest-wearing joint would gain exactly ``limit / steps`` of maximum
depth per slot under an explicit Euler step of the profile ODE dh/dN = f(h)
(the maximum depth is the step variable; the peak may move along the bushing).
A joint that reaches the limit has its profile held (it is at its end of
life); the others carry on.

The profile update: explicit or linearly implicit
-------------------------------------------------
Explicit Euler (``implicit=False``) is unstable for dN beyond about
1 / lambda, lambda = k k_f s_contact (~1e-3 per cycle on the Ch. 8 mechanism):
a worn node loses pressure at that rate.  ``implicit=True`` (default)
solves (I + dN A) dh_step = dN f(h) with `wear_operator` A, the
cycle-integrated response of the wear increment to the profile (a
W-method: first order for any A, stable when A holds the stiff part).  The
gain per slot is then a little below ``limit / steps``.

The crossing, differentiably
----------------------------
Within the slot where joint j crosses, its maximum depth is interpolated
linearly between the slot's ends:

    N_j = N + dN (limit - m_old) / (m_new - m_old).

This is the implicit-function root of the piecewise-linear depth history
m_j(N) = limit: its derivative w.r.t. any parameter is
dN_j/dp = -(dm_j/dp) / (dm_j/dN) on that segment, which is what automatic
differentiation of the formula gives.  N_j is continuous when the crossing
moves from one slot to the next (at the switch m_new = limit and both formulas
give the slot's end), so the result is piecewise smooth with kinks only there
and where the fastest joint changes.  ``max`` over the profile grid is the
exact maximum (a subgradient at ties; no smoothing bias).

The derivative
--------------
The mechanism state a slot starts from is passed on without its derivative
(`lax.stop_gradient`): the cycle's wear depends on the design through the
cycle itself, not through the inherited pin state.  Forward-mode derivatives
of a shallow life at a tight cycle tolerance (1e-8) agree with central
differences (`tests/test_life.py`); at the Ch. 8 limit of 2 mm they do not
(design note "The dynamic life's derivative" gives the measurements).
Callers that need a Jacobian of the Ch. 8 life therefore use central
differences (`diffwear.design.finite_difference_jacobian`, 1e-3 relative: it
averages over the roughness).
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float

from ..errors import InputError
from ..mechanism import Mechanism
from ._engine import Stop, WearState, integrate
from .dynamic_term import CycleSettings, DynamicWear
from .implicit import DepthGain
from .profile_ode import ProfileHistory
from .solution import WearSolution
from .status import RESULTS, not_an_answer, not_computed, stack


def not_computed_is_nan(cycles, inputs):
    """``cycles`` whose derivatives by every float leaf of ``inputs`` are NaN
    where a life is NaN (not computed): `diffwear.wear.status.not_an_answer`
    (the value and the derivatives of the computed lives are unchanged)."""
    return not_an_answer(cycles, jnp.isnan(cycles), inputs)


def dynamic_cycles_to_limit(
    mech: Mechanism,
    joints: tuple[str, ...],
    y0: Float[Array, " s"],
    *,
    period,
    limit,
    steps: int = 10,
    implicit: bool = True,
    operator_samples: int = 181,
    operator_width=1e-6,
    slots: int | None = None,
    warmup_cycles: int = 1,
    cycle: CycleSettings = CycleSettings(),
) -> WearSolution:
    """Cycles until the maximum bushing wear depth of each of ``joints`` reaches
    ``limit`` [m] (see the module notes for the stepping and the derivative).

    ``steps``: slots the fastest-wearing joint takes to reach the limit (the
    accuracy knob; the error falls as 1 / steps).  ``implicit``: the linearly
    implicit profile update, else explicit Euler (module notes);
    ``operator_samples`` states per cycle and
    ``operator_width`` [m] contact band of `wear_operator`.  ``slots``: scan
    slots (default 3 x steps + 4: the implicit gain per slot is below
    limit / steps, and the slowest joint carries on once the fastest is done).
    ``warmup_cycles`` dynamic cycles run first with their wear
    discarded (the pin's start-up transient).  ``cycle``: how each dynamic
    cycle is integrated (`CycleSettings`).
    Pure and jit-able; a solver failure or a joint that never reaches the
    limit is reported in the final state's ``status``.

    Returns the joints' `WearSolution`: ``life`` per joint the cycles at the
    limit (NaN where not reached, with NaN derivatives); ``depth`` the final
    profiles, held at the crossing slot's end once a joint is done (NaN
    where a joint has no answer); ``joint_result`` per joint (a joint at
    its limit is done, the others share the run's result); the history per
    joint (cycles, peak depth, valid slots; not the profiles); ``stats``
    with the dynamic cycles simulated, warm-up included; the engine's final
    ``state``.  `diffwear.models.Dynamic.solve` with ``limit=`` is this.
    """
    joints = tuple(joints)
    if not joints:
        raise InputError("cycles_to_limit needs at least one wearing joint")
    solver = DepthGain(int(steps), implicit=bool(implicit))
    stop = Stop(limit=jnp.asarray(limit, dtype=float))
    n_slots = solver.slots(stop, slots)
    if n_slots < 1:
        raise InputError(f"slots must be >= 1, got {slots}")
    # the state a slot starts from carries no derivative (module notes)
    term = DynamicWear(mech, joints, jnp.asarray(period, dtype=float), cycle,
                       saves=operator_samples if implicit else None, response=implicit,
                       operator_width=operator_width, fresh_state=True)
    memory, ok = term.warm_up(y0, warmup_cycles)
    state = WearState.initial(term.zeros(), memory, evaluations=warmup_cycles, ok=ok)
    final, hist = integrate(term, solver, state, stop=stop, slots=n_slots)
    inputs = (mech, y0, period, limit, cycle)
    # a life not reached is NaN with NaN derivatives, never a silent 0
    final = final.replace(life=not_computed_is_nan(final.life, inputs))
    n = len(joints)
    # the joints run together: a joint at its limit is done (its life and
    # profile are answers), the others share the run's result
    joint_result = stack([RESULTS.where(final.done[k], RESULTS.ok, final.status)
                          for k in range(n)])
    failed = not_computed(joint_result)
    nan = jnp.full(n, jnp.nan)
    return WearSolution(
        depth=tuple(not_an_answer(h, failed[k], inputs) for k, h in enumerate(final.h)),
        joint_cycles=jnp.full(n, final.n), life=final.life,
        result=final.status, joint_result=joint_result,
        contact_margin=nan, contact_margin_worn=nan,
        stats={"steps": jnp.full(n, final.steps), "evaluations": final.evaluations,
               "dynamic_cycles": final.evaluations},
        history=tuple(ProfileHistory.from_slots(None, 0.0, hist["cycles"], hist["max_depth"][:, k],
                                                hist["valid"]) for k in range(n)),
        state=final)
