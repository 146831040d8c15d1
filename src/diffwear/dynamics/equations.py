"""Equations of motion: the Baumgarte-stabilised index-1 DAE as an ODE.

    [ M      Phi_q^T ] [ qdd    ]   [ Q_A                                 ]
    [ Phi_q  0       ] [ lambda ] = [ gamma - 2 alpha Phidot - beta^2 Phi ]

(thesis Eq. 2-20 with Baumgarte's stabilisation).  M is diagonal, so the
system is solved by its Schur complement S = Phi_q M^-1 Phi_q^T (m x m):

    lambda = S^-1 (Phi_q M^-1 Q_A - rhs),    qdd = M^-1 (Q_A - Phi_q^T lambda).

Sign convention: the generalised constraint force on the bodies is
-Phi_q^T lambda (see `reactions.py`).
"""

from __future__ import annotations

from functools import partial

import equinox as eqx
import jax
import jax.numpy as jnp
from jax.custom_derivatives import SymbolicZero
from jaxtyping import Array, Float

from .._checks import check_positive
from ..mechanism import Mechanism
from .fused import t_times, times


class Baumgarte(eqx.Module):
    """Baumgarte stabilisation gains alpha [1/s] and beta [1/s].

    Default alpha = beta = 250 1/s: thesis Chapters 2-3 (values of 0, 5 and 100 shown in Fig. 2-8).
    alpha = beta = 0 gives the unstabilised index-1 DAE (drift grows).
    """

    alpha: Float[Array, ""]
    beta: Float[Array, ""]

    def __init__(self, alpha=250.0, beta=250.0):
        check_positive("Baumgarte alpha [1/s]", alpha, allow_zero=True)
        check_positive("Baumgarte beta [1/s]", beta, allow_zero=True)
        self.alpha = jnp.asarray(alpha, dtype=float)
        self.beta = jnp.asarray(beta, dtype=float)


def accelerations(
    mech: Mechanism, q, qd, aux, t, baumgarte: Baumgarte
) -> tuple[Float[Array, " n"], Float[Array, " m"], Float[Array, " a"]]:
    """(qdd, lambda, d aux/dt) at one state."""
    t = jnp.asarray(t, dtype=q.dtype)
    force, daux = mech.applied_forces(q, qd, aux, t)
    minv = 1.0 / mech.mass_diagonal()
    if mech.n_constraints == 0:
        return minv * force, jnp.zeros(0, dtype=q.dtype), daux
    jac = mech.phi_q(q, t)
    rhs = (
        mech.gamma(q, qd, t)
        - 2.0 * baumgarte.alpha * mech.phi_dot(q, qd, t)
        - baumgarte.beta**2 * mech.phi(q, t)
    )
    qdd, lam = schur_solve(jac, minv, force, rhs)
    return qdd, lam, daux


def _schur_solve(jac, minv, force, rhs):
    # the small products (m, n <= a few dozen) as elementwise sums (`fused`)
    jm = jac * minv
    factor = jax.scipy.linalg.cho_factor(jnp.sum(jm[:, None, :] * jac[None, :, :], axis=-1))
    lam = jax.scipy.linalg.cho_solve(factor, times(jm, force) - rhs)
    qdd = minv * (force - t_times(jac, lam))
    return qdd, lam, factor


@jax.custom_jvp
def schur_solve(jac, minv, force, rhs):
    """(qdd, lambda) of the saddle-point system above by its Schur complement
    S = J M^-1 J^T (J = Phi_q, m x n; ``minv`` = diag(M^-1); Cholesky of S)."""
    qdd, lam, _ = _schur_solve(jac, minv, force, rhs)
    return qdd, lam


def _tangent(t, like):
    return jnp.zeros_like(like) if isinstance(t, SymbolicZero) else t


@partial(schur_solve.defjvp, symbolic_zeros=True)
def _schur_solve_jvp(primals, tangents):
    # Differentiate  S lam = J M^-1 f - r,  qdd = M^-1 (f - J^T lam),  S = J M^-1 J^T.
    # With g = f - J^T lam (so qdd = M^-1 g) the terms of dS lam that pair with
    # those of d(J M^-1 f) collect into
    #     S dlam = dJ qdd + J a - dr,       a = dM^-1 g + M^-1 (df - dJ^T lam),
    #     dqdd   = dM^-1 g + M^-1 (df - dJ^T lam - J^T dlam) = a - M^-1 J^T dlam.
    # One solve with the primal's Cholesky factor per tangent (the back
    # substitution only); autodiff instead differentiates the factorisation
    # itself (a Cholesky JVP with triangular solves of m x m matrices per tangent),
    # which was ~2/3 of the cost of a right-hand side's forward-mode tangent.
    jac, minv, force, rhs = primals
    djac, dminv, dforce, drhs = (_tangent(t, p) for t, p in zip(tangents, primals))
    qdd, lam, factor = _schur_solve(jac, minv, force, rhs)
    g = force - t_times(jac, lam)
    a = dminv * g + minv * (dforce - t_times(djac, lam))
    dlam = jax.scipy.linalg.cho_solve(factor, times(djac, qdd) + times(jac, a) - drhs)
    dqdd = a - minv * t_times(jac, dlam)
    return (qdd, lam), (dqdd, dlam)


def vector_field(t, y, args) -> Float[Array, " s"]:
    """dy/dt for y = [q, qd, aux]; ``args = (mechanism, baumgarte)`` (diffrax signature)."""
    mech, baumgarte = args
    q, qd, aux = mech.split(y)
    qdd, _, daux = accelerations(mech, q, qd, aux, t, baumgarte)
    return jnp.concatenate([qd, qdd, daux])
