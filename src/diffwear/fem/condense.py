"""Compliance of the ring's inner surface: radial displacement per radial nodal force.

Result: ``C`` (n_theta x n_theta, symmetric positive definite) with

    u_r(theta_i) = sum_j C_ij f_j,

u_r the radial displacement of inner-surface node i [m] and f_j the radial
*nodal force* on inner-surface node j [N per metre of axial length], positive
outward (the pin pressing on the bushing); the outer ring r = b is held fixed,
every other node is free, and the tangential nodal forces are zero
(frictionless contact).  C condenses nodal forces, not pressures: a pressure
p(s) [Pa] on the inner surface enters through its consistent nodal loads
f = P p (`pressure_load_matrix`), or through the row sums w = P 1 (`tributary_lengths`)
for the lumped, node-by-node loads f_j = w_j p_j that `diffwear.fem.contact` uses.

Method.  C = N^T S^-1 N with S the Schur complement of the stiffness onto the
inner surface's 2 n_theta dofs and N the radial unit vectors.  S is computed
without forming the global stiffness: the wall is eliminated from the outside
in, one element layer at a time.  Layer k couples node rings 2k, 2k+1 and
2k+2 only; adding the condensed stiffness of everything outside ring 2k+2 to
that ring's block and eliminating rings 2k+1 and 2k+2 gives the condensed
stiffness of ring 2k (block Gaussian elimination in ring order: the same S as
the dense Schur complement, which tests/test_fem.py checks to 1e-10).  The
centre node of each Q9 element belongs to that element alone, so it is
eliminated element by element first (a 2 x 2 solve each); a layer step then
eliminates the ring 2k+1 nodes on the element edges (n_theta dofs) and ring
2k+2 (2 n_theta dofs): a Cholesky factorisation of size 3 n_theta and one
triangular solve, so the cost is ~n_r (3 n_theta)^3 / 3 + ... instead of
(2 (2 n_r + 1) n_theta)^3 / 3 for the dense factorisation: ~50x less work
at n_r = 4, growing as n_r^2.

Its cost (the FEM wear route's 180 x 4 ring: tens of milliseconds) is on the
docs' FEM page; on a loaded machine it depends on the threads of the
linear-algebra library (docs/notes/cpu-kernels.md).
"""

from __future__ import annotations

from typing import Protocol

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import concrete
from ..errors import InputError
from .element import (
    GAUSS3_POINTS,
    GAUSS3_WEIGHTS,
    element_stiffness,
    lagrange2,
    plane_strain_matrix,
)
from .mesh import RingMesh


class AnnularMesh(Protocol):
    """What the condensation reads of a mesh: a `RingMesh` (the bushing) or
    a `diffwear.fem.pin.PinMesh` (the pin), surface at ring 0."""

    nodes: Float[Array, "n_nodes 2"]
    elements: Array
    n_theta: int
    n_r: int

    @property
    def theta(self) -> Float[Array, " n_theta"]: ...


# Q9 local node at the element centre (local node 3 i_eta + i_xi, i_eta = i_xi = 1):
# on ring 2k + 1, coupled to its own element's nodes only.
CENTRE = 4
_EDGE_NODES = np.array([i for i in range(9) if i != CENTRE])
_EDGE_DOFS = (2 * _EDGE_NODES[:, None] + np.arange(2)).ravel()
_CENTRE_DOFS = 2 * CENTRE + np.arange(2)


def _condense_centre(ke: Float[Array, "18 18"]) -> Float[Array, "16 16"]:
    """An element's stiffness on its 8 edge nodes, its centre node eliminated."""
    kcc = ke[_CENTRE_DOFS[:, None], _CENTRE_DOFS[None, :]]
    kec = ke[_EDGE_DOFS[:, None], _CENTRE_DOFS[None, :]]
    return ke[_EDGE_DOFS[:, None], _EDGE_DOFS[None, :]] - kec @ jnp.linalg.solve(kcc, kec.T)


def _layer_numbering(n: int) -> np.ndarray:
    """Layer-relative node -> index in a layer's reduced numbering: ring 2k
    (n nodes), then the nodes of ring 2k+1 shared by two elements (even angle
    indices), then ring 2k+2; the element centres (odd angle indices of ring
    2k+1, in the numbering of `RingMesh` and `PinMesh` alike) map to -1."""
    index = -np.ones(3 * n, dtype=int)
    index[:n] = np.arange(n)
    index[n:2 * n:2] = n + np.arange(n // 2)
    index[2 * n:] = n + n // 2 + np.arange(n)
    return index


def _layer_stiffness(mesh: AnnularMesh, youngs_modulus, poisson_ratio) -> Float[Array, "n_r m m"]:
    """Stiffness of each element layer on its own 3 node rings, the element
    centres eliminated (5 n_theta dofs: `_layer_numbering`)."""
    n, per_layer = mesh.n_theta, mesh.n_theta // 2
    d = plane_strain_matrix(youngs_modulus, poisson_ratio)
    ke = jax.vmap(element_stiffness, in_axes=(0, None))(mesh.nodes[mesh.elements], d)
    ke = jax.vmap(_condense_centre)(ke).reshape(mesh.n_r, per_layer, 16, 16)
    number = _layer_numbering(n)
    layer0 = mesh.elements[:per_layer]  # layer 0 = every layer, relative to ring 2k
    centres = concrete(layer0[:, CENTRE])
    if centres is not None and not np.all(number[np.asarray(centres).astype(int)] < 0):
        raise InputError("condensation: the mesh's element centres are not the odd-angle "
                         "nodes of its middle rings (the numbering of RingMesh / PinMesh)")
    local = jnp.asarray(number)[layer0[:, _EDGE_NODES]]  # (per_layer, 8)
    idx = (2 * local[..., None] + jnp.arange(2)).reshape(per_layer, 16)
    m = 2 * (int(number.max()) + 1)

    def assemble(ke_layer):
        k = jnp.zeros((m, m))
        return k.at[idx[:, :, None], idx[:, None, :]].add(ke_layer)

    return jax.vmap(assemble)(ke)


def _schur(k: Float[Array, "m m"], keep: int) -> Float[Array, "keep keep"]:
    """K_aa - K_ab K_bb^-1 K_ba for the first ``keep`` dofs a (K_bb is SPD), as
    K_aa - Y^T Y with Y = L^-1 K_ba, K_bb = L L^T: one triangular solve, not
    two and a product (3/5 of the work of cho_solve and K_ab @ solution)."""
    y = jax.scipy.linalg.solve_triangular(jnp.linalg.cholesky(k[keep:, keep:]),
                                          k[keep:, :keep], lower=True)
    s = k[:keep, :keep] - y.T @ y
    return 0.5 * (s + s.T)


def inner_stiffness(mesh: AnnularMesh, youngs_modulus, poisson_ratio) -> Float[Array, "m m"]:
    """S: condensed stiffness of the inner-surface dofs (2 n_theta), outer ring fixed."""
    ring = 2 * mesh.n_theta  # dofs per node ring
    layers = _layer_stiffness(mesh, youngs_modulus, poisson_ratio)
    outer = layers.shape[1] - ring  # the layer's dofs before ring 2k+2
    s = None
    for k in reversed(range(mesh.n_r)):
        lk = layers[k]
        if s is None:  # outermost layer: ring 2 n_r is held, drop its dofs
            lk = lk[:outer, :outer]
        else:
            lk = lk.at[outer:, outer:].add(s)
        s = _schur(lk, ring)
    assert s is not None  # a mesh has at least one layer (n_r >= 1, checked when built)
    return s


def radial_directions(mesh: AnnularMesh) -> Float[Array, "m n"]:
    """N (2 n_theta, n_theta): column j is the radial unit vector of inner node j."""
    n = mesh.n_theta
    th = mesh.theta
    j = np.arange(n)
    return jnp.zeros((2 * n, n)).at[2 * j, j].set(jnp.cos(th)).at[2 * j + 1, j].set(jnp.sin(th))


def inner_compliance(mesh: AnnularMesh, youngs_modulus, poisson_ratio) -> Float[Array, "n n"]:
    """C [m per N/m]: u_r(inner nodes) = C f_r (radial nodal forces, outward positive)."""
    s = inner_stiffness(mesh, youngs_modulus, poisson_ratio)
    # C = N^T S^-1 N = Y^T Y with Y = L^-1 N, S = L L^T
    y = jax.scipy.linalg.solve_triangular(jnp.linalg.cholesky(s), radial_directions(mesh),
                                          lower=True)
    c = y.T @ y
    return 0.5 * (c + c.T)


def pressure_load_matrix(mesh: RingMesh) -> Float[Array, "n n"]:
    """P [m]: radial consistent nodal loads f = P p [N/m] of an inner-surface
    pressure p(s) = sum_j N_j(s) p_j [Pa], p_j at the inner nodes.

    P_ij = integral over the inner surface of N_i N_j (n . u_i) ds: the pressure
    acts along the surface normal n (outward, away from the pin; on a worn
    profile n includes the slope of the depth), and the condensed problem keeps
    the radial component of each nodal load (u_i = radial unit vector of node i;
    for a uniform pressure on a round ring the tangential components cancel
    exactly by symmetry).  Quadratic edges, 3-point Gauss per edge, on the
    isoparametric curve (n ds = (dy/deta, -dx/deta) deta for the counter-
    clockwise surface).  Using the normal rather than the radius matters: with
    16 elements around, radial loads with Simpson weights leave a 1.5e-3
    corner/mid-node ripple in the Lame displacement, the normal loads 4e-5."""
    n = mesh.n_theta
    edges = (np.arange(n // 2)[:, None] * 2 + np.arange(3)[None, :]) % n  # (n/2, 3)
    val, der = lagrange2(GAUSS3_POINTS)  # (3 Gauss points, 3 edge nodes)
    xe = mesh.nodes[:n][edges]  # (n/2, 3, 2)
    tangent = jnp.einsum("gk,ekd->egd", der, xe)  # dx/deta
    normal = jnp.stack([tangent[..., 1], -tangent[..., 0]], axis=-1)  # n ds / deta
    radial = jnp.stack([jnp.cos(mesh.theta), jnp.sin(mesh.theta)], axis=-1)[edges]
    pe = jnp.einsum("g,gi,gj,egd,eid->eij", GAUSS3_WEIGHTS, val, val, normal, radial)
    return jnp.zeros((n, n)).at[edges[:, :, None], edges[:, None, :]].add(pe)


def tributary_lengths(mesh: RingMesh) -> Float[Array, " n"]:
    """w = P 1 [m]: the radial load of a uniform pressure p on node j is w_j p
    (about 2/6 (corner) and 4/6 (mid-edge) of an edge's arc: Simpson weights)."""
    return pressure_load_matrix(mesh).sum(axis=1)
