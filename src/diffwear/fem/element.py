"""The 9-node quadratic (Q9, biquadratic Lagrange) plane element.

Shape functions N_k(xi, eta) = l_{i_xi}(xi) l_{i_eta}(eta), k = 3 i_eta + i_xi,
with the 1-D quadratic Lagrange polynomials on the nodes -1, 0, 1:

    l_0 = xi (xi - 1) / 2,   l_1 = 1 - xi^2,   l_2 = xi (xi + 1) / 2.

Stiffness K_e = integral of B^T D B over the element (unit thickness: plane
strain, forces per metre of axial length), integrated with the 3 x 3
Gauss-Legendre rule: exact for the polynomial integrand of a parallelogram
element (degree 4 in each of xi, eta) and the "full" rule of Q9 (Bathe,
*Finite Element Procedures*, 1996, Table 5.9); reduced 2 x 2 integration would
leave spurious zero-energy modes.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

#: 3-point Gauss-Legendre rule on [-1, 1]: points 0, +-sqrt(3/5), weights 8/9, 5/9.
GAUSS3_POINTS = np.array([-np.sqrt(0.6), 0.0, np.sqrt(0.6)])
GAUSS3_WEIGHTS = np.array([5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0])


def lagrange2(s):
    """(l_0, l_1, l_2)(s) and their derivatives, each stacked on the last axis."""
    s = jnp.asarray(s, dtype=float)
    val = jnp.stack([0.5 * s * (s - 1.0), 1.0 - s * s, 0.5 * s * (s + 1.0)], axis=-1)
    der = jnp.stack([s - 0.5, -2.0 * s, s + 0.5], axis=-1)
    return val, der


def shape(xi, eta):
    """N (9,), dN/dxi (9,), dN/deta (9,) at (xi, eta), node order k = 3 i_eta + i_xi."""
    lx, dlx = lagrange2(xi)
    le, dle = lagrange2(eta)
    n = (le[:, None] * lx[None, :]).reshape(9)
    dxi = (le[:, None] * dlx[None, :]).reshape(9)
    deta = (dle[:, None] * lx[None, :]).reshape(9)
    return n, dxi, deta


def plane_strain_matrix(youngs_modulus, poisson_ratio) -> Float[Array, "3 3"]:
    """D with sigma = D eps, eps = (eps_xx, eps_yy, gamma_xy), plane strain:
    E / ((1 + nu)(1 - 2 nu)) [[1 - nu, nu, 0], [nu, 1 - nu, 0], [0, 0, (1 - 2 nu) / 2]]."""
    e, nu = jnp.asarray(youngs_modulus, dtype=float), jnp.asarray(poisson_ratio, dtype=float)
    c = e / ((1.0 + nu) * (1.0 - 2.0 * nu))
    z = jnp.zeros_like(c)
    return c * jnp.array([[1.0 - nu, nu, z], [nu, 1.0 - nu, z], [z, z, 0.5 - nu]])


def strain_matrix(xe: Float[Array, "9 2"], xi, eta):
    """B (3, 18) on the dofs (u_0x, u_0y, u_1x, ...) and det J at (xi, eta)."""
    _, dxi, deta = shape(xi, eta)
    dnat = jnp.stack([dxi, deta])  # (2, 9)
    jac = dnat @ xe  # rows: d(x, y)/dxi, d(x, y)/deta
    det = jac[0, 0] * jac[1, 1] - jac[0, 1] * jac[1, 0]
    inv = jnp.array([[jac[1, 1], -jac[0, 1]], [-jac[1, 0], jac[0, 0]]]) / det
    dx = inv @ dnat  # (2, 9): dN/dx, dN/dy
    z = jnp.zeros(9)
    b = jnp.stack([
        jnp.stack([dx[0], z], axis=-1).reshape(18),
        jnp.stack([z, dx[1]], axis=-1).reshape(18),
        jnp.stack([dx[1], dx[0]], axis=-1).reshape(18),
    ])
    return b, det


def _gauss_grid():
    xi, eta = np.meshgrid(GAUSS3_POINTS, GAUSS3_POINTS, indexing="ij")
    w = np.outer(GAUSS3_WEIGHTS, GAUSS3_WEIGHTS)
    return xi.ravel(), eta.ravel(), w.ravel()


def element_stiffness(xe: Float[Array, "9 2"], d: Float[Array, "3 3"]) -> Float[Array, "18 18"]:
    """K_e = sum_g w_g det J_g B_g^T D B_g (3 x 3 Gauss), unit thickness [N/m per m]."""
    xi, eta, w = _gauss_grid()
    b, det = jax.vmap(strain_matrix, in_axes=(None, 0, 0))(xe, xi, eta)
    return jnp.einsum("g,g,gia,ij,gjb->ab", w, det, b, d, b)


def min_jacobian(xe: Float[Array, "9 2"]) -> Float[Array, ""]:
    """Smallest det J over the Gauss points (<= 0: an inverted element)."""
    xi, eta, _ = _gauss_grid()
    _, det = jax.vmap(strain_matrix, in_axes=(None, 0, 0))(xe, xi, eta)
    return jnp.min(det)
