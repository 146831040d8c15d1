"""Mass-conserving cavitation of the finite-length film: the
Jakobsson-Floberg-Olsson (JFO) conditions in Elrod & Adams' p-theta form, as
a complementarity problem on `finite_bearing`'s grid.

**Model.**  Where the film is cavitated it is not full: the gap holds the
fraction theta <= 1 of oil (the rest vapour and air at the ambient pressure,
P = 0), and the oil there is only carried along by the surfaces (Couette
flux), with no pressure flow.  Mass conservation of the oil, in the
notation of `finite_bearing` (P = p c^2 / (6 mu R^2), H = 1 - eps cos psi,
Omega = omega - 2 gamma_dot the surfaces' speed in the frame of the line of
centres, B = eps Omega, A = 2 eps_dot):

    -div(H^3 grad P) + Omega d(theta H)/dpsi + 2 theta dH/dt = 0,

with P >= 0, theta <= 1 and P (1 - theta) = 0: in the full film (theta = 1)
it is the Reynolds equation, in the cavitated region (P = 0) the transport of
the oil's content theta H by the surfaces.  With the void fraction
r = 1 - theta it is the complementarity problem of Giacopini, Fowell, Dini &
Strozzi (J. Tribol. 132 (2010) 041702):

    P >= 0,   r >= 0,   P r = 0,   K P + q - C r = 0,

where K P + q is `finite_bearing`'s full-film Reynolds residual and C r the
Couette flux of the void (and its squeeze term 2 r dH/dt).  The free
boundary follows from it: rupture where the film can no longer hold a positive
pressure (there JFO's condition is Swift-Stieber's, P = dP/dn = 0) and
reformation where the oil convected through the cavitated region meets the
full film and must be absorbed by it (where Swift-Stieber's condition
creates oil: its full film downstream of the cavitated region carries more
oil than arrives).

**What the instantaneous problem assumes.**  The film is solved at one
instant, for the pin centre at rest or moving at a given velocity (eps_dot,
gamma_dot), not over a cycle:

- the cavitated region's content is that convected from its rupture
  boundary at this instant (the transport above with d theta/dt = 0 in the
  frame of the line of centres: the film's content has no history, its
  squeeze term is theta dH/dt);
- the supply groove (the line psi = pi, the maximum film of the steady
  bearing) is a source at the supply pressure that refills the film to full
  (theta = 1) whatever arrives at it; without it no oil comes in (the
  bearing's ends, at the ambient pressure, only let it out), the steady
  film starves and the passes do not settle, so `FiniteBearingFilm` refuses
  the mass-conserving condition without the groove;
- theta >= 0 is not imposed: with a gap opening faster than the Couette flux
  fills it the problem can return an empty cavitated film (theta = 0) or,
  out of the model's range, theta < 0 (`mass_conserving_pressure` returns
  theta so that a caller can check it).

It does not track the film content's history over a load cycle (the
transient p-theta problem, where theta at an instant depends on the past
rupture and reformation); a dynamically loaded bearing whose cavitated
region moves round the bushing needs that, and this option only removes the
Swift-Stieber condition's oil creation at each instant.

With the groove at the maximum film of a steadily loaded bearing the oil in
the cavitated region reaches the groove before any full film, so the two
conditions give the same film (tests/test_finite_bearing_cavitation.py: the
same pressurised set, load and attitude to 1e-9 over eps = 0.2-0.9 at L/D =
1); they differ where
the cavitated oil reaches a full film before the groove: without a groove,
with a groove elsewhere, and under squeeze.

**Discretisation.**  `finite_bearing`'s finite volumes; the void's Couette
flux through the face between two cells is Omega H_face r of the upstream
cell (first-order upwind, as in Giacopini et al.), so the void is conserved
cell by cell and, where r = 0, the system is `finite_bearing`'s to the last
bit.  The unknowns are scaled, r = eps v (Omega r = B v), so that nothing
divides by eps: the flux is B H_face v and the squeeze term -A cos psi eps v.

**Solve.**  With one unknown u per node, P = max(u, 0) and r = -eps min(u, 0),
the problem is the piecewise-linear equation K max(u, 0) + C min(u, 0) + q = 0
(C here in v), and Newton's method on it is an active-set method: solve with
the pressurised set fixed (P unknown there, v elsewhere), take as pressurised
the nodes where u > 0, repeat until the set stops changing.  Both K and C have
positive diagonals and non-positive off-diagonals (C's diagonal as long as
no cavitated node's gap closes faster than the Couette flow carries its
void out), so each linear system is an M-matrix and the passes settle in a
few steps (3-14 over random squeeze and wedge states) (Brugnano & Casulli, SIAM J. Sci.
Comput. 30 (2008) 463-472, for such piecewise-linear systems).  Each linear
system is block-tridiagonal along zeta like the Reynolds problem's (no longer
symmetric).  Derivatives: the set is held fixed and the last solve is
differentiated, as for the Reynolds condition.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import lax

from .reynolds_grid import (
    MAX_PASSES,
    _apply,
    _grid,
    _Operator,
    _operator,
    block_tridiagonal_solve,
)

__all__ = ["convected_content", "flux_balance", "mass_conserving_pressure"]


def _void_stencil(eps, squeeze, wedge, op: _Operator, n_theta):
    """C (acting on v = r / eps) by its stencil (n_z, n_theta) each: the
    coefficient of v_i, of v_{i+1} and of v_{i-1} in cell i's balance
    (periodic): the upwind Couette flux B H_face v through the faces i +- 1/2
    times the cell's width dzeta, and the squeeze term -A cos psi eps v times
    the cell's volume."""
    _, _, psi_f, _, _ = _grid(eps, n_theta)
    h_east = 1.0 - eps * jnp.cos(psi_f)  # H at face i + 1/2
    h_west = jnp.roll(h_east, 1)  # H at face i - 1/2
    dzeta = op.weight[:, :1] / (2.0 * jnp.pi / n_theta)  # (n_z, 1)
    b_up, b_down = jnp.maximum(wedge, 0.0), jnp.minimum(wedge, 0.0)
    diag = (dzeta * (b_up * h_east - b_down * h_west)[None, :]
            - op.volume * (squeeze * eps * jnp.cos(op.psi))[None, :])
    nxt = dzeta * (b_down * h_east)[None, :] * jnp.ones_like(op.volume)
    prev = -dzeta * (b_up * h_west)[None, :] * jnp.ones_like(op.volume)
    return diag, nxt, prev


def _apply_void(stencil, v):
    diag, nxt, prev = stencil
    return diag * v + nxt * jnp.roll(v, -1, axis=1) + prev * jnp.roll(v, 1, axis=1)


def _ring(diag, nxt, prev):
    """The dense n x n matrix of a periodic three-point stencil."""
    n = diag.shape[0]
    eye = jnp.eye(n)
    return (jnp.diag(diag) + nxt[:, None] * jnp.roll(eye, 1, axis=1)
            + prev[:, None] * jnp.roll(eye, -1, axis=1))


def _solve_mixed(op: _Operator, void, pressurised, cavitated, rhs):
    """Solve (K D_F + C D_V) u = rhs on the nodes of F (``pressurised``) and V
    (``cavitated``), u = 0 and the equation dropped on the others (the
    groove): block-tridiagonal along zeta, by block elimination."""
    keep = pressurised + cavitated  # rows with an equation
    v_diag, v_next, v_prev = void

    def block(d, east, cd, cn, cp, f, c, k):
        reynolds = _ring(d, east, jnp.roll(east, 1))
        voids = _ring(cd, cn, cp)
        m = k[:, None] * (reynolds * f[None, :] + voids * c[None, :])
        return m + jnp.diag(1.0 - k)

    blocks = jax.vmap(block)(op.diag, op.east, v_diag, v_next, v_prev, pressurised, cavitated,
                             keep)
    lower = op.north[None, :] * keep[1:] * pressurised[:-1]  # eq j+1 on u_j
    upper = op.north[None, :] * keep[:-1] * pressurised[1:]  # eq j on u_{j+1}
    rhs = keep * rhs
    return block_tridiagonal_solve(blocks, rhs, lower, upper)


def _problem(eccentricity_ratio, squeeze, wedge, half_length, n_theta, n_z, supply_groove,
             supply_pressure):
    eps = jnp.asarray(eccentricity_ratio, dtype=float)
    op = _operator(eps, half_length, n_theta, n_z)
    f = wedge * jnp.sin(op.psi) - squeeze * jnp.cos(op.psi)
    q = op.volume * f[None, :]
    groove = jnp.zeros(n_theta)
    if supply_groove:
        groove = groove.at[n_theta // 2].set(1.0)  # psi = pi (even n_theta)
    supply = jnp.asarray(supply_pressure, dtype=float) * groove[None, :] * jnp.ones(n_z)[:, None]
    return eps, op, q, groove, supply


def mass_conserving_pressure(eccentricity_ratio, squeeze, wedge, half_length, n_theta=96,
                             n_z=12, supply_groove=True, supply_pressure=0.0,
                             initial_set=None):
    """The dimensionless film pressure P (n_z, n_theta) under the JFO
    (mass-conserving) cavitation condition, the film content theta (1 in the
    full film, the fraction of the gap filled with oil where cavitated), the
    `_Operator` and the number of active-set passes (module notes);
    arguments as `finite_bearing.reynolds_pressure`'s, and ``supply_pressure``
    the groove's P (>= 0; ambient 0).  ``initial_set`` (1 pressurised) starts
    the passes from a neighbouring solution's set.  It needs the groove
    (``supply_groove``; without it the film starves, module notes); the
    passes stop at `finite_bearing.MAX_PASSES`, which ``passes`` shows."""
    eps, op, q, groove, supply = _problem(eccentricity_ratio, squeeze, wedge, half_length,
                                          n_theta, n_z, supply_groove, supply_pressure)
    void = _void_stencil(eps, squeeze, wedge, op, n_theta)
    rhs = -q - _apply(op, supply)
    open_ = 1.0 - groove[None, :]  # nodes with an equation
    op_c, void_c, rhs_c = lax.stop_gradient((op, void, rhs))

    def unsettled(state):
        free, previous, k = state
        return (k < MAX_PASSES) & ((k == 0) | jnp.any(free != previous))

    def one_pass(state):
        free, _, k = state
        u = _solve_mixed(op_c, void_c, free, open_ - free, rhs_c)
        return (u > 0.0).astype(u.dtype) * open_, free, k + 1

    if initial_set is None:
        start = (lax.stop_gradient(q) < 0.0).astype(q.dtype) * open_
    else:
        start = lax.stop_gradient(jnp.asarray(initial_set, dtype=q.dtype)) * open_
    free, _, passes = lax.while_loop(unsettled, one_pass, (start, jnp.zeros_like(start), 0))
    free = lax.stop_gradient(free)
    u = _solve_mixed(op, void, free, open_ - free, rhs)
    p = free * u + supply
    content = 1.0 + eps * (open_ - free) * u  # theta = 1 - r = 1 - eps v, v = -u
    return p, content, op, passes


def flux_balance(eccentricity_ratio, squeeze, wedge, half_length, p, content,
                 supply_groove=True):
    """Each cell's net outflow of oil (n_z, n_theta), in the units of
    `finite_bearing`'s residual K P + q (the groove's cells, a source, set to
    0): the pressure flow out of its faces (K P), the Couette flux of the
    full film (q, the cell's integral of B sin psi - A cos psi) less that of
    the void r = 1 - theta (upwind, `_void_stencil`).  Zero in every cell for
    a mass-conserving film; ``content`` may be any film content (e.g.
    `convected_content`'s for a Reynolds-condition pressure)."""
    n_z, n_theta = p.shape
    eps, op, q, groove, _ = _problem(eccentricity_ratio, squeeze, wedge, half_length,
                                     n_theta, n_z, supply_groove, 0.0)
    void = _void_stencil(eps, squeeze, wedge, op, n_theta)
    v = (1.0 - content) / jnp.where(eps > 0.0, eps, 1.0)
    return (_apply(op, p) + q - _apply_void(void, v)) * (1.0 - groove[None, :])


def convected_content(eccentricity_ratio, squeeze, wedge, half_length, p, supply_groove=True):
    """The film content theta (n_z, n_theta) that conserves the oil in the
    cavitated cells of the pressure ``p`` (its zeros off the groove): the
    content convected from the rupture boundary (theta = 1 in the
    pressurised cells), for a pressure from another cavitation condition.
    `flux_balance` of ``p`` with it then vanishes in every cavitated cell and
    shows what the pressurised cells gain or lose (for Swift-Stieber's
    pressure: the oil created where the film reforms)."""
    n_z, n_theta = p.shape
    eps, op, q, groove, _ = _problem(eccentricity_ratio, squeeze, wedge, half_length,
                                     n_theta, n_z, supply_groove, 0.0)
    void = _void_stencil(eps, squeeze, wedge, op, n_theta)
    cavitated = (p <= 0.0).astype(p.dtype) * (1.0 - groove[None, :])
    residual = _apply(op, p) + q

    def row(cd, cn, cp, c, r):
        m = _ring(cd, cn, cp) * c[:, None] * c[None, :] + jnp.diag(1.0 - c)
        return jnp.linalg.solve(m, c * r)

    v = jax.vmap(row)(*void, cavitated, residual)
    return 1.0 - eps * v
