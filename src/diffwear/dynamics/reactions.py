"""Constraint reactions from the Lagrange multipliers (thesis Eq. 5-2).

The generalised constraint force on the bodies is -Phi_q^T lambda.  Restricted to
one constraint's rows and one body's columns it is the wrench that the rest of
the system exerts on that body through that constraint: (Fx, Fy) in the global
frame [N] and the moment about the body's COM [N m].
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..errors import InputError
from ..mechanism import GROUND, Mechanism
from .equations import Baumgarte, accelerations


def reaction_wrench(mech: Mechanism, q, lam, t, constraint: str, on_body: str) -> Float[Array, "3"]:
    """Wrench (Fx, Fy, M_com) that ``constraint`` applies to body ``on_body``."""
    if on_body == GROUND or on_body not in mech.index:
        raise InputError(f"on_body must be one of {list(mech.body_names)}, got {on_body!r}")
    rows = mech.constraint_rows(constraint)
    i = mech.index[on_body]
    jac = mech.phi_q(q, jnp.asarray(t, dtype=q.dtype))[rows, 3 * i : 3 * i + 3]
    return -jac.T @ lam[rows]


def driver_torque(mech: Mechanism, q, lam, t, driver: str) -> Float[Array, ""]:
    """Torque [N m] the driver applies to its body (positive counter-clockwise)."""
    body = mech.element(driver).body
    return reaction_wrench(mech, q, lam, t, driver, body)[2]


def along_trajectory(mech: Mechanism, ts, ys, baumgarte: Baumgarte | None = None):
    """(qdd, lambda, d aux/dt) at every saved state (vmapped `accelerations`)."""
    baumgarte = Baumgarte() if baumgarte is None else baumgarte

    def one(t, y):
        q, qd, aux = mech.split(y)
        return accelerations(mech, q, qd, aux, t, baumgarte)

    return jax.vmap(one)(ts, ys)
