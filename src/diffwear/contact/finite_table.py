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

import functools
import math
from importlib import resources
from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, Float

from .._checks import check_int_option, check_range, concrete
from ..errors import InputError
from .finite_bearing import (
    N_THETA,
    N_Z,
    REYNOLDS,
    FiniteBearingFilm,
    _catmull_rom,
    _film_forces,
    film_law_for,
    film_pressure,
    reynolds_pressure,
)
from .lubrication import MAX_ECCENTRICITY_RATIO, AbstractFilm, ShortBearingFilm, _safe_unit
from .reynolds_grid import _grid

__all__ = ["DynamicFiniteFilm", "ShippedFiniteFilm", "default_film", "moving_film",
           "shipped_tables"]

# Default table: 17 eccentricity nodes (uniform in w up to eps = 0.95, step
# 0.108) by 32 drive directions (17 solved, 15 mirrored): 289 solves, within
# 1.1 % of the direct solves' |F| at off-node points over eps <= 0.95 and
# L/D = 0.25 .. 2; 16 directions leave up to 8 % of |F| where the film
# separates (|F| ~ E / 30), 9 eps nodes up to 2.4 % (docs/notes/finite-film-table.md).
ECCENTRICITY_NODES = 17
DIRECTION_NODES = 32

# The shipped tables (finite_film_tables.npz, design_studies/finite_film_tables.py):
# the default grid's dimensionless table at 21 L/D nodes, log-spaced from 0.05
# to 4 (ratio 80^(1/20) = 1.245 between nodes), each 25 eps nodes (uniform in
# w = sqrt(-ln(1 - eps)) up to eps = 0.998: w step 0.104, the default table's
# 0.108 or finer) by 32 directions.  0.998 lies past the mixed law's largest
# saturation, 0.995 (mixed.MAX_SATURATION), and within what the 96-node grid
# resolves (0.9986, `nodes_for`).
SHIPPED_RATIOS = tuple(float(x) for x in np.geomspace(0.05, 4.0, 21))
SHIPPED_ECCENTRICITY_NODES = 25
SHIPPED_DIRECTION_NODES = 32
SHIPPED_TOP = 0.998
SHIPPED_FILE = "finite_film_tables.npz"


def _periodic_spline_matrix(n: int) -> np.ndarray:
    """S (n x n): the second derivatives M = S y of the periodic cubic spline
    through y at n uniform nodes of spacing h = 2 pi / n, from the spline's
    continuity of slope, M_{k-1} + 4 M_k + M_{k+1} = 6 (y_{k-1} - 2 y_k +
    y_{k+1}) / h^2 (a circulant system, diagonally dominant)."""
    h = 2.0 * math.pi / n
    eye = np.eye(n)
    shift = np.roll(eye, 1, axis=1) + np.roll(eye, -1, axis=1)
    return np.linalg.solve(4.0 * eye + shift, 6.0 / h**2 * (shift - 2.0 * eye))


def _node_coordinate(eps, top, k):
    """x = w / dw of eps on k nodes uniform in w = sqrt(-ln(1 - eps)) from 0
    to the ``top`` eps (eps clipped to the table)."""
    w_top = math.sqrt(-math.log1p(-top))
    u = -jnp.log1p(-jnp.clip(eps, 0.0, top))
    return jnp.sqrt(u + 1e-30) / (w_top / (k - 1))


def _along_directions(column, squeeze, wedge):
    """r (g_n, g_t) / E at phi = atan2(A, B), r = |(A, B)|, from a table's
    scaled values at one eps, ``column`` (m, 2) at m uniform phi nodes from
    -pi/2: the periodic cubic spline in phi (module docstring)."""
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
    return r * g[0], r * g[1]


class _TabulatedFilm(AbstractFilm):
    """A finite film read from a table of its dimensionless forces for any
    centre motion, F = K (g_n, g_t) with K = 6 mu R^4 / c^2: what
    `DynamicFiniteFilm` and `ShippedFiniteFilm` share.  A subclass gives
    ``dimensionless_forces(eps, squeeze, wedge)`` and ``_log_peak(eps)``
    (log max P of the steady film at B = 1)."""

    def steady_peak_pressure(self, eccentricity_ratio, omega, radius):
        """The film's largest pressure [Pa] with the centre at rest:
        6 mu R^2 / c^2 eps |omega| max P(eps)."""
        eps = self._saturated(jnp.asarray(eccentricity_ratio, dtype=float))
        return (6.0 * self.viscosity * radius**2 / self.clearance**2 * eps * jnp.abs(omega)
                * jnp.exp(self._log_peak(eps)))

    def _film_factor(self, radius):
        """6 mu R^4 / c^2 [N s], as `FiniteBearingFilm`'s."""
        return 6.0 * self.viscosity * radius**4 / self.clearance**2

    def _excess_components(self, eps_f, squeeze, wedge, radius):
        """F_n + K pi/2 A and F_t - K pi/2 B [N] (`_film_factor`) of the
        tabulated film."""
        k = self._film_factor(radius)
        f_n, f_t = self.dimensionless_forces(eps_f, squeeze, wedge)
        return k * f_n + 0.5 * jnp.pi * k * squeeze, k * f_t - 0.5 * jnp.pi * k * wedge


class DynamicFiniteFilm(_TabulatedFilm):
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
                if film.cavitation == REYNOLDS:
                    p, op, _ = reynolds_pressure(eps, jnp.sin(angle), jnp.cos(angle), half,
                                                 film.n_theta, film.n_z, film.supply_groove,
                                                 initial_set=free)
                else:  # its pressure is homogeneous in (A, B) too (mass_conserving)
                    p, op = film_pressure(eps, jnp.sin(angle), jnp.cos(angle), half,
                                          film.n_theta, film.n_z, film.supply_groove,
                                          film.cavitation)
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
        return _node_coordinate(eps, self.top, self.log_envelope.shape[0])

    def dimensionless_forces(self, eps, squeeze, wedge):
        """(F_n, F_t) / (6 mu R^4 / c^2) [-] (`reynolds_forces`' units) at
        eps, A = 2 eps_dot and B = eps (omega - 2 gamma_dot) [1/s], from the
        table."""
        x = self._node_coordinate(eps)
        envelope = jnp.exp(_catmull_rom(self.log_envelope, x))
        g_n, g_t = _along_directions(_catmull_rom(self.scaled, x), squeeze, wedge)
        return envelope * g_n, envelope * g_t

    def _log_peak(self, eps):
        """log max P of the steady film at B = 1 (the table's phi = 0 column)."""
        return _catmull_rom(self.log_peak, self._node_coordinate(eps))


class ShippedTables(NamedTuple):
    """The shipped dimensionless tables (`SHIPPED_RATIOS` x ... nodes):
    ``log_envelope`` (l, k), ``scaled`` (l, k, m, 2) and ``log_peak`` (l, k),
    as `DynamicFiniteFilm`'s fields at each L/D node."""

    length_over_diameter: np.ndarray
    log_envelope: np.ndarray
    scaled: np.ndarray
    log_peak: np.ndarray


@functools.cache
def shipped_tables() -> ShippedTables:
    """The moving-journal tables shipped with the package
    (finite_film_tables.npz, written by design_studies/finite_film_tables.py),
    read once; checked against the grid and nodes they were built for."""
    with resources.files(__package__).joinpath(SHIPPED_FILE).open("rb") as fh:
        data = np.load(fh)
        tables = ShippedTables(*(np.asarray(data[k], dtype=np.float64)
                                 for k in ShippedTables._fields))
        grid, top = tuple(int(n) for n in data["grid"]), float(data["top_eccentricity_ratio"])
    shape = (len(SHIPPED_RATIOS), SHIPPED_ECCENTRICITY_NODES, SHIPPED_DIRECTION_NODES, 2)
    if (grid != (N_THETA, N_Z) or top != SHIPPED_TOP or tables.scaled.shape != shape
            or not np.allclose(tables.length_over_diameter, SHIPPED_RATIOS, rtol=1e-12)):
        raise RuntimeError(f"{SHIPPED_FILE} does not match finite_table's SHIPPED_* nodes; "
                           "regenerate it with design_studies/finite_film_tables.py")
    return tables


def _padded(values):
    """``values`` (l, k, ...) with a ghost node at each end of both axes, for
    the Catmull-Rom cubics: along L/D (axis 0) extrapolated linearly, along
    w (axis 1) mirrored at w = 0 (even in w) and extrapolated at the top (as
    `_catmull_rom`)."""
    v = np.concatenate([2 * values[:1] - values[1:2], values, 2 * values[-1:] - values[-2:-1]])
    return np.concatenate([v[:, 1:2], v, 2 * v[:, -1:] - v[:, -2:-1]], axis=1)


@functools.cache
def _padded_tables() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`shipped_tables`' log envelope, scaled values and log peak, `_padded`."""
    t = shipped_tables()
    return _padded(t.log_envelope), _padded(t.scaled), _padded(t.log_peak)


def _cubic_weights(x, n):
    """The node index i and the four Catmull-Rom weights of nodes i - 1 .. i + 2
    at x in [0, n - 1] (clipped), n nodes."""
    x = jnp.clip(x, 0.0, n - 1.0)
    i = jnp.clip(jnp.floor(x).astype(int), 0, n - 2)
    t = x - i
    return i, 0.5 * jnp.stack([-t + 2 * t**2 - t**3, 2 - 5 * t**2 + 3 * t**3,
                               t + 4 * t**2 - 3 * t**3, -t**2 + t**3])


def _bicubic(padded, il, wl, ie, we):
    """The Catmull-Rom cubic in L/D and w of a `_padded` table at the nodes
    and weights of `_cubic_weights` (the 4 x 4 neighbouring nodes only)."""
    size = (4, 4) + padded.shape[2:]
    start = (il, ie) + (0,) * (padded.ndim - 2)
    block = lax.dynamic_slice(jnp.asarray(padded), start, size)
    return jnp.tensordot(wl, jnp.tensordot(we, block, axes=(0, 1)), axes=(0, 0))


class ShippedFiniteFilm(_TabulatedFilm):
    """`FiniteBearingFilm` on its default grid (`N_THETA` x `N_Z`, supply
    groove) for any motion of the journal centre, read from the tables
    shipped with the package: `DynamicFiniteFilm`'s dimensionless table
    g(eps, phi) built once at `SHIPPED_RATIOS` (21 L/D nodes, 0.05 to 4,
    log-spaced) up to eps = `SHIPPED_TOP` (0.998), interpolated in L/D by a
    Catmull-Rom cubic in log(L/D) (docs/notes/finite-film-table.md: its
    accuracy).  Nothing is solved at construction; the forces are
    differentiable in viscosity, clearance, length and radius (through
    K = 6 mu R^4 / c^2 and L/D).

    Arguments:
        film: the `FiniteBearingFilm` (its oil, length, bore, eps_max and
            saturation width; default grid and groove only: `DynamicFiniteFilm`
            tabulates others)
        radius: the journal radius R [m] (L / D = length / 2 R, in
            [0.05, 4])

    `InputError` for L/D outside the tables or an eps_max above their top
    (checked where the values are concrete).
    """

    radius: Float[Array, ""]

    def __init__(self, film: FiniteBearingFilm, radius):
        super().__init__(film.viscosity, film.length, film.clearance,
                         film.max_eccentricity_ratio, film.saturation_width)
        shipped = (N_THETA, N_Z, True, REYNOLDS)
        if (film.n_theta, film.n_z, film.supply_groove, film.cavitation) != shipped:
            raise InputError(
                f"the shipped finite-film tables hold the default grid and the Reynolds "
                f"condition only: n_theta = {film.n_theta}, n_z = {film.n_z}, supply_groove "
                f"= {film.supply_groove}, cavitation = {film.cavitation!r}; allowed: n_theta "
                f"= {N_THETA}, n_z = {N_Z}, supply_groove = True, cavitation = {REYNOLDS!r} "
                f"(DynamicFiniteFilm tabulates any grid and condition)")
        self.radius = jnp.asarray(radius, dtype=float)
        check_range("journal radius", self.radius, 0.0, low_open=True)
        ratio = concrete(film.length / (2.0 * self.radius))
        low, high = SHIPPED_RATIOS[0], SHIPPED_RATIOS[-1]
        if ratio is not None and not (low * (1 - 1e-9) <= float(ratio) <= high * (1 + 1e-9)):
            raise InputError(
                f"finite film length over diameter L/D = {float(ratio):.4g} is outside the "
                f"shipped tables; allowed: {low:g} <= L/D <= {high:g} (or DynamicFiniteFilm, "
                f"built for this L/D)")
        eps_max = concrete(film.max_eccentricity_ratio)
        if eps_max is not None and float(eps_max) > SHIPPED_TOP:
            raise InputError(
                f"finite film maximum eccentricity ratio = {float(eps_max):.6g} is above the "
                f"shipped tables' top; allowed: <= {SHIPPED_TOP} (or DynamicFiniteFilm with "
                f"a finer grid)")

    @property
    def length_over_diameter(self):
        """L / D = length / (2 R) [-]."""
        return self.length / (2.0 * self.radius)

    def _weights(self, eps):
        """The L/D and eps nodes and Catmull-Rom weights at this film's L/D and
        ``eps`` (`_cubic_weights`)."""
        nodes = np.log(SHIPPED_RATIOS)
        x = (jnp.log(self.length_over_diameter) - nodes[0]) / (nodes[1] - nodes[0])
        return (*_cubic_weights(x, len(SHIPPED_RATIOS)),
                *_cubic_weights(_node_coordinate(eps, SHIPPED_TOP, SHIPPED_ECCENTRICITY_NODES),
                                SHIPPED_ECCENTRICITY_NODES))

    def dimensionless_forces(self, eps, squeeze, wedge):
        """(F_n, F_t) / (6 mu R^4 / c^2) [-] (`reynolds_forces`' units) at
        eps, A = 2 eps_dot and B = eps (omega - 2 gamma_dot) [1/s]: log E and
        the scaled values g / E cubic in log(L/D) and w, then (as
        `DynamicFiniteFilm`) periodic cubic in phi."""
        log_envelope, scaled, _ = _padded_tables()
        weights = self._weights(eps)
        envelope = jnp.exp(_bicubic(log_envelope, *weights))
        column = _bicubic(scaled, *weights)  # (n_direction, 2)
        g_n, g_t = _along_directions(column, squeeze, wedge)
        return envelope * g_n, envelope * g_t

    def _log_peak(self, eps):
        """log max P of the steady film at B = 1, from the tables."""
        return _bicubic(_padded_tables()[2], *self._weights(eps))


def moving_film(film: FiniteBearingFilm, radius) -> AbstractFilm:
    """``film`` for any motion of the journal centre (squeeze and wedge),
    tabulated, for the journal radius ``radius``: on the default grid with
    the Reynolds condition the tables shipped with the package
    (`ShippedFiniteFilm`: nothing solved, L/D in [0.05, 4], eps_max <=
    0.998); on any other grid, or mass-conserving, a `DynamicFiniteFilm`
    built up to the film's eps_max (17 x 17 solves: seconds to minutes;
    traced, up to 0.995 or the grid's resolution)."""
    shipped = (N_THETA, N_Z, True, REYNOLDS)
    if (film.n_theta, film.n_z, film.supply_groove, film.cavitation) == shipped:
        return ShippedFiniteFilm(film, radius)
    eps_max = concrete(film.max_eccentricity_ratio)
    # traced (a derivative in the roughness or clearance): up to the mixed
    # law's largest saturation, 0.995 (mixed.MAX_SATURATION), or what the
    # grid resolves
    top = (min(0.995, film.resolved_eccentricity_ratio) if eps_max is None
           else float(eps_max))
    return DynamicFiniteFilm(film, radius, top_eccentricity_ratio=top)


def default_film(viscosity, length, clearance, radius,
                 max_eccentricity_ratio=MAX_ECCENTRICITY_RATIO) -> AbstractFilm:
    """The film a journal of ``radius`` [m] in a bushing of ``length`` [m] and
    radial ``clearance`` [m], run up to ``max_eccentricity_ratio``, gets by
    default (as a mechanism file's `lubricant` without `bearing`): the short
    (Ocvirk) film where it holds (`film_law_for`: (L/D)^2 <= 0.05 (1 -
    eps_max)), else the finite film from the shipped tables
    (`ShippedFiniteFilm`, L/D in [0.05, 4]).  ``viscosity`` [Pa s] may be
    traced (a derivative in the oil); the geometry decides the law and must
    be concrete.  For a lubricated joint, ``max_eccentricity_ratio`` is where
    its film saturates, `MixedLubrication.saturation(roughness, clearance)`."""
    geometry = [concrete(v) for v in (length, radius, max_eccentricity_ratio)]
    known = [float(v) for v in geometry if v is not None]
    if len(known) < len(geometry):
        raise InputError("default_film chooses its law from the bearing's L/D and "
                         "eps_max, which must be concrete numbers, not traced; name the "
                         "film (ShortBearingFilm, ShippedFiniteFilm) to trace them")
    length_, radius_, eps_max = known
    if film_law_for(length_ / (2.0 * radius_), eps_max) == "short":
        # as a file's short film (saturated by the mixed law, not by its own
        # eps_max): AbstractFilm's __init__, with its defaults, which the
        # dataclass view of ShortBearingFilm hides from a type checker
        short: type[AbstractFilm] = ShortBearingFilm
        return short(viscosity, length, clearance)
    return ShippedFiniteFilm(FiniteBearingFilm(viscosity, length, clearance,
                                               max_eccentricity_ratio=eps_max), radius)
