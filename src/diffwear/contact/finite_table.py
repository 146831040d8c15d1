"""The finite-length film for any motion of the journal centre, tabulated:
`FiniteBearingFilm`'s Reynolds solution with squeeze and wedge, read from a
table in the eccentricity ratio and the direction of the film's drive.

**Homogeneity.**  The dimensionless Reynolds problem of finite_bearing.py
depends on the pin's state through eps and the right-hand side f(psi) =
B sin psi - A cos psi only (A = 2 eps_dot, B = eps (omega - 2 gamma_dot)),
and its complementarity solution is positively homogeneous in f (P solves
the problem for f, so s P solves it for s f, s > 0).  With r = sqrt(A^2 + B^2)
and the drive's direction phi = atan2(A, B):

    (F_n, F_t) = K r (g_n(eps, phi), g_t(eps, phi)),   K = 6 mu R^4 / c^2,

so one table of g over eps and phi gives the film for any centre motion
(phi = 0: the steady film, phi = pi/2: pure squeeze towards the bore, phi =
pi: the reversed wedge).

**Mirror symmetry.**  The grid of finite_bearing.py is symmetric under psi
-> -psi (nodes s -> 2 pi - s, the groove at psi = pi on itself), which turns
f for (A, B) into f for (A, -B): g_n(eps, pi - phi) = g_n(eps, phi) and
g_t(eps, pi - phi) = -g_t(eps, phi).  Only the half -pi/2 <= phi <= pi/2
(B >= 0) is solved; the other half is its mirror image.

**Table.**  Nodes uniform in w = sqrt(-ln(1 - eps)) from eps = 0 to the
table's top eps (as `SteadyFiniteFilm`'s, which it reduces to at phi = 0),
and uniform in phi (a multiple of 4, so phi = 0, +-pi/2 and pi are nodes).
The forces grow by orders of magnitude towards eps = 1 but change sign with
phi, so neither the values nor their logarithms interpolate well in both
variables: each eps node's values are divided by their root mean square
over phi, the envelope E(eps).  log E is interpolated like the steady table's
log |F| (a Catmull-Rom cubic in w, mirrored at w = 0); the scaled values g / E,
between -1.5 and 1.5, by the same cubic in w and a periodic cubic spline in
phi (C2; it reproduces the first harmonic cos phi, sin phi of a film
without cavitation to O(h^4)).

**Construction.**  Along each eps node the directions are solved in order,
each active-set solve starting from its neighbour's pressurised set (about
half the passes it takes from the converging half); the eps nodes one
after the other (`lax.map`; ``batch_size`` batches them).  Sizes, times
and the accuracy against direct solves: docs/notes/finite-film-table.md.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, Float

from .._checks import check_int_option, check_range, concrete
from ..errors import InputError
from .finite_bearing import (
    FiniteBearingFilm,
    _catmull_rom,
    _film_forces,
    _grid,
    reynolds_pressure,
)
from .lubrication import MAX_ECCENTRICITY_RATIO, AbstractFilm, _safe_unit

__all__ = ["DynamicFiniteFilm"]

# Default table: 17 eccentricity nodes (uniform in w up to eps = 0.95, step
# 0.108) by 32 drive directions (17 solved, 15 mirrored): 289 solves, within
# 1.1 % of the direct solves' |F| at off-node points over eps <= 0.95 and
# L/D = 0.25 .. 2; 16 directions leave up to 8 % of |F| where the film
# separates (|F| ~ E / 30), 9 eps nodes up to 2.4 % (docs/notes/finite-film-table.md).
ECCENTRICITY_NODES = 17
DIRECTION_NODES = 32


def _periodic_spline_matrix(n: int) -> np.ndarray:
    """S (n x n): the second derivatives M = S y of the periodic cubic spline
    through y at n uniform nodes of spacing h = 2 pi / n, from the spline's
    continuity of slope, M_{k-1} + 4 M_k + M_{k+1} = 6 (y_{k-1} - 2 y_k +
    y_{k+1}) / h^2 (a circulant system, diagonally dominant)."""
    h = 2.0 * math.pi / n
    eye = np.eye(n)
    shift = np.roll(eye, 1, axis=1) + np.roll(eye, -1, axis=1)
    return np.linalg.solve(4.0 * eye + shift, 6.0 / h**2 * (shift - 2.0 * eye))


class DynamicFiniteFilm(AbstractFilm):
    """`FiniteBearingFilm` for any motion of the journal centre (squeeze and
    wedge), tabulated once over the eccentricity ratio and the direction phi =
    atan2(A, B) of the film's drive (module docstring): F = K r g(eps, phi).

    Arguments:
        film: the `FiniteBearingFilm` to tabulate (its oil, bore, grid and
            groove; its leaves enter the table's solves, so the table is
            differentiable in them)
        radius: the journal radius R [m] (L / D = length / 2 R)
        n_eccentricity: eps nodes, uniform in w = sqrt(-ln(1 - eps)) from 0 to
            the top (>= 4; default `ECCENTRICITY_NODES`)
        n_direction: phi nodes round the circle (a multiple of 4, >= 8;
            default `DIRECTION_NODES`; n_direction / 2 + 1 are solved)
        top_eccentricity_ratio: the table's largest eps, in (0, 1), not below
            the film's eps_max (the saturated film never exceeds eps_max);
            default 0.95, the films' default eps_max.  Beyond it the scaled
            forces are held at the top node's: a film whose eps_max is raised
            later (a mixed law's saturation) needs a table that reaches it.
        batch_size: eps nodes solved together (`lax.map`'s batch_size;
            default None, one after the other)

    The table costs n_eccentricity (n_direction / 2 + 1) Reynolds solves at
    construction; an evaluation is a few hundred flops.
    """

    radius: Float[Array, ""]
    log_envelope: Float[Array, " k"]  # log E(eps): the rms of |g| over phi
    scaled: Float[Array, "k m 2"]  # (g_n, g_t) / E at the (eps, phi) nodes
    log_peak: Float[Array, " k"]  # log(max P) of the steady film at B = 1
    top: float = eqx.field(static=True)

    def __init__(self, film: FiniteBearingFilm, radius, n_eccentricity=ECCENTRICITY_NODES,
                 n_direction=DIRECTION_NODES, top_eccentricity_ratio=MAX_ECCENTRICITY_RATIO,
                 batch_size=None):
        super().__init__(film.viscosity, film.length, film.clearance,
                         film.max_eccentricity_ratio, film.saturation_width)
        check_int_option("finite-film table n_eccentricity", n_eccentricity, 4, 4096)
        check_int_option("finite-film table n_direction", n_direction, 8, 4096)
        if n_direction % 4:
            raise InputError(f"finite-film table n_direction must be a multiple of 4 "
                             f"(phi = 0, pi/2, pi, 3 pi/2 on nodes), got {n_direction}")
        check_range("finite-film table top_eccentricity_ratio", top_eccentricity_ratio,
                    0.0, 1.0, low_open=True, high_open=True)
        eps_max = concrete(film.max_eccentricity_ratio)
        if eps_max is not None and float(eps_max) > float(top_eccentricity_ratio):
            raise InputError(f"finite-film table top_eccentricity_ratio = "
                             f"{float(top_eccentricity_ratio)} is below the film's maximum "
                             f"eccentricity ratio {float(eps_max)}; allowed: "
                             f">= {float(eps_max)} and < 1")
        self.top = float(top_eccentricity_ratio)
        film.check_resolution(self.top, "finite-film table's grid n_theta")
        self.radius = jnp.asarray(radius, dtype=float)
        half = film.length / (2.0 * self.radius)

        w = jnp.linspace(0.0, math.sqrt(-math.log1p(-self.top)), n_eccentricity)
        eps_nodes = -jnp.expm1(-(w**2))
        solved = n_direction // 2 + 1
        phi = -0.5 * jnp.pi + 2.0 * jnp.pi / n_direction * jnp.arange(solved)
        zeros = jnp.zeros((film.n_z, film.n_theta))

        def along_directions(eps):
            def step(free, angle):
                p, op, _ = reynolds_pressure(eps, jnp.sin(angle), jnp.cos(angle), half,
                                             film.n_theta, film.n_z, film.supply_groove,
                                             initial_set=free)
                forces = jnp.stack(_film_forces(op, p))
                return (p > 0.0).astype(p.dtype), (forces, jnp.max(p))

            # phi = -pi/2 (A = -1, B = 0, f = cos psi) starts from its converging
            # half, cos psi < 0, as `reynolds_pressure` would
            start = (jnp.cos(_grid(eps, film.n_theta)[0]) < 0.0)[None, :] + zeros
            _, (forces, peaks) = lax.scan(step, start.astype(zeros.dtype), phi)
            return forces, peaks[solved // 2]  # phi = 0: the steady film at B = 1

        # (k, solved, 2) forces and (k,) peaks
        half_table, peak = lax.map(along_directions, eps_nodes, batch_size=batch_size)
        # the other half, phi_{m - j} = pi - phi_j: g_n even, g_t odd
        mirrored = half_table[:, 1:-1][:, ::-1] * jnp.array([1.0, -1.0])
        table = jnp.concatenate([half_table, mirrored], axis=1)  # (k, n_direction, 2)
        envelope = jnp.sqrt(jnp.mean(jnp.sum(table**2, axis=-1), axis=1))
        self.log_envelope = jnp.log(envelope)
        self.scaled = table / envelope[:, None, None]
        self.log_peak = jnp.log(peak)

    def _node_coordinate(self, eps):
        """x = w / dw at the saturated eps (clipped to the table)."""
        k = self.log_envelope.shape[0]
        w_top = math.sqrt(-math.log1p(-self.top))
        u = -jnp.log1p(-jnp.clip(eps, 0.0, self.top))
        return jnp.sqrt(u + 1e-30) / (w_top / (k - 1))

    def dimensionless_forces(self, eps, squeeze, wedge):
        """(F_n, F_t) / (6 mu R^4 / c^2) [-] (`reynolds_forces`' units) at
        eps, A = 2 eps_dot and B = eps (omega - 2 gamma_dot) [1/s], from the
        table."""
        x = self._node_coordinate(eps)
        envelope = jnp.exp(_catmull_rom(self.log_envelope, x))
        column = _catmull_rom(self.scaled, x)  # (n_direction, 2) at this eps
        m = column.shape[0]
        curvature = jnp.asarray(_periodic_spline_matrix(m)) @ column
        direction, r = _safe_unit(jnp.stack([wedge, squeeze]))
        h = 2.0 * math.pi / m
        s = jnp.mod(jnp.arctan2(direction[1], direction[0]) + 0.5 * jnp.pi, 2.0 * jnp.pi) / h
        i = jnp.clip(jnp.floor(s).astype(int), 0, m - 1)
        t = s - i
        j = jnp.mod(i + 1, m)
        g = ((1.0 - t) * column[i] + t * column[j]
             + h**2 / 6.0 * (((1.0 - t) ** 3 - (1.0 - t)) * curvature[i]
                             + (t**3 - t) * curvature[j]))
        return r * envelope * g[0], r * envelope * g[1]

    def steady_peak_pressure(self, eccentricity_ratio, omega, radius):
        """The film's largest pressure [Pa] with the centre at rest, from the
        table's phi = 0 column: 6 mu R^2 / c^2 eps |omega| max P(eps)."""
        eps = self._saturated(jnp.asarray(eccentricity_ratio, dtype=float))
        return (6.0 * self.viscosity * radius**2 / self.clearance**2 * eps * jnp.abs(omega)
                * jnp.exp(_catmull_rom(self.log_peak, self._node_coordinate(eps))))

    def _film_factor(self, radius):
        """6 mu R^4 / c^2 [N s], as `FiniteBearingFilm`'s."""
        return 6.0 * self.viscosity * radius**4 / self.clearance**2

    def _excess_components(self, eps_f, squeeze, wedge, radius):
        """F_n + K pi/2 A and F_t - K pi/2 B [N] (`_film_factor`) of the
        tabulated film."""
        k = self._film_factor(radius)
        f_n, f_t = self.dimensionless_forces(eps_f, squeeze, wedge)
        return k * f_n + 0.5 * jnp.pi * k * squeeze, k * f_t - 0.5 * jnp.pi * k * wedge
