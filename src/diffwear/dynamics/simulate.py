"""Time integration of a `Mechanism` with diffrax.

`simulate` is a pure, jit-able function; it never raises on a numerical
failure (that is impossible under ``jit``).  It returns a `Trajectory` whose
``result`` says whether the solve succeeded; `Trajectory.raise_if_failed` turns a
failure into a `SolverError` that names the time reached.

Default solver: explicit Tsit5 with a PID step-size controller.  For the stiff
penalty contacts of this project this beat implicit Kvaerno5 by a wide margin
(see the performance docs).
"""

from __future__ import annotations

import dataclasses
from typing import Any, cast

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .._checks import check_finite, concrete, require_float64
from ..errors import InputError, SolverError
from ..mechanism import Mechanism
from .equations import Baumgarte, vector_field
from .projection import replace_inner, stepping_solver
from .rosenbrock import AbstractRosenbrock


class Trajectory(eqx.Module):
    """Saved states y(ts) = [q, qd, aux], the state where the integration ended
    (``t_final``, ``y_final``: t1 on success, the last accepted step on failure)
    and integrator statistics."""

    ts: Float[Array, " T"]
    ys: Float[Array, "T s"]
    t_final: Float[Array, ""]
    y_final: Float[Array, " s"]
    result: diffrax.RESULTS
    num_steps: Int[Array, ""]
    num_accepted_steps: Int[Array, ""]
    num_rejected_steps: Int[Array, ""]

    @property
    def succeeded(self):
        return self.result == diffrax.RESULTS.successful

    def reached(self) -> "Trajectory":
        """The saved states the integration reached before it stopped (all of
        them on success): the leading rows with finite times and states
        (diffrax fills the saved times it never reached with inf).  Call
        outside ``jit``."""
        ts, ys = np.asarray(self.ts), np.asarray(self.ys)
        ok = np.isfinite(ts) & np.all(np.isfinite(ys), axis=-1)
        n = ok.size if ok.all() else int(np.argmin(ok))
        return eqx.tree_at(lambda t: (t.ts, t.ys), self,
                           (jnp.asarray(ts[:n]), jnp.asarray(ys[:n])))

    @property
    def out_of_steps(self) -> bool:
        """Whether the integration stopped at its step budget (``max_steps``)."""
        return bool(self.result == diffrax.RESULTS.max_steps_reached)

    def raise_if_failed(self, what: str = "simulation", mech: Mechanism | None = None,
                        advice: str | None = None) -> "Trajectory":
        """Raise `SolverError` if the integrator failed or produced non-finite values.

        Call outside ``jit``.  With ``mech``, the message also describes each
        force element that can diagnose itself (e.g. a clearance joint's
        penetration) at the state where the integration ended.  ``advice``:
        the message's closing sentence (what to change), in place of the
        generic one.  Returns ``self``.
        """
        ts, ys = np.asarray(self.ts), np.asarray(self.ys)
        finite_rows = np.all(np.isfinite(ys), axis=-1)
        ok = bool(self.succeeded)
        if ok and finite_rows.all():
            return self
        # diffrax fills the saved times it never reached with inf
        reached = ts[finite_rows & np.isfinite(ts)]
        if reached.size:
            where = (f"last finite state saved at t = {reached.max():.6g} s "
                     f"({reached.size} of {ts.size} saved times reached)")
        else:
            where = f"no saved time was reached ({ts.size} requested)"
        if np.isfinite(float(self.t_final)):
            where += f"; integration ended at t = {float(self.t_final):.6g} s"
        if not ok:
            try:
                msg = str(cast(Any, diffrax.RESULTS)[self.result])
            except (KeyError, TypeError):  # older diffrax: no message lookup
                msg = str(self.result)
            reason = f"integrator stopped: {msg.rstrip('.')}."
        else:
            reason = "non-finite state (NaN or inf)."
        details = ""
        if mech is not None and np.all(np.isfinite(np.asarray(self.y_final))):
            q, qd, aux = mech.split(self.y_final)
            frames = mech.frames(q, qd)
            notes = [f.diagnose(frames, aux[mech.aux_slice(f.name)])
                     for f in mech.forces if hasattr(f, "diagnose")]
            details = "".join(f" {n}." for n in notes)
        if advice is None:
            advice = ("Raise max_steps." if self.out_of_steps else
                      "Tighten the tolerances, raise max_steps, or check the contact stiffness.")
        raise SolverError(
            f"{what}: {reason} After {int(self.num_steps)} steps; {where}.{details} {advice}"
        )


def _args_for_state_jacobian(args):
    """A Rosenbrock solver's Jacobian args: the mechanism with each force
    element's `for_state_jacobian` (same forces, cheaper Jacobian columns)."""
    mech, baumgarte = args
    return mech.for_state_jacobian(), baumgarte


def _check_inputs(mech: Mechanism, y0, t0, t1) -> None:
    """`InputError` for a state of the wrong length or precision and for
    times that are not finite or run backwards (concrete values; the shape
    and dtype inside a trace too)."""
    shape, dtype = jnp.shape(y0), jnp.result_type(y0)
    if shape != (mech.n_state,):
        raise InputError(f"simulate: y0 has shape {shape}; expected ({mech.n_state},): the "
                         f"positions and velocities of the mechanism's {len(mech.bodies)} "
                         "bodies (e.g. from consistent_state)")
    if dtype != jnp.float64:
        raise InputError(f"simulate: y0 is {dtype}; expected float64 (build it with "
                         "jnp.asarray(..., dtype=float) with jax_enable_x64 on)")
    check_finite("simulate: y0", y0)
    check_finite("simulate: t0", t0)
    check_finite("simulate: t1", t1)
    a, b = concrete(t0), concrete(t1)
    if a is not None and b is not None and not float(b) > float(a):
        raise InputError(f"simulate: t1 = {float(b):g} s must be after t0 = {float(a):g} s")


def simulate(
    mech: Mechanism,
    y0: Float[Array, " s"],
    t1,
    *,
    t0=0.0,
    ts: Float[Array, " T"] | None = None,
    baumgarte: Baumgarte | None = None,
    solver: diffrax.AbstractSolver | None = None,
    stepsize_controller: diffrax.AbstractStepSizeController | None = None,
    dt0=1e-4,
    max_steps: int = 2_000_000,
    adjoint: diffrax.AbstractAdjoint | None = None,
) -> Trajectory:
    """Integrate the mechanism from state ``y0`` at ``t0`` to ``t1`` [s].

    ``ts``: times at which to save (default: only ``t1``).  The defaults are
    Tsit5, a PID controller with rtol = atol = 1e-8 on the whole state, and
    recursive-checkpoint reverse-mode adjoints.  A Rosenbrock ``solver``
    (`Rodas4`, `ROS3P`, `ROS34PW2`) without ``jacobian_states`` gets the
    mechanism's `Mechanism.feedback_states` as its Jacobian structure and
    forms the Jacobian on `Mechanism.for_state_jacobian` (same values,
    cheaper columns).  ``solver=ConstraintProjection(diffrax.Tsit5())`` with
    ``baumgarte=Baumgarte(0.0, 0.0)`` replaces Baumgarte's stabilisation by a
    projection after every step (post-stabilisation: the same motion in far
    fewer steps where the Baumgarte modes set the step, e.g. an ideal
    mechanism; `diffwear.dynamics.projection`).
    """
    require_float64("simulate")
    _check_inputs(mech, y0, t0, t1)
    baumgarte = Baumgarte() if baumgarte is None else baumgarte
    solver = diffrax.Tsit5() if solver is None else solver
    if isinstance(stepping_solver(solver), AbstractRosenbrock):
        def configure(ros):
            if ros.jacobian_states is None:
                ros = dataclasses.replace(ros, jacobian_states=mech.feedback_states)
            if ros.jacobian_args is None:
                ros = dataclasses.replace(ros, jacobian_args=_args_for_state_jacobian)
            if ts is None:  # only t1 is saved: an end value of a step
                ros = dataclasses.replace(ros, dense_output=False)
            return ros

        solver = replace_inner(solver, configure)
    if stepsize_controller is None:
        stepsize_controller = diffrax.PIDController(rtol=1e-8, atol=1e-8, pcoeff=0.3, icoeff=0.4)
    adjoint = diffrax.RecursiveCheckpointAdjoint() if adjoint is None else adjoint
    t0 = jnp.asarray(t0, dtype=y0.dtype)
    t1 = jnp.asarray(t1, dtype=y0.dtype)
    # Keep XLA from constant-folding the step times: under an outer jit with
    # constant t0/t1 its algebraic simplifier rewrites t0 + (t1 - t0) * k / n as
    # k * dt, which moves some step times by one ulp.  The checkpointed reverse
    # pass then places a save time in a different step than the forward pass
    # did and returns a wrong gradient (tests/test_gradients.py reproduces it).
    t0, t1 = jax.lax.optimization_barrier((t0, t1))
    saveat = diffrax.SaveAt(subs=[
        diffrax.SubSaveAt(ts=jnp.atleast_1d(t1) if ts is None else ts),
        diffrax.SubSaveAt(t1=True),
    ])
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(vector_field),
        solver,
        t0,
        t1,
        dt0,
        y0,
        args=(mech, baumgarte),
        saveat=saveat,
        stepsize_controller=stepsize_controller,
        max_steps=max_steps,
        adjoint=adjoint,
        throw=False,
    )
    stats = sol.stats
    (saved_ts, final_t), (saved_ys, final_y) = sol.ts, sol.ys
    return Trajectory(
        ts=saved_ts,
        ys=saved_ys,
        t_final=final_t[-1],
        y_final=final_y[-1],
        result=sol.result,
        num_steps=stats["num_steps"],
        num_accepted_steps=stats["num_accepted_steps"],
        num_rejected_steps=stats["num_rejected_steps"],
    )
