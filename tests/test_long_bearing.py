"""The long-bearing hydrodynamic film (`LongBearingFilm`) against the steady
half-Sommerfeld closed forms, a quadrature of its Reynolds pressure field with
Gumbel cavitation, a finite-difference solution of the Reynolds equation, its
scaling laws and finite-difference derivatives."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import sparse
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.sparse.linalg import spsolve

from diffwear.contact import PinKinematics, ShortBearingFilm
from diffwear.contact.long_bearing import LongBearingFilm

# A long plain bearing: R = 10 mm, L = 80 mm (L/D = 4), c = 50 um, an SAE 30
# oil near 60 C (mu ~ 0.04 Pa s).
MU, R, L, C = 0.04, 0.010, 0.080, 50e-6
K_L = 6 * MU * R**3 * L / C**2  # 6 mu R^3 L / c^2


def _kin(offset, rate=(0.0, 0.0), omega=100.0, radius=R, clearance=C):
    return PinKinematics(offset=jnp.asarray(offset, dtype=float),
                         offset_rate=jnp.asarray(rate, dtype=float),
                         omega=jnp.asarray(omega, dtype=float),
                         pin_radius=jnp.asarray(radius, dtype=float),
                         bushing_radius=jnp.asarray(radius + clearance, dtype=float))


def _polar(eps, angle, clearance=C):
    return clearance * eps * np.array([np.cos(angle), np.sin(angle)])


def test_x64_is_on():
    assert jnp.zeros(1).dtype == jnp.float64


@pytest.mark.parametrize("eps", [0.0, 0.35, 0.9])
@pytest.mark.parametrize("psi_1", [-3.0, -1.2, 0.4, 2.5])
def test_half_film_cos_integral_matches_quadrature(eps, psi_1):
    from diffwear.contact.long_bearing import _half_film_cos

    closed = _half_film_cos(jnp.asarray(eps), jnp.cos(psi_1), jnp.sin(psi_1))
    ref = quad(lambda p: np.cos(p) / (1 - eps * np.cos(p)) ** 3, psi_1, psi_1 + np.pi,
               epsabs=1e-13, epsrel=1e-12, limit=200)[0]
    assert float(closed) == pytest.approx(ref, rel=1e-10, abs=1e-12)


# ---------------------------------------------------------------- steady journal

def _half_sommerfeld(eps, omega):
    """(W_r, W_t): the steady half-Sommerfeld load components of the infinitely
    long bearing (Hamrock, Schmid & Jacobson), U = omega R:
    W_r = 12 mu omega R^3 L eps^2 / (c^2 (2 + eps^2) (1 - eps^2)),
    W_t = 6 pi mu omega R^3 L eps / (c^2 (2 + eps^2) sqrt(1 - eps^2))."""
    w_r = 12 * MU * omega * R**3 * L * eps**2 / (C**2 * (2 + eps**2) * (1 - eps**2))
    w_t = 6 * np.pi * MU * omega * R**3 * L * eps / (C**2 * (2 + eps**2) * np.sqrt(1 - eps**2))
    return w_r, w_t


@pytest.mark.parametrize("eps", [0.2, 0.6, 0.9])
def test_half_sommerfeld_closed_forms_are_the_integrals_of_the_textbook_pressure(eps):
    """The reference itself, checked: the textbook Sommerfeld pressure
    p = 6 mu omega R^2 eps sin(th) (2 + eps cos th) / (c^2 (2 + eps^2) (1 + eps cos th)^2)
    (th from the maximum film) integrated over its positive half 0 < th < pi."""
    omega = 120.0

    def p(th):
        return (6 * MU * omega * R**2 * eps * np.sin(th) * (2 + eps * np.cos(th))
                / (C**2 * (2 + eps**2) * (1 + eps * np.cos(th)) ** 2))

    along = R * L * quad(lambda th: p(th) * np.cos(th), 0, np.pi, epsrel=1e-13, limit=200)[0]
    across = R * L * quad(lambda th: p(th) * np.sin(th), 0, np.pi, epsrel=1e-13, limit=200)[0]
    w_r, w_t = _half_sommerfeld(eps, omega)
    assert abs(along) == pytest.approx(w_r, rel=1e-10)
    assert abs(across) == pytest.approx(w_t, rel=1e-10)


@pytest.mark.parametrize("eps", np.linspace(0.1, 0.9, 9))
def test_steady_load_and_attitude_match_the_half_sommerfeld_closed_forms(eps):
    """W = sqrt(W_r^2 + W_t^2), tan phi = pi sqrt(1 - eps^2) / (2 eps)."""
    omega, gamma = 120.0, 0.7
    film = LongBearingFilm(MU, L, C).film(_kin(_polar(eps, gamma), omega=omega))
    w_r, w_t = _half_sommerfeld(eps, omega)
    assert float(jnp.linalg.norm(film.force)) == pytest.approx(np.hypot(w_r, w_t), rel=1e-10)
    # the film pushes the pin back towards the centre and ahead of the line of
    # centres in the sense of rotation
    assert float(film.radial) == pytest.approx(-w_r, rel=1e-10)
    assert float(film.tangential) == pytest.approx(w_t, rel=1e-10)
    tan_phi = np.pi * np.sqrt(1 - eps**2) / (2 * eps)
    assert float(film.tangential / -film.radial) == pytest.approx(tan_phi, rel=1e-10)
    n = np.array([np.cos(gamma), np.sin(gamma)])
    assert np.asarray(film.force) @ n == pytest.approx(float(film.radial), rel=1e-12)
    assert float(film.eccentricity_ratio) == pytest.approx(eps, rel=1e-12)
    assert float(film.min_film_thickness) == pytest.approx(C * (1 - eps), rel=1e-9)


def test_centred_journal_gives_petroff_torque_and_no_load():
    film = LongBearingFilm(MU, L, C).film(_kin([0.0, 0.0], omega=80.0))
    assert np.all(np.asarray(film.force) == 0.0)
    assert float(film.torque) == pytest.approx(-2 * np.pi * MU * 80.0 * R**3 * L / C, rel=1e-12)


# ------------------------------------------------- second method: quadrature

def _source(theta, e, ed, omega):
    """omega dh/dtheta + 2 dh/dt at the bushing angles theta (h = c - e . u)."""
    u = np.stack([np.cos(theta), np.sin(theta)], -1)
    du = np.stack([-np.sin(theta), np.cos(theta)], -1)
    return omega * (-du @ e) + 2 * (-u @ ed)


def _sommerfeld_pressure(theta, e, ed, omega):
    """The derived periodic long-bearing pressure (no cavitation), in the
    bushing frame: 6 mu R^2 (c + h) (V_L . u) / ((2 c^2 + |e|^2) h^2),
    V_L = 2 e_dot + (e . e_dot) e / c^2 - omega k x e."""
    u = np.stack([np.cos(theta), np.sin(theta)], -1)
    h = C - u @ e
    v_l = 2 * ed + (e @ ed) * e / C**2 - omega * np.array([-e[1], e[0]])
    return 6 * MU * R**2 * (C + h) * (u @ v_l) / ((2 * C**2 + e @ e) * h**2)


def _quadrature(offset, rate, omega):
    """Force and torque on the pin from the pressure field, Gumbel-cavitated
    (p set to 0 where negative), integrated numerically.  The positive intervals
    are found from sign changes of p on a grid, refined by root finding, and
    each is integrated by adaptive quadrature.  Torque: -R^2 L int [mu omega R / h
    + h / (2R) dp/dtheta] dtheta, the Couette part over the whole circumference,
    the Poiseuille part by parts over the positive intervals (p = 0 at their
    ends): -int p dh/dtheta.  Returns (force, torque, positive intervals)."""
    e, ed = np.asarray(offset, float), np.asarray(rate, float)

    def p(theta):
        return _sommerfeld_pressure(np.asarray(theta), e, ed, omega)

    grid = np.linspace(0.0, 2 * np.pi, 721)
    g = p(grid)
    roots = [brentq(p, a, b, xtol=1e-15, rtol=1e-15)
             for a, b, ga, gb in zip(grid[:-1], grid[1:], g[:-1], g[1:]) if ga * gb < 0]
    if not roots:
        return np.zeros(2), 0.0, []
    ends = roots + [roots[0] + 2 * np.pi]
    intervals = [(a, b) for a, b in zip(ends[:-1], ends[1:]) if p(0.5 * (a + b)) > 0]
    force = np.zeros(2)
    poiseuille = 0.0
    opts = dict(epsabs=0.0, epsrel=1e-12, limit=400)
    for a, b in intervals:
        force[0] -= R * L * quad(lambda th: p(th) * np.cos(th), a, b, **opts)[0]
        force[1] -= R * L * quad(lambda th: p(th) * np.sin(th), a, b, **opts)[0]
        # dh/dtheta = -e . u'(theta)
        # (zero in a pure squeeze along e: an absolute tolerance, far below the
        # Couette part's R mu omega R L 2 pi / c ~ 1e-2 N m per rad/s)
        poiseuille -= L * quad(lambda th: p(th) * (e[0] * np.sin(th) - e[1] * np.cos(th)),
                               a, b, epsabs=1e-12, epsrel=1e-12, limit=400)[0]
    couette = MU * omega * R * L * quad(lambda th: 1 / (C - e @ [np.cos(th), np.sin(th)]),
                                        0, 2 * np.pi, **opts)[0]
    torque = -R**2 * couette - R * poiseuille / 2
    return force, torque, intervals


CASES = [
    # (eps, line-of-centres angle, e_dot [m/s], omega [rad/s])
    pytest.param(0.5, 0.3, (0.0, 0.0), 150.0, id="steady"),
    pytest.param(0.6, 1.1, 0.6 * 50e-6 * 40.0 * np.array([-np.sin(1.1), np.cos(1.1)]), 150.0,
                 id="whirl-at-a-third-of-omega"),
    pytest.param(0.4, -0.5, 2e-3 * np.array([np.cos(-0.5), np.sin(-0.5)]), 0.0,
                 id="pure-squeeze-approach"),
    pytest.param(0.7, 2.0, -1e-3 * np.array([np.cos(2.0), np.sin(2.0)]), 0.0,
                 id="pure-squeeze-recede"),
    pytest.param(0.8, 2.5, (1.5e-3, -0.7e-3), 90.0, id="squeeze-and-wedge"),
    pytest.param(0.9, -2.2, (-0.3e-3, 0.2e-3), -60.0, id="reverse-spin-high-eps"),
    pytest.param(0.3, 0.9, (4e-3, 1e-3), 20.0, id="squeeze-dominated"),
    pytest.param(0.0, 0.0, (1e-3, -2e-3), 70.0, id="centred-moving"),
]


@pytest.mark.parametrize("eps, angle, rate, omega", CASES)
def test_force_and_torque_match_quadrature_of_the_pressure_field(eps, angle, rate, omega):
    e = _polar(eps, angle)
    ref_force, ref_torque, intervals = _quadrature(e, rate, omega)
    film = LongBearingFilm(MU, L, C).film(_kin(e, rate, omega))
    force = np.asarray(film.force)
    assert np.linalg.norm(force - ref_force) <= 1e-6 * np.linalg.norm(ref_force)
    assert float(film.torque) == pytest.approx(ref_torque, rel=1e-6)
    # with the pressure level chosen (zero at the ends of a half), the region of
    # positive pressure found numerically is one half of the film
    assert len(intervals) == 1
    assert intervals[0][1] - intervals[0][0] == pytest.approx(np.pi, abs=1e-9)


def test_pressure_solves_the_reynolds_equation_by_finite_differences():
    """A non-steady state (squeeze, whirl and spin): the periodic Reynolds
    equation d/dtheta (h^3 dp/dtheta) = 6 mu R^2 (omega dh/dtheta + 2 dh/dt),
    discretised with second-order central differences on 4000 nodes and solved
    with a zero mean (the equation fixes p up to a constant), against the derived
    pressure less its mean."""
    e, ed, omega = _polar(0.7, 0.4), np.array([1.2e-3, -0.8e-3]), 110.0
    n = 4000
    d = 2 * np.pi / n
    theta = d * np.arange(n)
    h_half = (C - np.stack([np.cos(theta + d / 2), np.sin(theta + d / 2)], -1) @ e) ** 3
    h_half /= C**3  # (h / c)^3: entries of order 1 / d^2
    idx = np.arange(n)
    # (h3_{i+1/2} (p_{i+1} - p_i) - h3_{i-1/2} (p_i - p_{i-1})) / d^2, periodic,
    # bordered with the zero-mean condition (a Lagrange multiplier) to fix p's level
    rows = np.concatenate([idx, idx, idx, np.full(n, n), idx])
    cols = np.concatenate([(idx + 1) % n, idx, (idx - 1) % n, idx, np.full(n, n)])
    vals = np.concatenate([h_half, -(h_half + np.roll(h_half, 1)), np.roll(h_half, 1),
                           np.ones(n), np.ones(n)]) / d**2
    a = sparse.csc_matrix((vals, (rows, cols)), shape=(n + 1, n + 1))
    rhs = np.append(6 * MU * R**2 * _source(theta, e, ed, omega) / C**3, 0.0)
    p_fd = spsolve(a, rhs)[:n]
    p_closed = _sommerfeld_pressure(theta, e, ed, omega)
    p_closed -= p_closed.mean()
    assert np.max(np.abs(p_fd - p_closed)) <= 1e-5 * np.max(np.abs(p_closed))


@pytest.mark.parametrize("eps", [0.2, 0.5, 0.85])
def test_whirl_without_squeeze_gives_the_dynamic_long_bearing_forces(eps):
    """eps_dot = 0: the steady forces with the wedge speed omega - 2 gamma_dot,
    F_n = -2 K_L eps^2 (omega - 2 gamma_dot) / ((2 + eps^2) (1 - eps^2)),
    F_t = K_L pi eps (omega - 2 gamma_dot) / ((2 + eps^2) sqrt(1 - eps^2));
    nothing at half-frequency whirl; and the line-of-centres form matches
    the offset form."""
    law = LongBearingFilm(MU, L, C)
    omega, gamma_dot = 140.0, 25.0
    wedge = omega - 2 * gamma_dot
    radial, tangential, torque = law.line_of_centres_forces(eps, 0.0, gamma_dot, omega, R)
    assert float(radial) == pytest.approx(
        -2 * K_L * eps**2 * wedge / ((2 + eps**2) * (1 - eps**2)), rel=1e-12)
    assert float(tangential) == pytest.approx(
        K_L * np.pi * eps * wedge / ((2 + eps**2) * np.sqrt(1 - eps**2)), rel=1e-12)
    angle = 0.9
    e = _polar(eps, angle)
    rate = gamma_dot * np.linalg.norm(e) * np.array([-np.sin(angle), np.cos(angle)])
    film = law.film(_kin(e, rate, omega))
    assert float(film.radial) == pytest.approx(float(radial), rel=1e-12)
    assert float(film.tangential) == pytest.approx(float(tangential), rel=1e-12)
    assert float(film.torque) == pytest.approx(float(torque), rel=1e-12)
    radial, tangential, _ = law.line_of_centres_forces(eps, 0.0, omega / 2, omega, R)
    assert float(radial) == 0.0 and float(tangential) == 0.0


def test_centred_squeeze_is_an_isotropic_damper():
    """At e = 0: F = -pi K_L e_dot / c = -6 pi mu R^3 L e_dot / c^3, whatever the
    spin (12 (R / L)^2 times the short bearing's -pi mu R L^3 e_dot / (2 c^3))."""
    rate = np.array([1e-3, -2e-3])
    film = LongBearingFilm(MU, L, C).film(_kin([0.0, 0.0], rate, 70.0))
    np.testing.assert_allclose(np.asarray(film.force), -np.pi * K_L * rate / C, rtol=1e-12)
    short = ShortBearingFilm(MU, L, C).film(_kin([0.0, 0.0], rate, 70.0))
    np.testing.assert_allclose(np.asarray(film.force),
                               12 * (R / L) ** 2 * np.asarray(short.force), rtol=1e-12)


# ---------------------------------------------------------------- scaling laws

STATE = dict(eps=0.55, angle=1.3, rate_over_c=np.array([8.0, -5.0]), omega=110.0)


def _film(mu=MU, length=L, clearance=C, radius=R, omega=STATE["omega"]):
    e = _polar(STATE["eps"], STATE["angle"], clearance)
    rate = STATE["rate_over_c"] * clearance  # fixed eps_dot, eps gamma_dot
    return LongBearingFilm(mu, length, clearance).film(
        _kin(e, rate, omega, radius=radius, clearance=clearance))


def test_force_scales_with_viscosity_length_radius_cubed_and_clearance_squared():
    """At fixed eps, eps_dot, eps gamma_dot and omega: F ~ mu R^3 L / c^2 (R^2
    from the wedge and squeeze terms of the Reynolds equation, R L from the area)."""
    base = np.asarray(_film().force)
    np.testing.assert_allclose(np.asarray(_film(mu=3 * MU).force), 3 * base, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(_film(length=2 * L).force), 2 * base, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(_film(radius=1.5 * R).force), 1.5**3 * base,
                               rtol=1e-12)
    np.testing.assert_allclose(np.asarray(_film(clearance=2 * C).force), base / 4, rtol=1e-12)


def test_reversing_the_spin_reverses_the_tangential_force_and_the_torque():
    e = _polar(0.6, 0.4)
    law = LongBearingFilm(MU, L, C)
    fwd, back = law.film(_kin(e, omega=90.0)), law.film(_kin(e, omega=-90.0))
    assert float(back.tangential) == pytest.approx(-float(fwd.tangential), rel=1e-12)
    assert float(back.radial) == pytest.approx(float(fwd.radial), rel=1e-12)
    assert float(back.torque) == pytest.approx(-float(fwd.torque), rel=1e-12)


@pytest.mark.parametrize("eps", [0.1, 0.5, 0.8])
def test_long_bearing_carries_less_than_the_short_one_when_long_and_more_when_short(eps):
    """Each theory overestimates the load outside its range (the finite bearing
    carries less than either), so at the same state the short-bearing load,
    ~ L^3, exceeds the long-bearing one, ~ L R^2, for a long bearing (L/D = 4)
    and falls below it for a short one (L/D = 0.2)."""
    e, rate, omega = _polar(eps, 0.5), (0.4e-3, -0.3e-3), 100.0
    for l_over_d, long_is_larger in [(4.0, False), (0.2, True)]:
        length = 2 * R * l_over_d
        kin = _kin(e, rate, omega)
        long_load = float(jnp.linalg.norm(LongBearingFilm(MU, length, C).film(kin).force))
        short_load = float(jnp.linalg.norm(ShortBearingFilm(MU, length, C).film(kin).force))
        assert (long_load > short_load) == long_is_larger, (l_over_d, long_load, short_load)


def test_film_reads_clearance_and_eps_max_from_its_leaves():
    """A mixed-lubrication law swaps the clearance and eps_max leaves with
    eqx.tree_at: the film must follow them (no cached constants)."""
    kin = _kin(_polar(0.5, 0.3, 2 * C), (1e-3, 0.0), 100.0)
    swapped = eqx.tree_at(lambda m: (m.clearance, m.max_eccentricity_ratio),
                          LongBearingFilm(MU, L, C), (jnp.asarray(2 * C), jnp.asarray(0.9)))
    fresh = LongBearingFilm(MU, L, 2 * C, max_eccentricity_ratio=0.9)
    np.testing.assert_array_equal(np.asarray(swapped.film(kin).force),
                                  np.asarray(fresh.film(kin).force))


# ---------------------------------------------------------------- derivatives
# (the derivatives both films share, at the centre too: tests/test_films.py)

def test_parameters_are_float64_leaves_with_exact_module_gradients():
    """Reverse mode through the module's leaves: F is linear in mu and in L and
    ~ 1 / c^2 at fixed offset plus the eps dependence, so dF/dmu = F / mu,
    dF/dL = F / L, and dF/dc against a central difference."""
    law = LongBearingFilm(MU, L, C)
    assert all(np.asarray(leaf).dtype == np.float64 for leaf in jax.tree_util.tree_leaves(law))
    kin = _kin(_polar(0.45, 0.6), (0.5e-3, -1e-3), 85.0)
    grads = eqx.filter_grad(lambda m: m.film(kin).force[1])(law)
    force_y = float(law.film(kin).force[1])
    assert float(grads.viscosity) == pytest.approx(force_y / MU, rel=1e-12)
    assert float(grads.length) == pytest.approx(force_y / L, rel=1e-12)
    h = 1e-6 * C
    fd = (float(LongBearingFilm(MU, L, C + h).film(kin).force[1])
          - float(LongBearingFilm(MU, L, C - h).film(kin).force[1])) / (2 * h)
    assert float(grads.clearance) == pytest.approx(fd, rel=1e-6)
