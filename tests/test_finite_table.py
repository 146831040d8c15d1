"""The tabulated finite film (`DynamicFiniteFilm`) against direct Reynolds
solves off the table's nodes (pure squeeze, pure wedge and the steady table,
mixed and reversed drives), the homogeneity and mirror symmetry it rests on,
and its derivatives (eps, A, B and the bearing length) against central
differences.  A coarse Reynolds grid (48 x 6) keeps the solves cheap; the
table is compared with solves on the same grid."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.contact import FiniteBearingFilm, PinKinematics
from diffwear.contact.finite_bearing import reynolds_forces
from diffwear.contact.finite_table import DynamicFiniteFilm
from diffwear.errors import InputError

# A plain journal bearing: R = 10 mm, c = 20 um, mu = 0.02 Pa s, L/D = 0.7.
MU, R, C, LD = 0.02, 0.010, 20e-6, 0.7
GRID = {"n_theta": 48, "n_z": 6}
# 13 eps nodes (w = sqrt(-ln(1 - eps)) step 0.144 up to eps = 0.95) by 16
# directions: 117 solves on the coarse grid.
TABLE = {"n_eccentricity": 13, "n_direction": 16}


def _film(length=2 * R * LD):
    return FiniteBearingFilm(MU, length, C, **GRID)


@pytest.fixture(scope="module")
def table():
    return eqx.filter_jit(lambda f: DynamicFiniteFilm(f, R, **TABLE))(_film())


@jax.jit
def _direct(eps, a, b):
    return jnp.stack(reynolds_forces(eps, a, b, LD, GRID["n_theta"], GRID["n_z"]))


@eqx.filter_jit
def _tabled(table, eps, a, b):
    return jnp.stack(table.dimensionless_forces(eps, a, b))


def _envelope(table, eps):
    """rms of |F| over the drive direction at eps (unit |(A, B)|), read from the
    table: the scale of the force where the film separates and |F| -> 0."""
    phi = jnp.linspace(0.0, 2 * jnp.pi, 64, endpoint=False)
    f = jax.vmap(lambda p: _tabled(table, eps, jnp.sin(p), jnp.cos(p)))(phi)
    return float(jnp.sqrt(jnp.mean(jnp.sum(f**2, axis=-1))))


# (eps, phi = atan2(A, B)) between the eps nodes: pure squeeze towards the bore
# (pi/2) and away (-pi/2), pure wedge (0), reversed wedge (pi), mixed drives
# off the direction nodes (spacing pi/8) too
CASES = [(0.37, 0.5 * np.pi), (0.81, 0.5 * np.pi), (0.5, -0.5 * np.pi),
         (0.23, 0.0), (0.66, 0.0), (0.93, 0.0), (0.66, np.pi),
         (0.44, 0.61), (0.74, 2.2), (0.9, -0.3), (0.58, -2.5), (0.87, 1.1)]


def test_table_reads_the_direct_solves_off_its_nodes(table):
    """To 2 % of |F| (of the envelope where the film separates, |F| < E / 4)."""
    for eps, phi in CASES:
        a, b = np.sin(phi), np.cos(phi)
        solved = np.asarray(_direct(eps, a, b))
        tabled = np.asarray(_tabled(table, jnp.asarray(eps), jnp.asarray(a), jnp.asarray(b)))
        scale = max(np.linalg.norm(solved), 0.25 * _envelope(table, eps))
        assert np.linalg.norm(tabled - solved) <= 0.02 * scale, (eps, phi, tabled, solved)


@eqx.filter_jit
def _films(a, b, kin):
    return a.film(kin).force, b.film(kin).force


def _kin(eps, rate, omega, angle=0.4):
    n = jnp.array([np.cos(angle), np.sin(angle)])
    return PinKinematics(offset=eps * C * n, offset_rate=jnp.asarray(rate, dtype=float),
                         omega=jnp.asarray(omega, dtype=float), pin_radius=jnp.asarray(R),
                         bushing_radius=jnp.asarray(R + C))


def test_the_film_interface_matches_the_solving_film(table):
    """`film` of the table and of `FiniteBearingFilm` for a moving centre
    (squeeze, whirl and spin together), to 2 % of |F|."""
    film = _film()
    for eps, rate, omega in [(0.62, (1e-4, -3e-4), 80.0), (0.85, (-2e-4, 1e-4), -40.0),
                             (0.3, (5e-4, 5e-4), 0.0)]:
        solved, tabled = _films(film, table, _kin(eps, rate, omega))
        assert float(jnp.linalg.norm(tabled - solved)) <= 0.02 * float(
            jnp.linalg.norm(solved)), (eps, rate, omega)


@pytest.mark.extended  # a second table (`SteadyFiniteFilm`'s 56 solves): ~20 s on 2 cores
def test_the_centre_at_rest_is_the_steady_table(table):
    """With e_dot = 0 the table's phi = 0 (and pi) column is `SteadyFiniteFilm`
    (an independent table: 56 solves, cubic in log |F|), to 1 %; and its peak
    pressure is the solving film's."""
    film = _film()
    steady = eqx.filter_jit(lambda f: f.steady(R))(film)
    for eps in [0.15, 0.52, 0.77, 0.91]:
        for omega in (100.0, -60.0):
            kin = _kin(eps, (0.0, 0.0), omega)
            tabled, stead = _films(table, steady, kin)
            assert float(jnp.linalg.norm(tabled - stead)) <= 0.01 * float(
                jnp.linalg.norm(stead)), (eps, omega)
        peak = eqx.filter_jit(lambda f, e: f.steady_peak_pressure(e, 100.0, R))
        assert float(peak(table, eps)) == pytest.approx(float(peak(film, eps)), rel=0.01)


def test_forces_are_homogeneous_and_mirror_symmetric_in_the_drive(table):
    """The properties the table rests on, of the direct solve: F(s A, s B) =
    s F(A, B) (s > 0) and F(A, -B) = (F_n, -F_t); and the table keeps both."""
    eps, a, b = 0.71, 0.8, -0.35
    base = np.asarray(_direct(eps, a, b))
    np.testing.assert_allclose(np.asarray(_direct(eps, 3.7 * a, 3.7 * b)), 3.7 * base,
                               rtol=1e-10)
    np.testing.assert_allclose(np.asarray(_direct(eps, a, -b)), base * [1, -1], rtol=1e-10)
    tb = np.asarray(_tabled(table, jnp.asarray(eps), jnp.asarray(a), jnp.asarray(b)))
    np.testing.assert_allclose(
        np.asarray(_tabled(table, jnp.asarray(eps), jnp.asarray(250 * a), jnp.asarray(250 * b))),
        250 * tb, rtol=1e-12)
    np.testing.assert_allclose(
        np.asarray(_tabled(table, jnp.asarray(eps), jnp.asarray(a), jnp.asarray(-b))),
        tb * [1, -1], rtol=1e-12)
    assert np.all(np.asarray(_tabled(table, jnp.asarray(0.5), jnp.asarray(0.0),
                                     jnp.asarray(0.0))) == 0.0)


def test_derivatives_in_the_state_match_central_differences(table):
    """d F / d(eps, A, B) of the interpolant against its central differences
    (1e-6), and against the direct solve's central differences (5 % of the
    largest: the table's slope between nodes)."""
    x = jnp.array([0.68, 0.45, 0.9])
    jac = np.asarray(jax.jacfwd(lambda x: _tabled(table, x[0], x[1], x[2]))(x))
    h = 1e-5
    for k in range(3):
        dx = jnp.zeros(3).at[k].set(h)
        fd = (np.asarray(_tabled(table, *(x + dx))) - np.asarray(_tabled(table, *(x - dx))))
        np.testing.assert_allclose(jac[:, k], fd / (2 * h), rtol=1e-6, atol=1e-9)
    hd = 2e-3
    for k in range(3):
        dx = jnp.zeros(3).at[k].set(hd)
        fd = (np.asarray(_direct(*(x + dx))) - np.asarray(_direct(*(x - dx)))) / (2 * hd)
        assert np.abs(jac[:, k] - fd).max() <= 0.05 * np.abs(fd).max(), (k, jac[:, k], fd)


def test_derivative_in_the_length_through_the_table():
    """d F / dL of a small table (built under the derivative) at one of its
    nodes, where it reads the solve, against central differences of the
    direct solve in L / D."""
    eps_node = float(-np.expm1(-(np.sqrt(-np.log(0.05)) * 2 / 4) ** 2))  # 3rd of 5 nodes
    a, b = np.sin(np.pi / 4), np.cos(np.pi / 4)  # a direction node of 8

    def force(length):
        t = DynamicFiniteFilm(_film(length), R, n_eccentricity=5, n_direction=8)
        return t.dimensionless_forces(jnp.asarray(eps_node), jnp.asarray(a), jnp.asarray(b))[0]

    length = 2 * R * LD
    grad = float(eqx.filter_jit(jax.grad(force))(jnp.asarray(length)))
    h = 1e-4
    fd = (float(_direct_ld(eps_node, a, b, LD + h)[0])
          - float(_direct_ld(eps_node, a, b, LD - h)[0])) / (2 * h) / (2 * R)
    assert grad == pytest.approx(fd, rel=1e-4)


@jax.jit
def _direct_ld(eps, a, b, ld):
    return jnp.stack(reynolds_forces(eps, a, b, ld, GRID["n_theta"], GRID["n_z"]))


def test_bad_table_options_are_input_errors():
    film = _film()
    with pytest.raises(InputError, match="n_direction must be a multiple of 4"):
        DynamicFiniteFilm(film, R, n_direction=10)
    with pytest.raises(InputError, match="n_eccentricity"):
        DynamicFiniteFilm(film, R, n_eccentricity=2)
    with pytest.raises(InputError, match="top_eccentricity_ratio = 0.9 is below"):
        DynamicFiniteFilm(film, R, top_eccentricity_ratio=0.9)
