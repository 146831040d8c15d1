"""Plane-strain linear elasticity on a Q9 mesh: dense stiffness and solves.

The global stiffness K (2 n_nodes square, dofs ``2 * node + {0: x, 1: y}``) is
assembled densely from `element.element_stiffness`.  Dense storage is meant for
small meshes (tests, checks: the patch test, the cross-check of the ring-by-
ring condensation in `diffwear.fem.condense`, which never forms the global K).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .element import GAUSS3_POINTS, element_stiffness, plane_strain_matrix, strain_matrix


def element_dofs(elements: Int[Array, "n_el 9"]) -> Int[Array, "n_el 18"]:
    """Global dof indices of each element, in the element's dof order."""
    return (2 * elements[..., None] + jnp.arange(2)).reshape(elements.shape[0], 18)


def assemble(nodes: Float[Array, "n 2"], elements: Int[Array, "n_el 9"],
             youngs_modulus, poisson_ratio, n_nodes: int | None = None
             ) -> Float[Array, "2n 2n"]:
    """Dense global stiffness [N/m per metre of axial length] (plane strain)."""
    n_nodes = nodes.shape[0] if n_nodes is None else n_nodes
    d = plane_strain_matrix(youngs_modulus, poisson_ratio)
    ke = jax.vmap(element_stiffness, in_axes=(0, None))(nodes[elements], d)
    idx = element_dofs(elements)
    k = jnp.zeros((2 * n_nodes, 2 * n_nodes))
    return k.at[idx[:, :, None], idx[:, None, :]].add(ke)


def solve_prescribed(k: Float[Array, "n n"], fixed, values, load=None) -> Float[Array, " n"]:
    """u with K u = load on the free dofs and u[fixed] = values (a NumPy index
    array of dofs): u_f = K_ff^-1 (load_f - K_fc values) by Cholesky (K_ff is SPD)."""
    n = k.shape[0]
    fixed = np.asarray(fixed)
    free = np.setdiff1d(np.arange(n), fixed)
    load = jnp.zeros(n) if load is None else load
    rhs = load[free] - k[np.ix_(free, fixed)] @ values
    u_free = jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(k[np.ix_(free, free)]), rhs)
    return jnp.zeros(n).at[free].set(u_free).at[fixed].set(values)


def stresses(nodes, elements, u, youngs_modulus, poisson_ratio) -> Float[Array, "n_el 9 3"]:
    """(sigma_xx, sigma_yy, sigma_xy) [Pa] at each element's 3 x 3 Gauss points."""
    d = plane_strain_matrix(youngs_modulus, poisson_ratio)
    xi, eta = (g.ravel() for g in np.meshgrid(GAUSS3_POINTS, GAUSS3_POINTS, indexing="ij"))
    ue = u[element_dofs(elements)]

    def one(xe, u_e):
        b, _ = jax.vmap(strain_matrix, in_axes=(None, 0, 0))(xe, xi, eta)
        return (b @ u_e) @ d.T

    return jax.vmap(one)(nodes[elements], ue)
