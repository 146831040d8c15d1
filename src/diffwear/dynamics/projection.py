"""Post-stabilisation: each step's end state projected back onto the constraints.

Baumgarte's terms (thesis Eq. 2-20) hold the drift of Phi and Phi_dot down
by making it decay at the rates alpha and beta.  Those rates are modes of the
ODE: integration errors excite them at the tolerance's level, and an error
controller must then resolve them: at the thesis's alpha = beta = 250 1/s
the ideal slider-crank (Table 2-1) takes ~30x the steps it takes with
alpha = beta = 0 (docs/notes/post-stabilisation.md).  Without the terms,
though, the drift grows.

Post-stabilisation (Ascher, Chin, Petzold and Reich, "Stabilization of
constrained mechanical systems with DAEs and invariant manifolds",
Mech. Struct. Mach. 23 (1995) 135-158) integrates the unstabilised index-1
equations (``Baumgarte(0, 0)``) and, after every step, removes the step's
drift by one mass-weighted Gauss-Newton step onto Phi = 0 and one onto
Phi_dot = 0:

    q  <- q  - M^-1 Phi_q^T S^-1 Phi(q, t),
    qd <- qd - M^-1 Phi_q^T S^-1 (Phi_q qd + Phi_t),    S = Phi_q M^-1 Phi_q^T,

the second with Phi_q at the corrected q (exact, the velocity constraint is
linear in qd).  The drift of one step is of the order of its local error, so
one position step leaves a remainder of that error squared.  The solution is
the same constrained motion as Baumgarte's, without its fast modes.

`ConstraintProjection` wraps a diffrax solver as diffrax's `HalfSolver` does:
the wrapped solver's step, error estimate and dense output (so saved times
between steps are the wrapped interpolant, off the constraints by at most a
step's local error), then the projection.  An FSAL solver (Tsit5) starts its
next step from the slope at the unprojected end, a difference of the same
order as the projection; it is not re-evaluated, which gained nothing
(docs/notes/post-stabilisation.md).
"""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax.numpy as jnp

from ..errors import InputError
from ..mechanism import Mechanism
from .kinematics import _projection


def project_to_constraints(mech: Mechanism, y, t):
    """y = [q, qd, aux] moved onto Phi(q, t) = 0 and Phi_dot(q, qd, t) = 0 by
    one mass-weighted Gauss-Newton step each (module notes); aux unchanged."""
    if mech.n_constraints == 0:
        return y
    q, qd, aux = mech.split(y)
    t = jnp.asarray(t, dtype=q.dtype)
    q = q + _projection(mech, q, t, jnp.zeros_like(q), -mech.phi(q, t))
    qd = _projection(mech, q, t, qd, -mech.phi_t(q, t))
    return mech.join(q, qd, aux)


class ConstraintProjection(diffrax.AbstractAdaptiveSolver, diffrax.AbstractWrappedSolver):
    """Post-stabilisation (module notes): ``solver``'s step, then the end state
    projected onto the mechanism's constraints.

    For `diffwear.dynamics.simulate`, whose vector field's ``args`` start
    with the mechanism.  Pair it with ``baumgarte=Baumgarte(0.0, 0.0)``: the
    projection replaces the Baumgarte terms and their fast modes.
    """

    solver: diffrax.AbstractAdaptiveSolver  # type: ignore[misc]  # as diffrax.HalfSolver declares it

    def __check_init__(self):
        if not isinstance(self.solver, diffrax.AbstractAdaptiveSolver):
            raise InputError("ConstraintProjection wraps a solver with an error estimate "
                             f"(an adaptive diffrax solver), got {type(self.solver).__name__}")

    @property
    def scan_kind(self):
        # diffrax's forward-mode adjoint sets a Runge-Kutta solver's stage
        # scan (``eqx.tree_at(lambda s: s.scan_kind, ...)``); this reaches
        # the wrapped solver's field, so the same works through the wrapper.
        return self.solver.scan_kind  # pyright: ignore

    @property
    def term_structure(self):
        return self.solver.term_structure

    @property
    def interpolation_cls(self):  # pyright: ignore
        return self.solver.interpolation_cls

    def order(self, terms):
        return self.solver.order(terms)

    def error_order(self, terms):
        return self.solver.error_order(terms)

    def init(self, terms, t0, t1, y0, args):
        return self.solver.init(terms, t0, t1, y0, args)

    def func(self, terms, t0, y0, args):
        return self.solver.func(terms, t0, y0, args)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        y1, y_error, dense_info, solver_state, result = self.solver.step(
            terms, t0, t1, y0, args, solver_state, made_jump)
        return project_to_constraints(args[0], y1, t1), y_error, dense_info, solver_state, result


def stepping_solver(solver):
    """The solver that takes the steps: the one inside a `ConstraintProjection`."""
    return solver.solver if isinstance(solver, ConstraintProjection) else solver


def replace_inner(solver, fn):
    """``solver`` with its `stepping_solver` replaced by ``fn`` of it (so that
    `simulate` configures the solver that steps)."""
    if isinstance(solver, ConstraintProjection):
        return eqx.tree_at(lambda s: s.solver, solver, fn(solver.solver))
    return fn(solver)
