"""Semismooth Newton for (mixed) complementarity problems, implicitly differentiated.

A complementarity condition 0 <= a  _|_  b >= 0 (a >= 0, b >= 0, a b = 0) is
written as one equation with the Fischer-Burmeister function

    phi(a, b) = a + b - sqrt(a^2 + b^2) = 0

(Fischer, Optimization 24 (1992) 269-284), and the whole system
Phi(z) = 0 (complementarity rows plus any ordinary equations) is solved by
Newton's method on a generalized Jacobian with an Armijo line search on the
merit Psi = |Phi|^2 / 2 (De Luca, Facchinei & Kanzow, Math. Program. 75 (1996)
407-439).  Psi is continuously differentiable and, where the Newton direction
d = -J^-1 Phi exists, grad Psi . d = -|Phi|^2 < 0, so the backtracking always
finds a step; where it does not (singular or non-finite J), the step falls back
to steepest descent, d = -J^T Phi (their Algorithm 3.1).  For a linear
complementarity problem with a P-matrix (here: the SPD compliance of the ring)
every generalized Jacobian is nonsingular and the iteration converges to the
unique solution, finally quadratically.

phi is not differentiable at a = b = 0; `fischer_burmeister` guards the sqrt
with the "double where" and returns the generalized derivative (1, 1) there.

Differentiation.  The loop runs on stop-gradient inputs; the solution z* is
then passed through one Newton step that is differentiable in the parameters:

    z = z* - J(z*)^-1 Phi(z*, theta),    J held constant,

which leaves the value unchanged to the tolerance (Phi(z*) ~ 0) and gives
exactly the implicit-function-theorem derivative dz/dtheta = -J^-1
dPhi/dtheta in forward and reverse mode.  With ``polish=False`` the step's
derivative is given as a custom JVP and the step itself is not taken (a
solve that is not differentiated skips its LU).  It is valid where the solution is
strictly complementary (no node with a = b = 0), i.e. away from the instant a
node enters contact.
"""

from __future__ import annotations

import functools
from typing import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

#: Armijo sufficient-decrease constant (De Luca et al. 1996 use 1e-4).
ARMIJO = 1e-4
#: Halvings of the step before giving up on a line search: 2^-40 ~ 1e-12.
MAX_HALVINGS = 40


def fischer_burmeister(a, b):
    """a + b - sqrt(a^2 + b^2): zero iff a >= 0, b >= 0, a b = 0."""
    r2 = a * a + b * b
    zero = r2 == 0.0
    r = jnp.sqrt(jnp.where(zero, 1.0, r2))  # double where: finite gradient at 0
    return a + b - jnp.where(zero, 0.0, r)


def fischer_burmeister_partials(a, b):
    """(d phi / da, d phi / db) of `fischer_burmeister`: 1 - a / r and 1 - b / r
    (r = sqrt(a^2 + b^2)), (1, 1) at a = b = 0, as its autodiff gives."""
    r2 = a * a + b * b
    zero = r2 == 0.0
    r = jnp.sqrt(jnp.where(zero, 1.0, r2))
    return jnp.where(zero, 1.0, 1.0 - a / r), jnp.where(zero, 1.0, 1.0 - b / r)


class NewtonInfo(eqx.Module):
    """How the solve ended: ``converged`` (max |Phi| <= tol), the final max |Phi|
    and the number of Newton steps."""

    converged: Bool[Array, ""]
    residual: Float[Array, ""]
    steps: Int[Array, ""]
    tol: float = eqx.field(static=True)


def _newton(residual: Callable, z0, args, tol: float, max_steps: int, jacobian: Callable):
    def merit(z):
        r = residual(z, args)
        return 0.5 * jnp.sum(r * r), r

    def cond(state):
        z, psi, r, k = state
        return (jnp.max(jnp.abs(r)) > tol) & (k < max_steps) & jnp.isfinite(psi)

    def body(state):
        z, psi, r, k = state
        jac = jacobian(z, args)
        d = jnp.linalg.solve(jac, -r)
        grad = jac.T @ r
        ok = jnp.all(jnp.isfinite(d)) & (grad @ d < -1e-12 * jnp.sum(d * d))
        d = jnp.where(ok, d, -grad)
        slope = grad @ d

        def ls_cond(ls):
            t, psi_t, _, j = ls
            return (psi_t > psi + ARMIJO * t * slope) & (j < MAX_HALVINGS)

        def ls_body(ls):
            t, _, _, j = ls
            t = 0.5 * t
            psi_t, r_t = merit(z + t * d)
            return t, jnp.where(jnp.isfinite(psi_t), psi_t, jnp.inf), r_t, j + 1

        psi1, r1 = merit(z + d)
        t, psi_t, r_t, _ = jax.lax.while_loop(
            ls_cond, ls_body, (1.0, jnp.where(jnp.isfinite(psi1), psi1, jnp.inf), r1, 0))
        return z + t * d, psi_t, r_t, k + 1

    psi0, r0 = merit(z0)
    z, _, r, k = jax.lax.while_loop(cond, body, (z0, psi0, r0, jnp.asarray(0)))
    res = jnp.max(jnp.abs(r))
    return z, NewtonInfo(converged=res <= tol, residual=res, steps=k, tol=tol)


def _jacobian_of(residual: Callable) -> Callable:
    """(z, args) -> d residual / dz by forward-mode autodiff."""
    return lambda z, args: jax.jacfwd(lambda y: residual(y, args))(z)


def solve(residual: Callable, z0: Float[Array, " m"], args, *, tol: float = 1e-12,
          max_steps: int = 100, jacobian: Callable | None = None, polish: bool = True
          ) -> tuple[Float[Array, " m"], NewtonInfo]:
    """z with residual(z, args) = 0 (max norm <= tol), differentiable in ``args``
    (a pytree of arrays) by the implicit function theorem; see the module docstring.

    ``jacobian(z, args)``: d residual / dz in closed form (its generalized
    derivative where the residual is not differentiable); default forward-mode
    autodiff of ``residual``, one tangent per unknown.  A ``z0`` that already
    meets ``tol`` takes no Newton step (a warm start at a known solution).
    ``polish``: return z one Newton step past the loop's (the step whose
    derivative is the implicit one; one more LU); False: z as the loop left
    it (within ``tol``), with the same derivative, for many solves whose
    values need nothing finer (the FEM wear route's samples).

    Never raises: check ``info.converged`` (`diffwear.fem.contact` does, and
    raises `SolverError` outside ``jit``)."""
    jacobian = _jacobian_of(residual) if jacobian is None else jacobian
    args_c = jax.lax.stop_gradient(args)
    z, info = _newton(residual, jax.lax.stop_gradient(z0), args_c, tol, max_steps, jacobian)
    z = jax.lax.stop_gradient(z)
    if not polish:
        return _at_solution(residual, jacobian, z, args), info
    jac = jax.lax.stop_gradient(jacobian(z, args_c))
    return z - jnp.linalg.solve(jac, residual(z, args)), info


@functools.partial(jax.custom_jvp, nondiff_argnums=(0, 1))
def _at_solution(residual, jacobian, z, args):
    """The solution ``z`` of residual(z, args) = 0, with the implicit-function
    derivative dz = -J^-1 (d residual / d args) d args (J = ``jacobian`` at z,
    held): the derivative of one Newton step at z (module docstring), whose
    value is not computed (it differs from z by the solve's tolerance)."""
    del residual, jacobian, args
    return z


@_at_solution.defjvp
def _at_solution_jvp(residual, jacobian, primals, tangents):
    z, args = primals
    _, d_args = tangents
    _, d_res = jax.jvp(lambda a: residual(z, a), (args,), (d_args,))
    return z, -jnp.linalg.solve(jax.lax.stop_gradient(jacobian(z, args)), d_res)
