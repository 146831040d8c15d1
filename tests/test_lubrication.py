"""The short-bearing hydrodynamic film (`ShortBearingFilm`) against the steady
closed forms, a quadrature of the Reynolds pressure field with Gumbel
cavitation, its scaling laws and finite-difference derivatives."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

from diffwear.contact import PinKinematics, ShortBearingFilm
from diffwear.contact.long_bearing import LongBearingFilm

# A connecting-rod-like pin: R = 10 mm, L = 8 mm (L/D = 0.4, short bearing),
# c = 50 um, an SAE 30 oil near 60 C (mu ~ 0.04 Pa s).
MU, R, L, C = 0.04, 0.010, 0.008, 50e-6


def _kin(offset, rate=(0.0, 0.0), omega=100.0, radius=R, clearance=C):
    return PinKinematics(offset=jnp.asarray(offset, dtype=float),
                         offset_rate=jnp.asarray(rate, dtype=float),
                         omega=jnp.asarray(omega, dtype=float),
                         pin_radius=jnp.asarray(radius, dtype=float),
                         bushing_radius=jnp.asarray(radius + clearance, dtype=float))


def _polar(eps, angle, clearance=C):
    return clearance * eps * np.array([np.cos(angle), np.sin(angle)])


@pytest.mark.parametrize("eps", [0.0, 0.35, 0.9])
@pytest.mark.parametrize("psi_1", [-3.0, -1.2, 0.4, 2.5])
def test_half_film_integrals_match_quadrature(eps, psi_1):
    """The closed forms of the three integrals over a half psi_1 .. psi_1 + pi
    (including halves across psi = pi, where the textbook atan form jumps)."""
    from scipy.integrate import quad

    from diffwear.contact.lubrication import _half_film_integrals

    closed = _half_film_integrals(jnp.asarray(eps), jnp.cos(psi_1), jnp.sin(psi_1))
    for value, (f, g) in zip(closed, [(np.cos, np.cos), (np.sin, np.cos), (np.sin, np.sin)]):
        ref = quad(lambda p: f(p) * g(p) / (1 - eps * np.cos(p)) ** 3, psi_1, psi_1 + np.pi,
                   epsabs=1e-11, epsrel=1e-12, limit=200)[0]
        assert float(value) == pytest.approx(ref, rel=1e-10, abs=1e-12)


# ---------------------------------------------------------------- steady journal

@pytest.mark.parametrize("eps", np.linspace(0.1, 0.9, 9))
def test_steady_load_and_attitude_match_the_short_bearing_closed_forms(eps):
    """Line of centres fixed, journal spinning: W and phi of the short-width
    journal bearing (Hamrock, Schmid & Jacobson):
    W = mu U L^3 eps / (4 c^2 (1-eps^2)^2) sqrt(16 eps^2 + pi^2 (1-eps^2)),
    tan phi = pi sqrt(1-eps^2) / (4 eps), U = omega R."""
    omega, gamma = 120.0, 0.7
    film = ShortBearingFilm(MU, L, C).film(_kin(_polar(eps, gamma), omega=omega))
    u = omega * R
    w_ref = (MU * u * L**3 * eps / (4 * C**2 * (1 - eps**2) ** 2)
             * np.sqrt(16 * eps**2 + np.pi**2 * (1 - eps**2)))
    tan_phi_ref = np.pi * np.sqrt(1 - eps**2) / (4 * eps)
    load = float(jnp.linalg.norm(film.force))
    assert load == pytest.approx(w_ref, rel=1e-10)
    # the film pushes the pin back towards the centre and ahead of the line of
    # centres in the sense of rotation
    assert float(film.radial) < 0 and float(film.tangential) > 0
    assert float(film.tangential / -film.radial) == pytest.approx(tan_phi_ref, rel=1e-10)
    # the components are those along n = e/|e| and t = k x n
    n = np.array([np.cos(gamma), np.sin(gamma)])
    assert np.asarray(film.force) @ n == pytest.approx(float(film.radial), rel=1e-12)
    assert float(film.eccentricity_ratio) == pytest.approx(eps, rel=1e-12)
    assert float(film.min_film_thickness) == pytest.approx(C * (1 - eps), rel=1e-9)


def test_centred_journal_gives_petroff_torque_and_no_load():
    film = ShortBearingFilm(MU, L, C).film(_kin([0.0, 0.0], omega=80.0))
    assert np.all(np.asarray(film.force) == 0.0)
    # Petroff: T = -2 pi mu omega R^3 L / c on the pin (opposing its spin)
    assert float(film.torque) == pytest.approx(-2 * np.pi * MU * 80.0 * R**3 * L / C, rel=1e-12)


# ------------------------------------------------- second method: quadrature

def _quadrature(offset, rate, omega, n_panel=60, n_gauss=24):
    """Force and torque on the pin from the short-bearing pressure p(theta, z),
    integrated numerically in the bushing frame.  h = c - e . u(theta);
    h_theta = -e . u'(theta); h_t = -e_dot . u(theta);
    d/dz(h^3 dp/dz) = 6 mu (omega h_theta + 2 h_t), p(+-L/2) = 0, so
    p = -3 mu (omega h_theta + 2 h_t) (L^2/4 - z^2) / h^3, set to 0 where negative.
    The positive intervals are found from sign changes on a grid, their ends
    refined by root finding, and each is integrated by composite Gauss-Legendre
    in theta times 4-point Gauss-Legendre in z.  Returns (force, torque,
    positive intervals)."""
    e, ed = np.asarray(offset, float), np.asarray(rate, float)

    def parts(theta):
        u = np.stack([np.cos(theta), np.sin(theta)], -1)
        du = np.stack([-np.sin(theta), np.cos(theta)], -1)
        h = C - u @ e
        h_theta = -du @ e
        h_t = -u @ ed
        return u, h, h_theta, h_t

    def source(theta):  # omega h_theta + 2 h_t: p > 0 where it is < 0
        _, _, h_theta, h_t = parts(np.asarray(theta))
        return omega * h_theta + 2 * h_t

    grid = np.linspace(0.0, 2 * np.pi, 721)
    g = source(grid)
    roots = [brentq(source, a, b, xtol=1e-15, rtol=1e-15)
             for a, b, ga, gb in zip(grid[:-1], grid[1:], g[:-1], g[1:]) if ga * gb < 0]
    if not roots:
        return np.zeros(2), 0.0, []
    # intervals between consecutive roots (periodic) where the source is negative
    ends = roots + [roots[0] + 2 * np.pi]
    intervals = [(a, b) for a, b in zip(ends[:-1], ends[1:]) if source(0.5 * (a + b)) < 0]

    xg, wg = np.polynomial.legendre.leggauss(n_gauss)
    zg, wz = np.polynomial.legendre.leggauss(4)
    z, wz = 0.5 * L * zg, 0.5 * L * wz
    force = np.zeros(2)
    poiseuille = 0.0
    for a, b in intervals:
        edges = np.linspace(a, b, n_panel + 1)
        mid, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
        theta = (mid[:, None] + half[:, None] * xg).ravel()
        w_theta = (half[:, None] * wg).ravel()
        u, h, h_theta, h_t = parts(theta)
        p = -3 * MU * (omega * h_theta + 2 * h_t)[:, None] * (L**2 / 4 - z**2) / h[:, None] ** 3
        p_axial = p @ wz  # integral over z
        force -= R * (w_theta * p_axial) @ u
        # Poiseuille shear (h / 2R) dp/dtheta integrated by parts over the
        # positive interval (p = 0 at its ends): -int p dh/dtheta
        poiseuille += -(w_theta * p_axial) @ h_theta
    # shear moment on the pin: -R^2 int [mu omega R / h + h/(2R) dp/dtheta] dtheta dz,
    # the Couette part over the whole (periodic) circumference by the trapezoid rule
    theta = np.linspace(0.0, 2 * np.pi, 4001)[:-1]
    _, h, _, _ = parts(theta)
    couette = MU * omega * R * L * np.mean(1.0 / h) * 2 * np.pi
    torque = -R**2 * couette - R**2 * poiseuille / (2 * R)
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
    film = ShortBearingFilm(MU, L, C).film(_kin(e, rate, omega))
    force = np.asarray(film.force)
    assert np.linalg.norm(force - ref_force) <= 1e-6 * np.linalg.norm(ref_force)
    assert float(film.torque) == pytest.approx(ref_torque, rel=1e-6)
    # the positive-pressure region found numerically is one half of the film
    assert len(intervals) == 1
    assert intervals[0][1] - intervals[0][0] == pytest.approx(np.pi, abs=1e-9)


def test_pure_squeeze_presses_on_the_half_facing_the_approach():
    """omega = 0, eps_dot > 0: the positive region is centred on the direction
    of e_dot (here along e: the half around the minimum film), and the film
    resists the approach (force against e_dot)."""
    angle = 0.8
    n = np.array([np.cos(angle), np.sin(angle)])
    _, _, intervals = _quadrature(_polar(0.5, angle), 1e-3 * n, 0.0)
    (a, b), = intervals
    assert np.mod(0.5 * (a + b) - angle + np.pi, 2 * np.pi) - np.pi == pytest.approx(0, abs=1e-9)
    film = ShortBearingFilm(MU, L, C).film(_kin(_polar(0.5, angle), 1e-3 * n, 0.0))
    assert float(film.radial) < 0 and float(film.tangential) == pytest.approx(0, abs=1e-9)


def test_centred_squeeze_is_an_isotropic_damper():
    """At e = 0 (eps = 0) the film is the centred squeeze damper
    F = -pi mu R L^3 e_dot / (2 c^3), whatever the spin (from the pressure at
    eps = 0: F = -K pi e_dot / c, K = mu R L^3 / (2 c^2))."""
    rate = np.array([1e-3, -2e-3])
    film = ShortBearingFilm(MU, L, C).film(_kin([0.0, 0.0], rate, 70.0))
    ref = -np.pi * MU * R * L**3 * rate / (2 * C**3)
    np.testing.assert_allclose(np.asarray(film.force), ref, rtol=1e-12)


@pytest.mark.parametrize("eps", [0.65, 1.2])
def test_line_of_centres_form_matches_the_offset_form(eps):
    """Also past eps_max (1.2): both evaluate the film at eps_max with the same
    centre velocity."""
    angle, rate, omega = -1.4, np.array([0.8e-3, 1.9e-3]), 75.0
    e = _polar(eps, angle)
    n = e / np.linalg.norm(e)
    eps_dot = n @ rate / C
    gamma_dot = (n[0] * rate[1] - n[1] * rate[0]) / np.linalg.norm(e)
    law = ShortBearingFilm(MU, L, C)
    radial, tangential, torque = law.line_of_centres_forces(eps, eps_dot, gamma_dot, omega, R)
    film = law.film(_kin(e, rate, omega))
    assert float(radial) == pytest.approx(float(film.radial), rel=1e-12)
    assert float(tangential) == pytest.approx(float(film.tangential), rel=1e-12)
    assert float(torque) == pytest.approx(float(film.torque), rel=1e-12)


@pytest.mark.parametrize("eps", [0.2, 0.5, 0.85])
def test_whirl_without_squeeze_gives_the_classical_dynamic_forces(eps):
    """eps_dot = 0, gamma_dot != 0: the positive half is the steady one (for
    omega - 2 gamma_dot > 0) and the forces are the short-bearing dynamic forces
    with the wedge speed omega - 2 gamma_dot:
    F_n = -2 K eps^2 (omega - 2 gamma_dot) / (1 - eps^2)^2,
    F_t = K pi eps (omega - 2 gamma_dot) / (2 (1 - eps^2)^(3/2)), K = mu R L^3 / (2 c^2);
    at gamma_dot = omega / 2 (half-frequency whirl) the film carries nothing."""
    law = ShortBearingFilm(MU, L, C)
    k = MU * R * L**3 / (2 * C**2)
    omega, gamma_dot = 140.0, 25.0
    wedge = omega - 2 * gamma_dot
    radial, tangential, _ = law.line_of_centres_forces(eps, 0.0, gamma_dot, omega, R)
    assert float(radial) == pytest.approx(-2 * k * eps**2 * wedge / (1 - eps**2) ** 2, rel=1e-12)
    assert float(tangential) == pytest.approx(
        k * np.pi * eps * wedge / (2 * (1 - eps**2) ** 1.5), rel=1e-12)
    radial, tangential, _ = law.line_of_centres_forces(eps, 0.0, omega / 2, omega, R)
    assert float(radial) == 0.0 and float(tangential) == 0.0


@pytest.mark.parametrize("eps", [0.0, 0.4, 0.8])
def test_pure_squeeze_force_is_the_integral_over_the_approach_half(eps):
    """omega = gamma_dot = 0, eps_dot > 0: p > 0 on -pi/2 < psi < pi/2, so
    F_n = -2 K eps_dot int cos^2 psi / (1 - eps cos psi)^3 over that half
        = -2 K eps_dot [3 eps / beta^4 + (1 + 2 eps^2) (pi + 4 atan(eps / (1 + beta)))
                        / (2 beta^5)],  beta = sqrt(1 - eps^2),
    (the antiderivative of `_half_film_integrals`), checked against quadrature
    too, and more than the steady half's pi (1 + 2 eps^2) / (2 beta^5) for
    eps > 0: the approach half holds the thin film."""
    law = ShortBearingFilm(MU, L, C)
    k = MU * R * L**3 / (2 * C**2)
    eps_dot = 30.0
    beta = np.sqrt(1 - eps**2)
    integral = (3 * eps / beta**4
                + (1 + 2 * eps**2) * (np.pi + 4 * np.arctan(eps / (1 + beta))) / (2 * beta**5))
    radial, tangential, _ = law.line_of_centres_forces(eps, eps_dot, 0.0, 0.0, R)
    assert float(radial) == pytest.approx(-2 * k * eps_dot * integral, rel=1e-12)
    assert float(tangential) == pytest.approx(0.0, abs=1e-12 * abs(float(radial)))
    numeric = _quadrature(_polar(eps, 0.0) if eps > 0 else np.zeros(2),
                          (eps_dot * C, 0.0), 0.0)[0][0]
    assert float(radial) == pytest.approx(numeric, rel=1e-6)
    steady_half = np.pi * (1 + 2 * eps**2) / (2 * beta**5)
    if eps > 0:
        assert integral > steady_half
    else:
        assert integral == pytest.approx(steady_half, rel=1e-14)


# ---------------------------------------------------------------- scaling laws

STATE = dict(eps=0.55, angle=1.3, rate_over_c=np.array([8.0, -5.0]), omega=110.0)


def _film(mu=MU, length=L, clearance=C, radius=R, omega=STATE["omega"]):
    e = _polar(STATE["eps"], STATE["angle"], clearance)
    rate = STATE["rate_over_c"] * clearance  # fixed eps_dot, eps gamma_dot
    return ShortBearingFilm(mu, length, clearance).film(
        _kin(e, rate, omega, radius=radius, clearance=clearance))


def test_force_scales_with_viscosity_length_cubed_clearance_squared_and_radius():
    base = np.asarray(_film().force)
    np.testing.assert_allclose(np.asarray(_film(mu=3 * MU).force), 3 * base, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(_film(length=2 * L).force), 8 * base, rtol=1e-12)
    # fixed eps and eps rates: F ~ 1/c^2
    np.testing.assert_allclose(np.asarray(_film(clearance=2 * C).force), base / 4, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(_film(radius=1.5 * R).force), 1.5 * base, rtol=1e-12)


def test_reversing_the_spin_reverses_the_tangential_force_and_the_torque():
    e = _polar(0.6, 0.4)
    law = ShortBearingFilm(MU, L, C)
    fwd, back = law.film(_kin(e, omega=90.0)), law.film(_kin(e, omega=-90.0))
    assert float(back.tangential) == pytest.approx(-float(fwd.tangential), rel=1e-12)
    assert float(back.radial) == pytest.approx(float(fwd.radial), rel=1e-12)
    assert float(back.torque) == pytest.approx(-float(fwd.torque), rel=1e-12)


# the saturation is the films' shared one (`AbstractFilm`): each film at a
# length in its own range (the long film at L/D = 4)
@pytest.mark.parametrize("film, length", [(ShortBearingFilm, L), (LongBearingFilm, 0.080)])
def test_saturates_beyond_the_maximum_eccentricity_ratio(film, length):
    """Up to eps_max - w the film is the pin's own (the same as a film with a
    larger eps_max, to the last bit); past it the film is evaluated at
    eps_max - w + w (1 - exp(-(eps - eps_max + w) / w)): below the pin's eps,
    C1, and never past the film at eps_max."""
    law = film(MU, length, C, max_eccentricity_ratio=0.95)
    free = film(MU, length, C, max_eccentricity_ratio=0.99)
    rate, omega = (1e-3, 2e-3), 50.0
    for eps in (0.5, 0.9, 0.94):
        kin = _kin(_polar(eps, 0.2), rate, omega)
        np.testing.assert_array_equal(np.asarray(law.film(kin).force),
                                      np.asarray(free.film(kin).force))
    cap = free.film(_kin(_polar(0.95, 0.2), omega=omega))
    beyond = law.film(_kin(_polar(1.3, 0.2), rate, omega))
    assert np.all(np.isfinite(np.asarray(beyond.force)))
    assert float(beyond.min_film_thickness) == pytest.approx(-0.3 * C, rel=1e-9)
    loads = [float(jnp.linalg.norm(law.film(_kin(_polar(eps, 0.2), omega=omega)).force))
             for eps in (0.9, 0.93, 0.945, 0.95, 1.0, 1.5)]
    assert loads == sorted(loads) and loads[-1] <= float(jnp.linalg.norm(cap.force)) * (1 + 1e-12)
    assert loads[-1] == pytest.approx(float(jnp.linalg.norm(cap.force)), rel=1e-6)
    for eps in (0.945, 0.95, 0.97):  # never a heavier film than the pin's own
        own = float(jnp.linalg.norm(free.film(_kin(_polar(eps, 0.2), omega=omega)).force))
        assert float(jnp.linalg.norm(law.film(_kin(_polar(eps, 0.2), omega=omega)).force)) < own
    # C1 at the onset eps_max - w: the slope of the load just below and above agree
    h = 1e-7
    slope = [(float(jnp.linalg.norm(law.film(_kin(_polar(e + h, 0.2), omega=omega)).force))
              - float(jnp.linalg.norm(law.film(_kin(_polar(e - h, 0.2), omega=omega)).force)))
             / (2 * h) for e in (0.94 - 2e-6, 0.94 + 2e-6)]
    assert slope[1] == pytest.approx(slope[0], rel=1e-3)


# ---------------------------------------------------------------- derivatives
# (the derivatives both films share, at the centre too: tests/test_films.py)

def test_parameters_are_float64_leaves_with_exact_module_gradients():
    """Reverse mode through the module's leaves: F is linear in mu and cubic in
    L, so dF/dmu = F / mu and dF/dL = 3 F / L."""
    law = ShortBearingFilm(MU, L, C)
    assert all(np.asarray(leaf).dtype == np.float64 for leaf in jax.tree_util.tree_leaves(law))
    kin = _kin(_polar(0.45, 0.6), (0.5e-3, -1e-3), 85.0)
    grads = eqx.filter_grad(lambda m: m.film(kin).force[1])(law)
    force_y = float(law.film(kin).force[1])
    assert float(grads.viscosity) == pytest.approx(force_y / MU, rel=1e-12)
    assert float(grads.length) == pytest.approx(3 * force_y / L, rel=1e-12)
