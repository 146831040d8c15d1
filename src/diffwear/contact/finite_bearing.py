"""Hydrodynamic film force of a lubricated pin in a bushing of finite length:
the Reynolds equation on the bushing's (theta, z) grid with squeeze and wedge
action and Reynolds (Swift-Stieber) cavitation.

The finite-length counterpart of `ShortBearingFilm` (lubrication.py) and
`LongBearingFilm` (long_bearing.py): the same parameters, checks, saturation
at eps_max and outputs, for any length-to-diameter ratio.  Like them, the law
models the film only: no asperity contact and no wear.

**Reynolds equation.**  In the notation of lubrication.py (bushing at rest,
pin centre at e = eps c n, t = k x n, h = c (1 - eps cos psi) = c H at the
bushing angle theta = gamma + psi, A = 2 eps_dot, B = eps (omega - 2
gamma_dot)), the Reynolds equation of an incompressible isoviscous film,

    1/R^2 d/dpsi (h^3 dp/dpsi) + d/dz (h^3 dp/dz) = 6 mu (omega dh/dtheta + 2 dh/dt),

becomes, with p = 6 mu R^2 / c^2 P and z = R zeta,

    d/dpsi (H^3 dP/dpsi) + H^3 d^2P/dzeta^2 = B sin psi - A cos psi = f(psi),

on |zeta| <= L / D (the half length over R), P = 0 at the bearing's ends
zeta = +-L/D, periodic in psi; symmetric in zeta, so only 0 <= zeta <= L/D
is solved (dP/dzeta = 0 at zeta = 0).  The short bearing drops the first
term, the long bearing the second.

**Cavitation (Reynolds / Swift-Stieber).**  The film cannot hold a pressure
below the ambient one: P >= 0, and where the film is cavitated (P = 0) the
oil would be drawn out of it, so there the Reynolds operator's residual has
the sign that keeps it empty.  This is the complementarity problem (the
minimum over P >= 0 of the film's energy int (H^3 |grad P|^2 / 2 + f P)):

    P >= 0,    w = -div(H^3 grad P) + f >= 0,    P w = 0,

whose free boundary carries P = 0 and dP/dn = 0 (the Swift-Stieber
conditions), the cavitation model of Raimondi & Boyd's finite bearing.  The
oil is supplied at ambient pressure along the maximum film (psi = pi, an
axial groove that follows the line of centres), as in Raimondi & Boyd's full
journal bearing and the classical Reynolds-condition solution of the long
bearing: P = 0 on that line.  (Without it, the complementarity problem
also pressurises a little of the diverging film upstream of the maximum film;
at eps = 0.2, L/D = 1 that turns the attitude angle by 5 %.)

**Mass-conserving cavitation** (``cavitation = "mass-conserving"``): the
Jakobsson-Floberg-Olsson conditions in Elrod & Adams' p-theta form on the
same grid, where the film reforms only with the oil its cavitated region
carries (`mass_conserving`); with the groove at the maximum film and the
centre at rest it gives this film.

**Discretisation.**  Finite volumes on a grid uniform in s, psi = s - a sin s
(a = 0.9 eps: nodes crowd at the minimum film, spacing (1 - a) 2 pi / n_theta
there, where the pressure peak narrows as sqrt(2 (1 - eps) / eps)), and
uniform in zeta (n_z nodes, the first on the symmetry plane with half a
cell, the Dirichlet end at zeta = L/D); fluxes H^3 / J at the cell faces
(J = dpsi/ds), so the matrix K is symmetric and an M-matrix, and the
problem is the linear complementarity problem P >= 0, K P + q >= 0,
P (K P + q) = 0.

**Complementarity solve.**  A primal-dual active set method (the semismooth
Newton method on min(P, (K P + q) / diag K) = 0; Hintermueller, Ito &
Kunisch, SIAM J. Optim. 13 (2003) 865-888): from the converging half
(f < 0) as the pressurised set, solve K P + q = 0 on the pressurised nodes
with P = 0 elsewhere, then take as pressurised the nodes where P diag K >
K P + q; repeat until the set stops changing (for an M-matrix it does, in
finitely many steps).  Each linear solve is a block-tridiagonal elimination
along zeta (blocks n_theta x n_theta).  Derivatives: the set found is held
fixed and the last solve is differentiated (implicit differentiation at the
converged active set: exact wherever the set does not change under the
perturbation, i.e. away from the grid-scale kinks where a node enters or
leaves the pressurised region).

**Forces and torque** as in lubrication.py: F = -int int p u(theta) R
dtheta dz, summed with the finite volumes' weights, and the moment on the pin
T = -2 pi mu omega R^3 L / (c sqrt(1 - eps^2)) - (e / 2) F_t (the
Poiseuille part integrated by parts holds for any pressure that vanishes on
the boundary of its region: `AbstractFilm._torque`).

**Accuracy** (tests/test_finite_bearing.py): at the default grid, 96 x 12,
the steady Sommerfeld number and attitude angle are within 1.5 % of Raimondi
& Boyd's tables at L/D = 1/4, 1/2 and 1 over eps = 0.2-0.9; the grid must
resolve the minimum film, which `check_resolution` asks of the largest
eccentricity ratio the film is evaluated at (its eps_max).

References: Raimondi & Boyd, A solution for the finite journal bearing and
its application to analysis and design, ASLE Trans. 1 (1958) 159-209;
Hamrock, Schmid & Jacobson, Fundamentals of Fluid Film Lubrication (the
Reynolds equation and its boundary conditions); Hintermueller, Ito & Kunisch
(the active set method).
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

from .._checks import check_int_option, concrete
from ..errors import InputError
from .lubrication import MAX_ECCENTRICITY_RATIO, SATURATION_WIDTH, AbstractFilm
from .mass_conserving import mass_conserving_pressure
from .reynolds_grid import (
    MAX_PASSES,
    N_THETA,
    N_Z,
    _apply,
    _Operator,
    _operator,
    _resolved_eccentricity,
    block_tridiagonal_solve,
    nodes_for,
)

__all__ = ["CAVITATION", "FiniteBearingFilm", "SteadyFiniteFilm", "film_law_for",
           "film_out_of_range",
           "film_pressure", "nodes_for", "reynolds_forces"]

# Cavitation conditions (`FiniteBearingFilm`'s ``cavitation``): Reynolds
# (Swift-Stieber), this module's complementarity problem; mass-conserving
# (Jakobsson-Floberg-Olsson in Elrod & Adams' p-theta form), `mass_conserving`.
REYNOLDS, MASS_CONSERVING = "reynolds", "mass-conserving"
CAVITATION = (REYNOLDS, MASS_CONSERVING)


def _solve_on(op: _Operator, free, rhs):
    """Solve K P = rhs on the ``free`` nodes (mask, 1 free) with P = 0 on the
    others: (diag(1 - m) + m K m) P = m rhs, a symmetric block-tridiagonal
    system along zeta, by block elimination (block Thomas)."""
    n_z, n = op.diag.shape

    def block(d, east, m):
        k = (jnp.diag(d) + jnp.diag(east[:-1], 1) + jnp.diag(east[:-1], -1))
        k = k.at[n - 1, 0].add(east[-1]).at[0, n - 1].add(east[-1])
        return m[:, None] * k * m[None, :] + jnp.diag(1.0 - m)

    blocks = jax.vmap(block)(op.diag, op.east, free)
    coupling = op.north[None, :] * free[:-1] * free[1:]  # (n_z - 1, n)
    rhs = free * rhs
    return block_tridiagonal_solve(blocks, rhs, coupling, coupling)


def reynolds_pressure(eccentricity_ratio, squeeze, wedge, half_length,
                      n_theta=N_THETA, n_z=N_Z, supply_groove=True, initial_set=None,
                      supply_pressure=0.0):
    """The dimensionless film pressure P = p c^2 / (6 mu R^2) on the grid
    (n_z, n_theta), its `_Operator` and the number of active-set passes, from
    eps, A = 2 eps_dot and B = eps (omega - 2 gamma_dot) [1/s] and the half
    length over the radius, L / D (module notes).  ``initial_set`` (n_z,
    n_theta; 1 pressurised) starts the active-set passes from a neighbouring
    solution's set instead of the converging half (the same solution: for an
    M-matrix the method converges from any start).  ``supply_pressure``: the
    groove's P (>= 0; default 0, the ambient pressure; unused without the
    groove)."""
    eps = jnp.asarray(eccentricity_ratio, dtype=float)
    op = _operator(eps, half_length, n_theta, n_z)
    f = wedge * jnp.sin(op.psi) - squeeze * jnp.cos(op.psi)
    q = op.volume * f[None, :]
    # the active set, found without derivatives
    op_c, q_c = lax.stop_gradient(op), lax.stop_gradient(q)
    groove = jnp.ones(n_theta)
    if supply_groove:
        groove = groove.at[n_theta // 2].set(0.0)  # psi = pi: s = pi is a node (even n)
    # the groove's pressure, carried to the right-hand side (0 at the ambient supply)
    supply = supply_pressure * (1.0 - groove[None, :]) * jnp.ones((n_z, 1))
    load = -q - _apply(op, supply)
    load_c = lax.stop_gradient(load)

    def unsettled(state):
        free, previous, k = state
        return (k < MAX_PASSES) & ((k == 0) | jnp.any(free != previous))

    def one_pass(state):
        free, _, k = state
        p = _solve_on(op_c, free, load_c) + supply
        residual = _apply(op_c, p) + q_c
        new = (p * op_c.diag - residual > 0.0).astype(p.dtype) * groove[None, :]
        return new, free, k + 1

    if initial_set is None:
        start = (q_c < 0.0).astype(q_c.dtype) * groove[None, :]
    else:
        start = lax.stop_gradient(jnp.asarray(initial_set, dtype=q_c.dtype)) * groove[None, :]
    free, _, passes = lax.while_loop(unsettled, one_pass, (start, jnp.zeros_like(start), 0))
    free = lax.stop_gradient(free)
    return _solve_on(op, free, load) + supply, op, passes


def film_pressure(eccentricity_ratio, squeeze, wedge, half_length, n_theta=N_THETA,
                  n_z=N_Z, supply_groove=True, cavitation=REYNOLDS):
    """(P, op): the grid pressure and its `_Operator` under the cavitation
    condition ``cavitation`` (`CAVITATION`): `reynolds_pressure`'s, or
    `mass_conserving.mass_conserving_pressure`'s."""
    if cavitation == REYNOLDS:
        p, op, _ = reynolds_pressure(eccentricity_ratio, squeeze, wedge, half_length,
                                     n_theta, n_z, supply_groove)
        return p, op
    if cavitation != MASS_CONSERVING:
        raise InputError(f"finite-bearing cavitation {cavitation!r} is unknown; allowed: "
                         + " | ".join(repr(c) for c in CAVITATION))
    p, _, op, _ = mass_conserving_pressure(eccentricity_ratio, squeeze, wedge, half_length,
                                           n_theta, n_z, supply_groove)
    return p, op


def reynolds_forces(eccentricity_ratio, squeeze, wedge, half_length,
                    n_theta=N_THETA, n_z=N_Z, supply_groove=True, cavitation=REYNOLDS):
    """(F_n, F_t) / (6 mu R^4 / c^2) [-]: the film force on the pin along the
    line of centres and along k x n, for the whole length (both halves), in
    units of 6 mu R^4 / c^2 (`film_pressure`'s arguments)."""
    return _film_forces(*film_pressure(eccentricity_ratio, squeeze, wedge, half_length,
                                       n_theta, n_z, supply_groove, cavitation)[::-1])


def _film_forces(op: _Operator, p):
    """(F_n, F_t) / (6 mu R^4 / c^2) of the grid pressure ``p`` on ``op``'s
    cells, both halves of the length (`reynolds_forces`)."""
    load = 2.0 * op.volume * p
    return -jnp.sum(load * jnp.cos(op.psi)[None, :]), -jnp.sum(load * jnp.sin(op.psi)[None, :])


def _catmull_rom(values, x):
    """Catmull-Rom cubic through ``values`` (nodes along axis 0 at x = 0, 1,
    ...), at x >= 0: mirrored at x = 0 (even, so smooth in eps there), held
    at the last node beyond the table."""
    n = values.shape[0]
    x = jnp.clip(x, 0.0, n - 1.0)
    i = jnp.clip(jnp.floor(x).astype(int), 0, n - 2)
    t = x - i
    p = jnp.concatenate([values[1:2], values, 2 * values[-1:] - values[-2:-1]])
    p0, p1, p2, p3 = p[i], p[i + 1], p[i + 2], p[i + 3]
    return 0.5 * (2 * p1 + (p2 - p0) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t**2
                  + (3 * p1 - p0 - 3 * p2 + p3) * t**3)


class FiniteBearingFilm(AbstractFilm):
    """Finite-length hydrodynamic film: the Reynolds equation on the bushing's
    (theta, z) grid, squeeze and wedge action, Reynolds (Swift-Stieber)
    cavitation by a complementarity solve (module docstring).

    Arguments (viscosity, length, clearance, max_eccentricity_ratio,
    saturation_width as for `ShortBearingFilm`; each a float64 array leaf):
        viscosity: dynamic viscosity mu of the oil [Pa s] (> 0)
        length: axial length L of the bearing [m] (> 0; any L / D)
        clearance: radial clearance c of the round bore [m] (> 0)
        max_eccentricity_ratio: eps_max in (0, 1), default 0.95; the film is
            evaluated at the pin's eps up to eps_max - w and saturates towards eps_max
            and the grid must resolve the minimum film at eps_max
            (`check_resolution`)
        saturation_width: width w of the saturation below eps_max, in
            (0, eps_max), default 0.01
        n_theta: grid nodes round the bushing (even, >= 16; default 96)
        n_z: grid nodes along the half length (>= 2; default 12)
        supply_groove: oil at ambient pressure along the maximum film (as in
            Raimondi & Boyd's full bearing; default True) or only at the ends
        cavitation: ``"reynolds"`` (Swift-Stieber, default) or
            ``"mass-conserving"`` (Jakobsson-Floberg-Olsson in Elrod & Adams'
            p-theta form: the film reforms only with the oil that the
            cavitated region carries; `mass_conserving`)

    Journal radius R: the pin radius of the `PinKinematics`, as for the other
    films; L / D = length / (2 R).
    """

    n_theta: int = eqx.field(static=True)
    n_z: int = eqx.field(static=True)
    supply_groove: bool = eqx.field(static=True)
    cavitation: str = eqx.field(static=True)

    def __init__(self, viscosity, length, clearance,
                 max_eccentricity_ratio=MAX_ECCENTRICITY_RATIO,
                 saturation_width=SATURATION_WIDTH, n_theta=N_THETA, n_z=N_Z,
                 supply_groove=True, cavitation=REYNOLDS):
        super().__init__(viscosity, length, clearance, max_eccentricity_ratio, saturation_width)
        check_int_option("finite-bearing grid n_theta", n_theta, 16, 4096)
        if n_theta % 2:
            raise InputError(f"finite-bearing grid n_theta must be even (a node on the "
                             f"maximum film), got {n_theta}")
        check_int_option("finite-bearing grid n_z", n_z, 2, 1024)
        self.n_theta = int(n_theta)
        self.n_z = int(n_z)
        self.supply_groove = bool(supply_groove)
        if cavitation not in CAVITATION:
            raise InputError(f"finite-bearing cavitation {cavitation!r} is unknown; allowed: "
                             + " | ".join(repr(c) for c in CAVITATION))
        self.cavitation = str(cavitation)
        if self.cavitation == MASS_CONSERVING and not self.supply_groove:
            raise InputError("finite-bearing cavitation 'mass-conserving' needs the supply "
                             "groove (supply_groove = True): without it the oil only leaves "
                             "through the ends and the film starves; allowed: supply_groove "
                             "= True, or cavitation = 'reynolds'")
        self.check_resolution(self.max_eccentricity_ratio)

    @property
    def resolved_eccentricity_ratio(self) -> float:
        """The largest eps whose minimum film the grid resolves (`NODES_PER_FILM_WIDTH`
        nodes across sqrt(2 (1 - eps) / eps))."""
        return _resolved_eccentricity(self.n_theta)

    def check_resolution(self, eccentricity_ratio, what="finite-bearing grid n_theta"):
        """`InputError` when the grid is too coarse for the minimum film at
        ``eccentricity_ratio`` (silent under tracing)."""
        eps = concrete(eccentricity_ratio)
        if eps is None:
            return
        eps_max = float(eps.max())
        top = self.resolved_eccentricity_ratio
        if eps_max > top:
            need = nodes_for(eps_max)
            raise InputError(
                f"{what} = {self.n_theta} is too coarse for the film at eccentricity ratio "
                f"{eps_max:.4g}: it resolves the minimum film up to eps = {top:.4g}; allowed: "
                f"n_theta >= {need} (or a smaller maximum eccentricity ratio)")

    def _film_factor(self, radius):
        """6 mu R^4 / c^2 [N s]: the scale of `reynolds_forces` (the pressure
        factor 6 mu R^2 / c^2 times the area R dpsi R dzeta).  Unlike the short
        and long films' K, K pi/2 is not the eps = 0 film's damping (that
        depends on L / D); the shared `AbstractFilm.film` only adds and
        subtracts it."""
        return 6.0 * self.viscosity * radius**4 / self.clearance**2

    def _excess_components(self, eps_f, squeeze, wedge, radius):
        """F_n + K pi/2 A and F_t - K pi/2 B [N] (`_film_factor`): the solved
        forces less the part `AbstractFilm.film` adds back."""
        k = self._film_factor(radius)
        f_n, f_t = reynolds_forces(eps_f, squeeze, wedge, self.length / (2.0 * radius),
                                   self.n_theta, self.n_z, self.supply_groove,
                                   self.cavitation)
        return k * f_n + 0.5 * jnp.pi * k * squeeze, k * f_t - 0.5 * jnp.pi * k * wedge

    def steady_peak_pressure(self, eccentricity_ratio, omega, radius):
        """The film's largest pressure [Pa] with the centre at rest (e_dot = 0):
        6 mu R^2 / c^2 times the grid's largest P, at the saturated eps."""
        eps = self._saturated(jnp.asarray(eccentricity_ratio, dtype=float))
        p, _ = film_pressure(eps, 0.0, eps * jnp.abs(omega), self.length / (2.0 * radius),
                             self.n_theta, self.n_z, self.supply_groove, self.cavitation)
        return 6.0 * self.viscosity * radius**2 / self.clearance**2 * jnp.max(p)

    def steady(self, radius) -> "SteadyFiniteFilm":
        """This film for a journal centre at rest in the bushing (e_dot = 0),
        tabulated in eps (`SteadyFiniteFilm`) for the journal radius ``radius``."""
        return SteadyFiniteFilm(self, radius)


# The short (Ocvirk) film's steady load is within 4.5 % of the finite film's
# (96 x 12 grid) wherever (L/D)^2 <= 0.05 (1 - eps) (on that boundary: 1.9 %
# high at eps = 0.2, 3.4 % at 0.8, 4.2 % at 0.995); beyond it the error grows,
# roughly as 0.6 (L/D)^2 / (1 - eps) at first: 7 % at L/D = 0.1, eps = 0.9;
# x 3.5 at L/D = 0.7, eps = 0.9; x 13 at eps = 0.98 (tests/test_finite_bearing.py,
# the map in docs/guide/lubrication.md).
SHORT_BEARING_LIMIT = 0.05


def film_law_for(length_over_diameter: float, max_eccentricity_ratio: float) -> str:
    """The film law a bearing of ``length_over_diameter`` run up to
    ``max_eccentricity_ratio`` gets by default: ``"short"`` where
    (L/D)^2 <= 0.05 (1 - eps_max), where the short film's load is within 4.5 %
    of the finite film's at every eps <= eps_max, else ``"finite"``.  The
    long (half-Sommerfeld) film is never the default: against the finite film
    it is within 5 % only in a narrow band (L/D ~ 4, eps <= 0.8; at L/D = 4 it
    is 7 % low at eps = 0.9 and 11 % low at 0.95, at L/D = 2 and eps = 0.4
    52 % high)."""
    ld, eps = float(length_over_diameter), float(max_eccentricity_ratio)
    return "short" if ld**2 <= SHORT_BEARING_LIMIT * (1.0 - eps) else "finite"


def film_out_of_range(bearing: str, law, pin_radius) -> str | None:
    """A sentence where the ``bearing`` film (``"short"``, ``"long"`` or
    ``"finite"``) of the lubricated ``law`` (a `MixedLubrication`) on a pin of
    ``pin_radius`` [m] is outside its range (`film_law_for`: the short film
    beyond (L/D)^2 = 0.05 (1 - eps_max), the long film anywhere), else None."""
    ld = float(law.film.length) / (2.0 * float(pin_radius))
    eps_max = float(law.saturated_film().max_eccentricity_ratio)
    if bearing == "finite" or film_law_for(ld, eps_max) == bearing:
        return None
    return (f"the {bearing} film is outside its range here (L/D = {ld:.3g}, eccentricity ratio "
            f"up to {eps_max:.3g}: the short film holds to 4.5 % only where (L/D)^2 <= 0.05 "
            f"(1 - eps); at L/D = 0.7 and eps = 0.9 it carries 3.5 x the finite film's "
            f"load); bearing = \"finite\" gives the finite-length film's numbers")


# Nodes of the steady film's table: uniform in w = sqrt(-ln(1 - eps)) from
# eps = 0 to 1 - 2.5e-3 (w = 2.45, past the largest eps the saturated film is
# evaluated at, 0.995 + 0.0025); 56 nodes.  The forces vary like (1 - eps)^-k
# near contact (linear in w^2 in log scale) and like a + b eps near the centre
# (even in w), so a cubic (Catmull-Rom) through log |F| in w, mirrored at
# w = 0, is within 1e-3 of the solve between nodes (tests/test_finite_bearing.py).
TABLE_NODES = 56
_TABLE_TOP = math.sqrt(-math.log(2.5e-3))


class SteadyFiniteFilm(AbstractFilm):
    """The finite film of a journal whose centre is at rest in the bushing
    (e_dot = 0: the steadily loaded bearing), tabulated once: with no squeeze
    the Reynolds problem depends on the pin's state only through eps and the
    wedge B = eps (omega - 2 gamma_dot), to which the pressure is proportional
    (the complementarity solution is positively homogeneous in the
    right-hand side; a reversed wedge mirrors the film, F_t changes sign).  So
    F_n = K |B| g_n(eps) and F_t = K B g_t(eps), K = 6 mu R^4 / c^2, with g
    interpolated from `TABLE_NODES` solves (cubic in w = sqrt(-ln(1 - eps))
    through log g).  The table is computed from the film's leaves (length, and the pin
    radius given), so it is differentiable in them; it is exact for e_dot = 0
    only (`FiniteBearingFilm.steady`; the quasi-static orbit, which has
    squeeze, takes `finite_table.moving_film`)."""

    radius: Float[Array, ""]
    log_radial: Float[Array, " k"]  # log(-g_n) (g_n does not vanish at eps = 0: the
    # Reynolds condition's film reaches past the minimum film, phi(0) < 90 deg)
    log_tangential: Float[Array, " k"]  # log(g_t)
    log_peak: Float[Array, " k"]  # log(max P) at B = 1

    def __init__(self, film: "FiniteBearingFilm", radius):
        super().__init__(film.viscosity, film.length, film.clearance,
                         film.max_eccentricity_ratio, film.saturation_width)
        self.radius = jnp.asarray(radius, dtype=float)
        w = jnp.linspace(0.0, _TABLE_TOP, TABLE_NODES)
        eps = -jnp.expm1(-(w**2))
        half = film.length / (2.0 * self.radius)
        # one solve after the other (lax.map): batched, the small dense
        # inverses of the elimination are slower on a CPU (docs/notes/cpu-kernels.md)
        def solve(e):
            p, op = film_pressure(e, 0.0, 1.0, half, film.n_theta, film.n_z,
                                  film.supply_groove, film.cavitation)
            return (*_film_forces(op, p), jnp.max(p))

        f_n, f_t, peak = lax.map(solve, eps)
        self.log_radial = jnp.log(-f_n)
        self.log_tangential = jnp.log(f_t)
        self.log_peak = jnp.log(peak)

    def _interpolate(self, values, eps):
        """Catmull-Rom cubic through ``values`` at the uniform w nodes, at
        w = sqrt(-ln(1 - eps)): mirrored at w = 0 (even in w, so smooth in eps
        there), held at the last node beyond the table."""
        step = _TABLE_TOP / (TABLE_NODES - 1)
        top = 1.0 - math.exp(-(_TABLE_TOP**2))
        u = -jnp.log1p(-jnp.clip(eps, 0.0, top))
        return _catmull_rom(values, jnp.sqrt(u + 1e-30) / step)

    def steady_peak_pressure(self, eccentricity_ratio, omega, radius):
        """The film's largest pressure [Pa], from the table: 6 mu R^2 / c^2
        eps |omega| max P(eps) (max P proportional to the wedge B)."""
        eps = self._saturated(jnp.asarray(eccentricity_ratio, dtype=float))
        return (6.0 * self.viscosity * radius**2 / self.clearance**2 * eps * jnp.abs(omega)
                * jnp.exp(self._interpolate(self.log_peak, eps)))

    def _film_factor(self, radius):
        """6 mu R^4 / c^2 [N s], as `FiniteBearingFilm`'s."""
        return 6.0 * self.viscosity * radius**4 / self.clearance**2

    def _excess_components(self, eps_f, squeeze, wedge, radius):
        """F_n + K pi/2 A and F_t - K pi/2 B [N] of the tabulated steady film
        (A, the squeeze, is taken as 0: the table holds e_dot = 0 only)."""
        k = self._film_factor(radius)
        f_n = -k * jnp.abs(wedge) * jnp.exp(self._interpolate(self.log_radial, eps_f))
        f_t = k * wedge * jnp.exp(self._interpolate(self.log_tangential, eps_f))
        return f_n + 0.5 * jnp.pi * k * squeeze, f_t - 0.5 * jnp.pi * k * wedge
