"""One dynamic crank cycle with Archard wear integrated as ODE states.

`wear_cycle` resets the wear accumulators of a clearance joint (bushing wear
depth h(theta_k) and the integral of normal load x sliding distance) to zero,
integrates the mechanism over one period and returns the end state and the
increments.  Because the increments are ODE states integrated with the
dynamics, they are exact for the discretised cycle (no quadrature of saved
forces afterwards): thesis Eq. 4-18 with A = 1, h += k p ds summed over steps.
"""

from __future__ import annotations

from typing import Any

import diffrax
import equinox as eqx
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float, Int

from .._checks import require_float64
from ..contact.archard import ArchardWear
from ..contact.clearance_joint import ClearanceJoint
from ..contact.laws import ElasticFoundation
from ..contact.mixed import MixedLubrication
from ..dynamics import AbstractRosenbrock, Rodas4, simulate
from ..dynamics.projection import stepping_solver
from ..errors import InputError
from ..mechanism import Mechanism

# Default integration tolerances of a wear cycle (rtol = atol on the whole
# state, SI units).  1e-6 resolves an EFM cycle of the Table 2-1 mechanism in
# ~3500 Tsit5 steps; tests/test_wear.py checks the wear result converges.
CYCLE_RTOL = 1e-6
CYCLE_ATOL = 1e-6

# The wear cycle's integrators by name, each with the tolerance (rtol = atol)
# at which it is used.  Tsit5 is stability-bound on the stiff EFM contact
# (~2,800 accepted steps per rig cycle at any rtol from 1e-4 to 1e-6); the
# linearly implicit, L-stable Rodas4 is not.  At rtol 1e-4 (~210 steps per rig
# cycle) it keeps the wear studies' depth and volume within 3.4e-3 of Tsit5
# (wear-5000's volume; tests/test_rosenbrock.py; the performance docs give the
# measurements).  ROS3P is not offered: it is A-stable only (R(-inf) = -0.73),
# and one wear-5000 dynamic cycle on it failed after a change of rounding.
CYCLE_INTEGRATORS: dict[str, tuple[type[diffrax.AbstractSolver], float]] = {
    "tsit5": (diffrax.Tsit5, CYCLE_RTOL),
    "rodas4": (Rodas4, 1e-4),
}


# A lubricated joint's cycle resolves its film: the whole state's tolerance
# (rtol = atol, SI units: positions of ~0.1-1 m) is at most this fraction of
# the combined roughness sigma in metres, the film thickness where the film
# saturates (lambda_b = 1), so that the pin's position is resolved to ~10 %
# of the thinnest film.  On the lubricated rig's cycle the wear then agrees
# with 1e-10's to ~6e-5 (measured at 1e-7 and 1e-8, either side of sigma / 10;
# at sigma itself, 2e-4: docs/notes/lubricated-motion.md).
FILM_TOLERANCE_FRACTION = 0.1


def film_tolerance(mech: Mechanism) -> Float[Array, ""] | None:
    """The tolerance (rtol = atol) at which ``mech``'s lubricated joints'
    films are resolved, `FILM_TOLERANCE_FRACTION` x the smallest roughness
    [m] (a setting of the integrator: no derivative flows through it); None
    without a lubricated joint."""
    laws = [getattr(f, "law", None) for f in mech.forces]
    sigmas = [law.roughness for law in laws if isinstance(law, MixedLubrication)]
    if not sigmas:
        return None
    return FILM_TOLERANCE_FRACTION * lax.stop_gradient(jnp.min(jnp.stack(sigmas)))


def lubricated_cycle(mech: Mechanism, rtol, atol, solver: diffrax.AbstractSolver | None
                     ) -> tuple[Any, Any, diffrax.AbstractSolver | None]:
    """(rtol, atol, solver) of a cycle of ``mech``: unchanged without a
    lubricated joint; with one, the tolerances at most `film_tolerance` and
    an explicit (or default) integrator replaced by Rodas4, since the film's
    squeeze damping (time constant pin mass / film damping, ~0.1 us) holds an
    explicit method at steps of that size."""
    tol = film_tolerance(mech)
    if tol is None:
        return rtol, atol, solver
    return jnp.minimum(rtol, tol), jnp.minimum(atol, tol), film_integrator(solver)


def film_integrator(solver: diffrax.AbstractSolver | None) -> diffrax.AbstractSolver:
    """The integrator of a cycle with a lubricated joint given ``solver``:
    a Rosenbrock method as it is, anything else (or the default) Rodas4."""
    if solver is None or not isinstance(stepping_solver(solver), AbstractRosenbrock):
        return Rodas4()
    return solver


def cycle_integrator(name: str) -> tuple[diffrax.AbstractSolver, float]:
    """(solver, tolerance) of the wear cycle's integrator ``name``
    (`CYCLE_INTEGRATORS`)."""
    try:
        cls, tol = CYCLE_INTEGRATORS[name]
    except KeyError:
        raise InputError(f"unknown cycle integrator {name!r}; choose one of "
                         f"{sorted(CYCLE_INTEGRATORS)}") from None
    return cls(), tol


def integrator_name(solver: diffrax.AbstractSolver | None) -> str:
    """The `CYCLE_INTEGRATORS` name of a cycle integrator (None: Tsit5, the
    default); its class name when it is none of them."""
    kind = diffrax.Tsit5 if solver is None else type(solver)
    return next((name for name, (cls, _) in CYCLE_INTEGRATORS.items() if cls is kind),
                kind.__name__)


class CycleResult(eqx.Module):
    """End state, wear-depth increment [m] on the grid, load x sliding increment
    [N m], integrator statistics, and (if requested) the saved trajectory."""

    y_end: Float[Array, " s"]
    depth_increment: Float[Array, " n"]
    load_sliding: Float[Array, ""]
    num_steps: Int[Array, ""]
    ok: Array
    ts: Float[Array, " T"] | None = None
    ys: Float[Array, "T s"] | None = None


def clearance_element(mech: Mechanism, joint: str) -> tuple[int, ClearanceJoint]:
    """(index in ``mech.forces``, element) of the clearance joint with wear."""
    for i, f in enumerate(mech.forces):
        if f.name == joint:
            if not isinstance(f, ClearanceJoint):
                raise InputError(f"{joint!r} is a {type(f).__name__}, not a ClearanceJoint")
            if f.wear is None:
                raise InputError(f"clearance joint {joint!r} has no wear law (wear=ArchardWear(k))")
            return i, f
    raise InputError(f"no clearance joint named {joint!r}; have {[f.name for f in mech.forces]}")


def wear_parts(el: ClearanceJoint) -> tuple[ElasticFoundation, ArchardWear]:
    """The elastic foundation that carries the joint's wearing contact (the
    dry law, or a lubricated joint's asperities) and its Archard wear (the
    wear routes read the foundation's bushing depth and stiffness)."""
    if el.law.solid_contact is None or el.wear is None:
        raise InputError(f"clearance joint {el.name!r}: its wear needs the elastic-foundation "
                         f"law and a wear law, got {type(el.law).__name__} and {el.wear!r}")
    return el.law.solid_contact, el.wear


def reset_wear(mech: Mechanism, joint: str, y: Float[Array, " s"]) -> Float[Array, " s"]:
    """``y`` with the wear accumulators of ``joint`` set to zero."""
    _, el = clearance_element(mech, joint)
    sl = mech.aux_slice(joint)
    start = 2 * mech.n_coords + sl.start + el.law.n_memory
    stop = 2 * mech.n_coords + sl.stop
    return y.at[start:stop].set(0.0)


class JointsCycleResult(eqx.Module):
    """`wear_cycle_joints`: like `CycleResult`, with one depth increment and one
    load x sliding increment per joint (tuples in the order of ``joints``)."""

    y_end: Float[Array, " s"]
    depth_increment: tuple
    load_sliding: tuple
    num_steps: Int[Array, ""]
    ok: Array
    ts: Float[Array, " T"] | None = None
    ys: Float[Array, "T s"] | None = None


def wear_cycle_joints(
    mech: Mechanism,
    joints: tuple[str, ...],
    y: Float[Array, " s"],
    t0,
    period,
    *,
    rtol: float = CYCLE_RTOL,
    atol: float = CYCLE_ATOL,
    n_save: int | None = None,
    adjoint: diffrax.AbstractAdjoint | None = None,
    max_steps: int = 200_000,
    solver: diffrax.AbstractSolver | None = None,
    step_to_saves: bool = False,
) -> JointsCycleResult:
    """One cycle [t0, t0 + period] from ``y`` with the wear states of every
    joint in ``joints`` reset: the wear of several joints in one integration.
    ``solver``: the integrator (default Tsit5; see `CYCLE_INTEGRATORS`);
    ``step_to_saves``: as `wear_cycle`.  A mechanism with a lubricated joint
    runs on Rodas4 at the film's tolerance (`lubricated_cycle`)."""
    require_float64("wear_cycle_joints")
    rtol, atol, solver = lubricated_cycle(mech, rtol, atol, solver)
    elements = [clearance_element(mech, j)[1] for j in joints]
    y0 = y
    for j in joints:
        y0 = reset_wear(mech, j, y0)
    t0 = jnp.asarray(t0, dtype=float)
    t1 = t0 + period
    ts = None if n_save is None else t0 + period * jnp.linspace(0.0, 1.0, n_save)
    controller = diffrax.PIDController(rtol=rtol, atol=atol, pcoeff=0.3, icoeff=0.4)
    if step_to_saves and ts is not None:  # every saved time the end of a step
        controller = diffrax.ClipStepSizeController(controller, step_ts=ts)
    traj = simulate(mech, y0, t1, t0=t0, ts=ts, adjoint=adjoint, max_steps=max_steps,
                    solver=solver, stepsize_controller=controller)
    y1 = traj.ys[-1]
    aux = mech.split(y1)[2]
    auxes = [aux[mech.aux_slice(j)] for j in joints]
    ok = (traj.result == diffrax.RESULTS.successful) & jnp.all(jnp.isfinite(y1))
    return JointsCycleResult(
        y_end=y1,
        depth_increment=tuple(el.wear_depth(a) for el, a in zip(elements, auxes)),
        load_sliding=tuple(el.load_sliding_integral(a) for el, a in zip(elements, auxes)),
        num_steps=traj.num_steps,
        ok=ok,
        ts=None if n_save is None else traj.ts,
        ys=None if n_save is None else traj.ys,
    )


def wear_cycle(
    mech: Mechanism,
    joint: str,
    y: Float[Array, " s"],
    t0,
    period,
    *,
    rtol: float = CYCLE_RTOL,
    atol: float = CYCLE_ATOL,
    n_save: int | None = None,
    adjoint: diffrax.AbstractAdjoint | None = None,
    max_steps: int = 200_000,
    solver: diffrax.AbstractSolver | None = None,
    step_to_saves: bool = False,
) -> CycleResult:
    """Integrate one cycle [t0, t0 + period] from state ``y`` (wear states reset).

    ``n_save``: also return the trajectory at ``n_save`` equally spaced times
    (for contact loci and joint-force plots).  ``solver``: the integrator
    (default Tsit5; `CYCLE_INTEGRATORS` names the choices and their
    tolerances; a lubricated joint's cycle runs on Rodas4 at its film's
    tolerance, `lubricated_cycle`: its wear is the asperities').
    ``step_to_saves``: the integrator steps exactly onto the ``n_save``
    times (diffrax's ``step_ts``), so the saved states are ends of steps,
    not the dense interpolant between them: needed on Rodas4, whose
    interpolant between its long steps misses the stiff contact (on a rig
    cycle at rtol 1e-4 the joint force at the saved times was up to 13 % of
    its peak off; stepped onto them, 1.1 %).  Pure and jit-able; failure is
    reported in ``ok`` (False on an integrator failure or a non-finite state).
    """
    require_float64("wear_cycle")
    r = wear_cycle_joints(mech, (joint,), y, t0, period, rtol=rtol, atol=atol, n_save=n_save,
                          adjoint=adjoint, max_steps=max_steps, solver=solver,
                          step_to_saves=step_to_saves)
    return CycleResult(y_end=r.y_end, depth_increment=r.depth_increment[0],
                       load_sliding=r.load_sliding[0], num_steps=r.num_steps, ok=r.ok,
                       ts=r.ts, ys=r.ys)
