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

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive
from ..mechanism import Mechanism


class Baumgarte(eqx.Module):
    """Baumgarte stabilisation gains alpha [1/s] and beta [1/s].

    Default alpha = beta = 250 1/s: thesis Chapters 2-3 (digest section 1).
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
    jm = jac * minv
    lam = jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(jm @ jac.T), jm @ force - rhs)
    qdd = minv * (force - jac.T @ lam)
    return qdd, lam, daux


def vector_field(t, y, args) -> Float[Array, " s"]:
    """dy/dt for y = [q, qd, aux]; ``args = (mechanism, baumgarte)`` (diffrax signature)."""
    mech, baumgarte = args
    q, qd, aux = mech.split(y)
    qdd, _, daux = accelerations(mech, q, qd, aux, t, baumgarte)
    return jnp.concatenate([qd, qdd, daux])
