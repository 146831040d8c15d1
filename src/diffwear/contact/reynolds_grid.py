"""The finite-volume grid of the finite-length film's Reynolds equation on
the bushing's (theta, z) surface, shared by its two cavitation conditions
(`finite_bearing`: Reynolds; `mass_conserving`): the node spacing crowded at
the minimum film, the grid a film needs at an eccentricity ratio, and the
operator K of the discrete equation K P = rhs (finite_bearing's module notes
give the discretisation)."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax

# Default grid: 96 nodes round the bushing, 12 along the half length; with the
# clustering below it reproduces Raimondi & Boyd's S and attitude angle to
# 1.5 % over L/D = 1/4 .. 1, eps = 0.2 .. 0.9 (tests/test_finite_bearing.py;
# 192 x 24 moves them by < 0.3 %).
N_THETA, N_Z = 96, 12
# Node crowding at the minimum film: psi = s - a sin s with a = CLUSTERING eps
# (the finest spacing (1 - a) 2 pi / n_theta).  0.9: the finest spacing stays a
# tenth of the uniform one, so J = dpsi/ds >= 0.1 and the cells stay regular.
CLUSTERING = 0.9
# Nodes the grid must have across the minimum film's half width
# sqrt(2 (1 - eps) / eps) (where the film is twice its minimum): 8.  At 8 the
# default grid's load is within 1 % of a twice-as-fine grid's at eps = 0.995.
NODES_PER_FILM_WIDTH = 8.0
# Most active-set passes (each a linear solve); the default grid needs <= 16,
# a 192-node one <= 28.
MAX_PASSES = 64


def _resolved_eccentricity(n_theta: int) -> float:
    """The largest eps whose minimum film the grid resolves with
    `NODES_PER_FILM_WIDTH` nodes: sqrt(2 (1 - eps) / eps) = k (1 - 0.9 eps)
    2 pi / n_theta, solved for eps (bisection; the left side falls, the right
    side rises with eps)."""
    def excess(eps):
        return (math.sqrt(2.0 * (1.0 - eps) / eps)
                - NODES_PER_FILM_WIDTH * (1.0 - CLUSTERING * eps) * 2.0 * math.pi / n_theta)

    lo, hi = 1e-6, 1.0 - 1e-15
    if excess(hi) > 0.0:
        return hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) > 0.0 else (lo, mid)
    return lo


def nodes_for(eccentricity_ratio: float) -> int:
    """The fewest grid nodes round the bushing (even, at most 4096) that
    resolve the minimum film at ``eccentricity_ratio`` (`NODES_PER_FILM_WIDTH`
    nodes across it)."""
    need = 16
    while _resolved_eccentricity(need) < eccentricity_ratio and need < 4096:
        need += 2
    return need


def _grid(eps, n_theta):
    """Nodes psi_i, J_i = dpsi/ds and the faces' psi and J (at s + ds/2)."""
    a = CLUSTERING * eps
    ds = 2.0 * jnp.pi / n_theta
    s = ds * jnp.arange(n_theta)
    face = s + 0.5 * ds
    return (s - a * jnp.sin(s), 1.0 - a * jnp.cos(s),
            face - a * jnp.sin(face), 1.0 - a * jnp.cos(face), ds)


class _Operator(eqx.Module):
    """The finite-volume Reynolds operator K (module notes), by its stencil:
    ``diag`` (n_z, n_theta), ``east`` (n_z, n_theta) the coupling of node i to
    i + 1 (periodic), ``north`` (n_theta,) the coupling of row j to j + 1
    (the same for every row), and the nodes' psi, J and volumes."""

    diag: jax.Array
    east: jax.Array
    north: jax.Array
    psi: jax.Array
    volume: jax.Array  # ds dzeta_j J_i: the cell's area in (psi, zeta)
    weight: jax.Array  # ds dzeta_j: the cell's area in (s, zeta)


def _operator(eps, half_length, n_theta, n_z) -> _Operator:
    psi, jac, psi_f, jac_f, ds = _grid(eps, n_theta)
    h3 = (1.0 - eps * jnp.cos(psi)) ** 3
    east_flux = (1.0 - eps * jnp.cos(psi_f)) ** 3 / jac_f  # H^3 / J at face i + 1/2
    dz = half_length / n_z
    # row 0 lies on the symmetry plane: half a cell, one neighbour row
    dzeta = jnp.full(n_z, dz).at[0].set(0.5 * dz)
    rows = jnp.full(n_z, 2.0).at[0].set(1.0)
    axial = ds * jac * h3 / dz
    diag = (dzeta[:, None] / ds * (east_flux + jnp.roll(east_flux, 1))[None, :]
            + rows[:, None] * axial[None, :])
    weight = ds * dzeta[:, None] * jnp.ones(n_theta)[None, :]
    return _Operator(diag=diag, east=-dzeta[:, None] / ds * east_flux[None, :], north=-axial,
                     psi=psi, volume=weight * jac[None, :], weight=weight)


def _apply(op: _Operator, p):
    """K p for p of shape (n_z, n_theta) (P = 0 beyond the last row)."""
    out = (op.diag * p + op.east * jnp.roll(p, -1, axis=1)
           + jnp.roll(op.east, 1, axis=1) * jnp.roll(p, 1, axis=1))
    above = jnp.concatenate([p[1:], jnp.zeros_like(p[:1])], axis=0)
    below = jnp.concatenate([jnp.zeros_like(p[:1]), p[:-1]], axis=0)
    return out + op.north[None, :] * (above + below)


def block_tridiagonal_solve(blocks, rhs, lower, upper):
    """u (n_z, n) solving the block-tridiagonal system along zeta with the
    dense diagonal ``blocks`` (n_z, n, n), the diagonal couplings ``lower``
    (n_z - 1, n: row j + 1 on u_j) and ``upper`` (n_z - 1, n: row j on
    u_{j+1}) and right-hand side ``rhs`` (n_z, n), by block elimination
    (block Thomas: forward elimination, back substitution; one n x n inverse
    per row)."""
    def eliminate(carry, row):
        inverse, y = carry
        d, r, lo, up = row
        reduced = d - lo[:, None] * inverse * up[None, :]
        y_new = r - lo * (inverse @ y)
        inverse_new = jnp.linalg.inv(reduced)
        return (inverse_new, y_new), (inverse_new, y_new)

    first = jnp.linalg.inv(blocks[0])
    _, (inverses, ys) = lax.scan(eliminate, (first, rhs[0]),
                                 (blocks[1:], rhs[1:], lower, upper))
    inverses = jnp.concatenate([first[None], inverses], axis=0)
    ys = jnp.concatenate([rhs[:1], ys], axis=0)

    def substitute(u_next, row):
        inverse, y, up = row
        u = inverse @ (y - up * u_next)
        return u, u

    last = inverses[-1] @ ys[-1]
    _, us = lax.scan(substitute, last, (inverses[:-1], ys[:-1], upper), reverse=True)
    return jnp.concatenate([us, last[None]], axis=0)
