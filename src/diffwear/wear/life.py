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
Explicit Euler (``scheme="euler"``) is unstable for dN beyond about
1 / lambda, lambda = k k_f s_contact (~1e-3 per cycle on the Ch. 8 mechanism):
a worn node loses pressure at that rate.  ``scheme="implicit"`` (default)
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

The derivative: what is measured (Ch. 8 model, box centre, steps = 3)
--------------------------------------------------------------------
The mechanism state a slot starts from is passed on without its derivative
(`lax.stop_gradient`): the cycle's wear depends on the design through the
cycle itself, not through the inherited pin state, whose tangent grows from
cycle to cycle.  Forward-mode autodiff (`jax.jacfwd`, diffrax `ForwardMode`)
then behaves as follows against central differences of the same model:

* Cycle tolerance decides most of it.  At the default rtol = atol = 1e-6 the
  tangents reach 1e9 by the third slot (measured with A frozen) and 1e20-1e44
  at the end, and central differences themselves are not converged
  (dcyc1/dh1 = 2.4e6, 2.2e6, 1.0e7 cycles/m at relative steps 1e-2, 1e-3,
  1e-4): the integrator's error
  (step rejections changing with the design) is part of the derivative.  At
  rtol = atol = 1e-8 (2.5x the run time) the slot tangents stay finite.
* While the wear is shallow it is right: limit 0.2 mm, rtol 1e-8, the whole
  Jacobian within 0.12 % of the largest entry of each row (1e-2 relative
  central differences; `tests/test_life.py` checks 2 %).
* At the 2 mm limit it is close for the joint that reaches the limit first
  (cyc1 row within 1-4 % at rtol 1e-8) and wrong for the other (cyc2 row off
  by a factor ~30: dcyc2/dd2 = 2.7e8 vs -2e4 cycles/m).  The cyc2 row is
  set by the slots run after joint 1 is held at its end-of-life profile (a
  groove over 2 mm deep): there a single cycle's wear is rough in the design
  (central differences of one cycle's max increment change sign between
  relative steps 1e-2, 1e-3 and 1e-4 even at rtol 1e-8), already visible at
  a 1.7 mm groove (one cycle's jvp 8x below central differences).  The
  pointwise derivative of that cycle is not the slope of the life; no guard
  in this module changes that (it is in the dynamics of a deeply worn joint).
  Even the cyc1 row is right only by luck of rounding: writing the profile
  update as h + 1.0 (h_new - h) (a 1e-16 change) moved slot 3's cycle count
  by 2e-6 relative and jacfwd's dcyc1/dh1 by 9 % (2.61e6 -> 2.84e6
  cycles/m; 4 % -> 15 % of the row), while central differences at relative
  steps 1e-2, 3e-3, 1e-3 stayed within 2.51-2.56e6.  Holding a finished
  joint at its crossing profile (max depth = limit) instead of the slot's
  end sent the cyc2 tangents to ~5e9 (differences: ~9e6).  Both measured and
  not kept.
* Treating `wear_operator` A as a preconditioner (`lax.stop_gradient` on A)
  does not help and is wrong at coarse steps: with few slots the W-method's
  result depends on A at first order (1 % error instead of 0.02 % in the
  shallow case; cyc1 row 6 % instead of 1 % at 2 mm), so A is differentiated.

Callers that need a Jacobian of the Ch. 8 life therefore use central
differences (`diffwear.design.finite_difference_jacobian`, 1e-3 relative: it
averages over the roughness).
"""

from __future__ import annotations

from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

from ..errors import InputError
from ..mechanism import Mechanism
from .cycle import CYCLE_ATOL, CYCLE_RTOL, clearance_element, wear_cycle_joints, wear_parts
from .status import STATUS_INCOMPLETE, STATUS_OK, STATUS_SOLVER

SCHEMES = ("implicit", "euler")

# A per-cycle depth increment below this [m] counts as "not wearing" (1e-18 m
# per cycle is 1 nm per billion cycles): such a joint sets no step size.
_NO_WEAR_RATE = 1e-18
_MAX_STEP_CYCLES = 1e12  # cap on dN when no active joint wears at all
# Ridge added to M = U^T D U (units: grid nodes in contact) in `wear_operator`.
# Without it M^-1 is singular in free flight and its derivative (through the
# contact indicator D) swamps the gradient; 0.01 of a node changes the
# projection by < 0.1 % for a contact arc of >= 10 nodes.
OPERATOR_RIDGE = 1e-2


class LifeResult(eqx.Module):
    """Per-joint cycles to the limit and the evolution that found them.

    ``cycles[j]``: real cycles until joint j's maximum depth reaches the limit
    (NaN if it did not within the slots: ``status`` 3).  ``depth``: final
    profiles (tuple, one per joint; held at the crossing slot's end once a
    joint is done).  ``history``: per scan slot ``cycles`` (N at its end),
    ``max_depth`` (per joint), ``step`` (dN) and ``valid``.
    """

    cycles: Float[Array, " J"]
    depth: tuple
    status: Array                # `diffwear.wear.status`: 0 ok, 2 solver failure, 3 incomplete, ...
    dynamic_cycles: Array        # dynamic cycles simulated (incl. warm-up; 0: quasi-static)
    history: dict


def not_computed_is_nan(cycles, inputs):
    """``cycles`` whose derivatives by every float leaf of ``inputs`` are NaN
    once any life is NaN (not computed).  A gradient through ``jnp.where(ok,
    life, nan)`` is 0 where not ok, which an optimiser reads as a flat
    optimum; a NaN scaled into the tangent does not survive the selects
    upstream in reverse mode.  So a term NaN x (sum of the inputs) is added
    where a life is NaN (0 x it elsewhere: the value and the derivatives of
    the computed lives are unchanged; infinite leaves are left out)."""
    leaves = jax.tree.leaves(eqx.filter(inputs, eqx.is_inexact_array))
    probe = sum((jnp.sum(jnp.where(jnp.isfinite(v), v, 0.0)) for v in leaves),
                jnp.zeros(()))
    return cycles + jnp.where(jnp.isnan(cycles), jnp.nan, 0.0) * probe


def _with_profiles(mech: Mechanism, indices, bases, depths) -> Mechanism:
    for i, base, h in zip(indices, bases, depths):
        mech = eqx.tree_at(lambda m: m.forces[i].profile.clearance, mech, base + h)
    return mech


def wear_operator(mech: Mechanism, joint: str, ys: Float[Array, "T s"], period,
                  width=1e-6) -> Float[Array, "n n"]:
    """The cycle-integrated linear response A of the wear increment to the
    profile, d(dh)/dh ~ -A, of an elastic-foundation joint (see module notes).

    At every saved state (``ys``, equally spaced over one cycle, both ends
    included) the nodes in contact, D = diag(step(delta_k, width)), respond to a
    deeper profile with a pressure drop k_f (I - U M^-1 U^T D) dh, where the
    pin translation U M^-1 U^T D dh (M = U^T D U, U = [cos, sin]) keeps the
    contact resultant, i.e. the joint force, unchanged.  Weighted by the
    sliding increment ds and by k, and summed over the cycle (trapezoid rule).
    """
    from ..contact import smoothing

    _, el = clearance_element(mech, joint)
    theta = el.profile.theta
    u = jnp.stack([jnp.cos(theta), jnp.sin(theta)], axis=-1)  # (n, 2)
    n = theta.shape[0]

    def sample(y):
        q, qd, _ = mech.split(y)
        kin = el.kinematics(mech.frames(q, qd))
        d = smoothing.step(u @ kin.offset - el.profile.clearance, width)
        m = u.T @ (d[:, None] * u) + OPERATOR_RIDGE * jnp.eye(2)
        follow = u @ jnp.linalg.solve(m, u.T * d[None, :])  # (n, n) pin translation
        response = d[:, None] * (jnp.eye(n) - follow)
        return response, el.sliding_rate(kin)

    responses, rates = jax.vmap(sample)(ys)
    w = period * jnp.ones(ys.shape[0]).at[0].set(0.5).at[-1].set(0.5) / (ys.shape[0] - 1)
    law, wear = wear_parts(el)
    return wear.coefficient * law.stiffness * jnp.einsum("t,tij->ij", w * rates, responses)


def _cycles_to_gain(h, dh, target):
    """The dN at which max_k (h_k + dN dh_k) first reaches ``target`` (>= max h):
    min over wearing nodes of (target - h_k) / dh_k (exact: the maximum of
    lines is reached first by the line that gets there first)."""
    wearing = dh > _NO_WEAR_RATE
    safe = jnp.where(wearing, dh, 1.0)  # double where: no 1/0 in the gradient
    return jnp.min(jnp.where(wearing, (target - h) / safe, _MAX_STEP_CYCLES))


def dynamic_cycles_to_limit(
    mech: Mechanism,
    joints: tuple[str, ...],
    y0: Float[Array, " s"],
    *,
    period,
    limit,
    steps: int = 10,
    scheme: str = "implicit",
    operator_samples: int = 181,
    operator_width=1e-6,
    slots: int | None = None,
    warmup_cycles: int = 1,
    cycle_rtol: float = CYCLE_RTOL,
    cycle_atol: float = CYCLE_ATOL,
    adjoint=None,
    max_steps: int = 200_000,
    cycle_solver=None,
) -> LifeResult:
    """Cycles until the maximum bushing wear depth of each of ``joints`` reaches
    ``limit`` [m] (see the module notes for the stepping and the derivative).

    ``steps``: slots the fastest-wearing joint takes to reach the limit (the
    accuracy knob; the error falls as 1 / steps).  ``scheme``: "implicit" or
    "euler" (module notes); ``operator_samples`` states per cycle and
    ``operator_width`` [m] contact band of `wear_operator`.  ``slots``: scan
    slots (default 3 x steps + 4: the implicit gain per slot is below
    limit / steps, and the slowest joint carries on once the fastest is done).
    ``warmup_cycles`` dynamic cycles run first with their wear
    discarded (the pin's start-up transient).  ``cycle_solver``: the dynamic
    cycles' integrator (default Tsit5; `diffwear.wear.cycle.CYCLE_INTEGRATORS`).
    Pure and jit-able; a solver failure or a joint that never reaches the
    limit is reported in ``status``.
    """
    joints = tuple(joints)
    if not joints:
        raise InputError("cycles_to_limit needs at least one wearing joint")
    if scheme not in SCHEMES:
        raise InputError(f"scheme must be one of {SCHEMES}, got {scheme!r}")
    if int(steps) < 1:
        raise InputError(f"steps must be >= 1, got {steps}")
    n_slots = 3 * int(steps) + 4 if slots is None else int(slots)
    if n_slots < 1:
        raise InputError(f"slots must be >= 1, got {slots}")
    found = [clearance_element(mech, j) for j in joints]
    indices = [i for i, _ in found]
    bases = [el.profile.clearance for _, el in found]
    limit = jnp.asarray(limit, dtype=float)
    dh_target = limit / steps
    n_j = len(joints)
    kw = dict(rtol=cycle_rtol, atol=cycle_atol, adjoint=adjoint, max_steps=max_steps,
              solver=cycle_solver)

    def run_cycle(hs, y, t, n_save=None):
        return wear_cycle_joints(_with_profiles(mech, indices, bases, hs), joints, y, t,
                                 period, n_save=n_save, **kw)

    zeros = tuple(jnp.zeros_like(b) for b in bases)
    y, t, ok = y0, jnp.zeros(()), jnp.array(True)
    for _ in range(warmup_cycles):
        r = run_cycle(zeros, y, t)
        y, t, ok = r.y_end, t + period, ok & r.ok
    state = dict(h=zeros, y=y, t=t, n=jnp.zeros(()), life=jnp.full((n_j,), jnp.nan),
                 done=jnp.zeros((n_j,), bool), dyn=jnp.asarray(warmup_cycles),
                 status=jnp.where(ok, STATUS_OK, STATUS_SOLVER))

    def active(c):
        return (c["status"] == STATUS_OK) & ~jnp.all(c["done"])

    def do(c):
        implicit = scheme == "implicit"
        # the state a slot starts from carries no derivative (module notes)
        r = run_cycle(c["h"], lax.stop_gradient(c["y"]), c["t"],
                      n_save=operator_samples if implicit else None)
        m_old = jnp.stack([jnp.max(h) for h in c["h"]])
        dn_joint = jnp.stack([_cycles_to_gain(h, dh, m + dh_target)
                              for h, dh, m in zip(c["h"], r.depth_increment, m_old)])
        dn = jnp.min(jnp.where(c["done"], _MAX_STEP_CYCLES, dn_joint))
        rate = r.depth_increment
        if implicit:  # linearly implicit Euler: (I + dN A) dh_step = dN f(h)
            worn = _with_profiles(mech, indices, bases, c["h"])
            rate = tuple(jnp.linalg.solve(jnp.eye(dh.shape[0]) + dn * wear_operator(
                worn, j, r.ys, period, operator_width), dh) for j, dh in zip(joints, rate))
        h_new = tuple(jnp.where(d, h, h + dn * dh) for d, h, dh in zip(c["done"], c["h"], rate))
        m_new = jnp.stack([jnp.max(h) for h in h_new])
        cross = ~c["done"] & (m_new >= limit)
        gain = jnp.where(cross, m_new - m_old, 1.0)
        n_cross = c["n"] + dn * (limit - m_old) / gain
        bad = ~r.ok
        out = dict(c)
        out["h"] = tuple(jnp.where(bad, h, hn) for h, hn in zip(c["h"], h_new))
        out["y"] = jnp.where(bad, c["y"], r.y_end)
        out["t"] = c["t"] + period
        out["n"] = jnp.where(bad, c["n"], c["n"] + dn)
        out["life"] = jnp.where(cross & ~bad, n_cross, c["life"])
        out["done"] = c["done"] | (cross & ~bad)
        out["dyn"] = c["dyn"] + 1
        out["status"] = jnp.where(bad, STATUS_SOLVER, c["status"])
        return out, dn

    def step(c, _):
        go = active(c)
        c2, dn = lax.cond(go, do, lambda c: (c, jnp.zeros(())), c)
        rec = dict(cycles=c2["n"], max_depth=jnp.stack([jnp.max(h) for h in c2["h"]]),
                   step=dn, valid=go)
        return c2, rec

    final: dict[str, Any]
    final, hist = lax.scan(step, state, None, length=n_slots)
    short = (final["status"] == STATUS_OK) & ~jnp.all(final["done"])
    return LifeResult(
        cycles=final["life"], depth=final["h"],
        status=jnp.where(short, STATUS_INCOMPLETE, final["status"]),
        dynamic_cycles=final["dyn"], history=hist,
    )
