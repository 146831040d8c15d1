"""The Greenwood-Tripp asperity contact (`diffwear.contact.asperities`) and
the mixed-lubrication joint that carries it: F_{5/2} against the parabolic
cylinder function and adaptive quadrature, the constant K against a direct
integration of Hertz summit pairs, the series solve with the foundation
against a second implementation (SciPy), the load sharing at the
quasi-static equilibrium, the asperity share against the viscosity, the
derivatives against central differences, and the file keys."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, optimize, special

from diffwear.cli import main
from diffwear.config import units as U
from diffwear.contact import (
    PTFE,
    STEEL,
    ArchardWear,
    ClearanceJoint,
    CoulombFriction,
    ElasticFoundation,
    MixedLubrication,
    PinKinematics,
    ShortBearingFilm,
)
from diffwear.contact.asperities import (
    GT_CONSTANT,
    GreenwoodTripp,
    composite_modulus,
    gaussian_tail_integral,
)
from diffwear.errors import InputError
from diffwear.quasistatic import LubricatedQuasiStaticJoint
from diffwear.quasistatic.loads import JointLoads

# the lubricated joint of tests/test_lubricated_joint.py: R = 10 mm, L = 8 mm,
# c = 50 um, 0.04 Pa s, k_f = 1e13 Pa/m
MU, R, L, C, KF = 0.04, 0.010, 0.008, 50e-6, 1e13
SIGMA = 0.5e-6


def _f_closed(lam, order=2.5):
    """F_n(lambda) = Gamma(n + 1) exp(-lambda^2 / 4) D_{-n-1}(lambda) / sqrt(2 pi)
    (parabolic cylinder function, D_{-n-1} = U(n + 1/2, .), DLMF 12.5.1);
    0 beyond lambda = 37 (below 1e-300)."""
    if lam > 37.0:
        return 0.0
    return (special.gamma(order + 1.0) * np.exp(-lam * lam / 4.0)
            * special.pbdv(-order - 1.0, lam)[0] / math.sqrt(2.0 * math.pi))


def _f_quad(lam, order=2.5):
    return integrate.quad(lambda s: (s - lam) ** order * math.exp(-s * s / 2.0), lam,
                          max(lam, 0.0) + 12.0, epsabs=0.0, epsrel=1e-13,
                          limit=200)[0] / math.sqrt(2.0 * math.pi)


# ------------------------------------------------------------ F_{5/2}
@pytest.mark.parametrize("order", [2.5, 1.5])
def test_the_gaussian_tail_integral_matches_two_references(order):
    lams = np.array([-40.0, -30.0, -12.0, -10.3, -8.0, -3.0, -1.0, -0.2, 0.0, 0.5, 1.0, 2.0,
                     3.0, 4.0, 5.5, 7.0])
    got = np.asarray(gaussian_tail_integral(jnp.asarray(lams), order))
    closed = np.array([_f_closed(x, order) for x in lams])
    quad = np.array([_f_quad(x, order) for x in lams if x > -20.0])
    np.testing.assert_allclose(got, closed, rtol=1e-10)
    np.testing.assert_allclose(got[lams > -20.0], quad, rtol=1e-10)
    # F_{5/2}(0) = Gamma(7/2) 2^(-7/4) / (sqrt(2) Gamma(9/4)) (D_nu(0) = 2^(nu/2)
    # sqrt(pi) / Gamma((1 - nu) / 2), DLMF 12.2.6)
    if order == 2.5:
        f0 = special.gamma(3.5) * 2.0 ** -1.75 / (math.sqrt(2.0) * special.gamma(2.25))
        assert float(gaussian_tail_integral(0.0)) == pytest.approx(f0, rel=1e-12)


def test_the_tail_integral_is_smooth_and_its_derivative_is_the_lower_order():
    """dF_{5/2}/dlambda = -(5/2) F_{3/2}, by autodiff and by central
    differences, across the quadrature's span changes (lambda = 0, -10, -11)."""
    lams = jnp.array([-11.0, -10.5, -10.0, -3.0, -0.5, 0.0, 0.5, 2.0, 4.0])
    grad = jax.vmap(jax.grad(lambda x: gaussian_tail_integral(x)))(lams)
    np.testing.assert_allclose(np.asarray(grad),
                               [-2.5 * _f_closed(float(x), 1.5) for x in lams], rtol=1e-9)
    h = 1e-5
    fd = (gaussian_tail_integral(lams + h) - gaussian_tail_integral(lams - h)) / (2 * h)
    np.testing.assert_allclose(np.asarray(grad), np.asarray(fd), rtol=1e-7)


# ------------------------------------------------------------ the pressure
def test_the_constant_is_that_of_hertz_summit_pairs():
    """K E' F_{5/2}(h / sigma) against the model it stands for, integrated
    directly: eta^2 summit pairs per unit area, heights summing to a Gaussian
    of RMS sigma, offset r, Hertz with radius beta / 2 at interference
    w = s - h - r^2 / (4 beta) (module notes of `diffwear.contact.asperities`)."""
    sigma, eta, beta, e_star = 0.8e-6, 5e8, 100e-6, 2.0e9
    gt = GreenwoodTripp(sigma, eta, beta, e_star)
    for h in (-0.5 * sigma, 0.0, 1.5 * sigma):
        def pairs(s):
            w0 = s - h  # overlap at zero offset
            hertz = lambda r: (4.0 / 3.0 * e_star * math.sqrt(beta / 2.0)  # noqa: E731
                               * (w0 - r * r / (4.0 * beta)) ** 1.5 * 2.0 * math.pi * r)
            return integrate.quad(hertz, 0.0, math.sqrt(4.0 * beta * w0), epsrel=1e-12)[0]

        density = lambda s: math.exp(-0.5 * (s / sigma) ** 2) / (sigma * math.sqrt(2 * math.pi))  # noqa: E731
        direct = eta**2 * integrate.quad(lambda s: pairs(s) * density(s), h, h + 12 * sigma,
                                         epsrel=1e-11)[0]
        assert float(gt.pressure(h)) == pytest.approx(direct, rel=1e-6)


def test_the_pressure_scales_as_the_closed_form():
    """p = (16 sqrt(2) pi / 15) (eta beta sigma)^2 sqrt(sigma / beta) E'
    F_{5/2}(h / sigma): eta^2, beta^(3/2), E', and sigma^(5/2) at a fixed
    film ratio; E' of steel on PTFE from Table 3-2."""
    sigma, eta, beta = 0.65e-6, 1e9, 50e-6
    gt = GreenwoodTripp.from_materials(STEEL, PTFE, sigma, eta, beta)
    e_star = 1.0 / ((1 - 0.29**2) / 206.8e9 + (1 - 0.38**2) / 0.5e9)
    assert float(gt.modulus) == pytest.approx(e_star, rel=1e-13)
    assert float(composite_modulus(STEEL, PTFE)) == pytest.approx(e_star, rel=1e-13)
    h = 0.7 * sigma
    k = 16 * math.sqrt(2) * math.pi / 15 * (eta * beta * sigma) ** 2 * math.sqrt(sigma / beta)
    assert float(gt.pressure(h)) == pytest.approx(k * e_star * _f_closed(0.7), rel=1e-10)
    assert GT_CONSTANT == pytest.approx(16 * math.sqrt(2) * math.pi / 15, rel=1e-15)
    p = float(gt.pressure(h))
    assert float(GreenwoodTripp(sigma, 2 * eta, beta, e_star).pressure(h)) == pytest.approx(
        4 * p, rel=1e-12)
    assert float(GreenwoodTripp(sigma, eta, 2 * beta, e_star).pressure(h)) == pytest.approx(
        2**1.5 * p, rel=1e-12)
    assert float(GreenwoodTripp(sigma, eta, beta, 3 * e_star).pressure(h)) == pytest.approx(
        3 * p, rel=1e-12)
    assert float(GreenwoodTripp(2 * sigma, eta, beta, e_star).pressure(2 * h)) == pytest.approx(
        2**2.5 * p, rel=1e-12)


def test_pressure_derivative_matches_central_differences():
    gt = GreenwoodTripp(SIGMA)
    for h in (-2 * SIGMA, 0.0, 0.8 * SIGMA, 3 * SIGMA):
        step = 1e-4 * SIGMA
        fd = (float(gt.pressure(h + step)) - float(gt.pressure(h - step))) / (2 * step)
        assert float(jax.grad(gt.pressure)(h)) == pytest.approx(fd, rel=1e-7)
        assert float(gt.stiffness(h)) == pytest.approx(-fd, rel=1e-7)


def test_summit_parameters_out_of_range_are_refused():
    with pytest.raises(InputError, match="summit density eta"):
        GreenwoodTripp(1e-6, -1.0, 1e-4)
    with pytest.raises(InputError, match=r"eta beta sigma = 0.5 .* must lie in \[0.01, 0.1\]"):
        GreenwoodTripp(1e-6, 5e9, 1e-4)
    with pytest.raises(InputError, match="sigma / beta"):
        GreenwoodTripp(1e-6, 4e10, 1e-6)
    gt = GreenwoodTripp(0.65e-6)  # defaults: eta beta sigma = 0.04, sigma / beta = 1e-3
    assert float(gt.summit_radius) == pytest.approx(0.65e-3, rel=1e-12)
    assert float(gt.summit_density * gt.summit_radius * gt.roughness) == pytest.approx(0.04)


# ------------------------------------------------------------ on the foundation
def _series_reference(gt: GreenwoodTripp, gap, k_f):
    """The common pressure of asperities and Winkler layer in series, solved
    with SciPy: p = p_a(g + p / k_f), F_{5/2} by the parabolic cylinder function."""
    ke, sigma = float(gt.contact_modulus), float(gt.roughness)

    def one(g):
        res = lambda p: p - ke * _f_closed((g + p / k_f) / sigma)  # noqa: E731
        hi = ke * _f_closed(g / sigma) + 1.0
        return optimize.brentq(res, 0.0, hi, xtol=1e-300, rtol=1e-14) if hi > 1.0 else 0.0

    return np.array([one(float(g)) for g in np.atleast_1d(gap)])


@pytest.mark.parametrize("k_f", [1e10, 1e13, 1e16])
def test_the_series_pressure_matches_a_second_solver(k_f):
    gt = GreenwoodTripp(SIGMA)
    gaps = np.array([-30, -12, -8, -2, 0, 0.5, 2, 3.5]) * SIGMA
    p, k_s = gt.on_foundation(jnp.asarray(gaps), k_f)
    np.testing.assert_allclose(np.asarray(p), _series_reference(gt, gaps, k_f), rtol=1e-10)
    # the pair's stiffness: dp / d(-g), against central differences
    step = 1e-5 * SIGMA
    fd = (_series_reference(gt, gaps - step, k_f) - _series_reference(gt, gaps + step, k_f)) / (
        2 * step)
    np.testing.assert_allclose(np.asarray(k_s), fd, rtol=1e-5)
    # the pair is softer than either part and stiffens as the gap closes; a
    # rigid bulk leaves the asperities alone
    k_s = np.asarray(k_s)
    assert np.all(np.diff(k_s) < 0) and np.all(k_s < k_f)
    assert np.all(k_s < np.asarray(gt.stiffness(gaps + np.asarray(p) / k_f)))
    # (the bulk still gives p / k_f ~ 2e-5 sigma at g = 0)
    if k_f == 1e16:
        np.testing.assert_allclose(np.asarray(p)[gaps >= 0], np.asarray(gt.pressure(gaps))[
            gaps >= 0], rtol=1e-4)


def test_the_series_root_converges_over_the_range_of_the_notes():
    from diffwear.contact.asperities import _series_root

    gamma = jnp.linspace(-500.0, 8.0, 509)
    for a in (1e-3, 1e-1, 1.0, 10.0, 1e3):
        y = _series_root(gamma, a)
        residual = y - a * gaussian_tail_integral(gamma + y)
        assert float(jnp.max(jnp.abs(residual) / jnp.maximum(y, 1e-300))) < 1e-12


# ------------------------------------------------------------ the joint
def _joint(mu=MU, sigma=SIGMA, n=90, friction=0.1, wear=1e-14):
    law = MixedLubrication(ShortBearingFilm(mu, L, C), ElasticFoundation(KF, L), sigma)
    return ClearanceJoint("j", "a", [0.0, 0.0], "b", [0.0, 0.0], R, R + C, law,
                          friction=CoulombFriction(friction), wear=ArchardWear(wear),
                          n_theta=n)


def _asperity_force_reference(law: MixedLubrication, e, omega, n, mu_f, slip_width):
    """The asperities' force on the pin at rest in the bushing (offset ``e``),
    from `_series_reference` node by node: normal -sum p_k u_k A, friction
    opposing the slip R_pin omega along t_k (smoothed sign as the joint's)."""
    theta = 2 * np.pi * np.arange(n) / n
    u = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    t = np.stack([-np.sin(theta), np.cos(theta)], axis=1)
    p = _series_reference(law.summits, C - u @ np.asarray(e), float(law.asperity.stiffness))
    load = p * (R + C) * L * 2 * np.pi / n
    slip = R * omega
    f_t = -mu_f * slip / math.sqrt(slip**2 + slip_width**2) * load
    return f_t @ t - load @ u, load.sum()


def _short_bearing_load(eps, mu=MU, omega=100.0):
    return (mu * omega * R * L**3 * eps / (4 * C**2 * (1 - eps**2) ** 2)
            * math.sqrt(16 * eps**2 + math.pi**2 * (1 - eps**2)))


@pytest.fixture(scope="module")
def solve():
    return eqx.filter_jit(lambda j, w, om, c: j.pin_offset(w, om, c))


def test_film_and_asperities_balance_the_load_at_equilibrium(solve):
    """At the quasi-static equilibrium in the mixed regime the film's force
    (short bearing) plus the asperities' force, the latter recomputed with
    SciPy node by node, balance the load; both carry a share."""
    omega = 100.0
    j = _joint()
    qs = LubricatedQuasiStaticJoint.from_joint(j)
    # beyond the saturated film's load (lambda_b = 1): the asperities, pressed
    # past the mean surfaces onto the bulk, carry the rest
    load = jnp.array([150.0, -1.3 * _short_bearing_load(1.0 - SIGMA / C)])
    e, ok = solve(qs, load, jnp.asarray(omega), qs.dry.clearance)
    assert float(ok) == 1.0
    kin = PinKinematics(e, jnp.zeros(2), jnp.asarray(omega), jnp.asarray(R), jnp.asarray(R + C))
    parts = j.law.lubrication(kin, jnp.zeros(0), j.profile, j.friction)
    f_asp, n_asp = _asperity_force_reference(j.law, e, omega, 90, 0.1,
                                             float(j.friction.slip_width))
    np.testing.assert_allclose(np.asarray(parts.film.force) + f_asp, -np.asarray(load),
                               rtol=0, atol=1e-8 * float(jnp.abs(load).max()))
    assert float(parts.asperity_load) == pytest.approx(n_asp, rel=1e-9)
    assert 0.1 < float(parts.asperity_share) < 0.9
    assert float(parts.interference) > 10 * SIGMA  # the bulk carries, in series


def test_the_asperity_share_rises_smoothly_as_the_viscosity_drops(solve):
    """Fixed load, viscosity from 1 Pa s down to 1e-7 Pa s: the asperities'
    share rises monotonically from 0 (the film carries at lambda > 3; its
    Gaussian tail underflows) to ~1, and the film thins."""
    omega = 100.0
    load = jnp.array([0.0, -300.0])
    shares, films = [], []
    for mu in (1.0, 0.1, 0.03, 0.01, 3e-3, 1e-3, 3e-4, 1e-4, 1e-5, 1e-7):
        qs = LubricatedQuasiStaticJoint.from_joint(_joint(mu=mu))
        e, ok = solve(qs, load, jnp.asarray(omega), qs.dry.clearance)
        assert float(ok) == 1.0
        parts = qs._parts(e, jnp.asarray(omega), qs.dry.clearance)
        shares.append(float(parts.asperity_share))
        films.append(float(C - jnp.linalg.norm(e)))
    touching = np.asarray(shares) > 0.0
    assert np.all(np.diff(shares) >= 0), shares
    assert np.all(np.diff(np.asarray(shares)[touching]) > 0), shares
    assert np.all(np.diff(films) < 0), films
    assert shares[0] < 1e-12 and shares[-1] > 0.99 and touching.sum() >= 6
    assert films[0] > 3 * SIGMA


@pytest.mark.extended
def test_wear_derivative_in_viscosity_matches_central_differences():
    """d(wear of a cycle)/d(viscosity) on 6 samples of a turning load, by
    forward mode (through the implicit offset and the series solve) against
    central differences (relative step 1e-6)."""
    s = 6
    phase = 2 * np.pi * np.arange(s) / s
    force = jnp.stack([200 * np.cos(phase), -250 - 150 * np.sin(phase)], axis=1)
    loads = JointLoads(force=force, omega=jnp.full(s, 100.0), period=jnp.asarray(0.1))

    def wear(mu):
        qs = LubricatedQuasiStaticJoint.from_joint(_joint(mu=mu, n=48))
        dh, _, eq = qs.cycle_wear(jnp.zeros(48), loads)
        return dh, eq.ok

    mu = 0.02
    f = eqx.filter_jit(wear)
    (dh, ok), (d_dh, _) = eqx.filter_jit(lambda m: jax.jvp(wear, (m,), (jnp.ones(()),)))(
        jnp.asarray(mu))
    assert bool(ok) and float(jnp.max(dh)) > 0.0
    h = 1e-6 * mu
    fd = (np.asarray(f(jnp.asarray(mu + h))[0]) - np.asarray(f(jnp.asarray(mu - h))[0])) / (2 * h)
    assert float(jnp.min(d_dh)) < 0.0  # a thicker oil wears less
    np.testing.assert_allclose(np.asarray(d_dh), fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())


# ------------------------------------------------------------ the file keys
def test_areal_density_units():
    assert U.parse_quantity("1e10 1/m^2", "areal density") == 1e10
    assert U.parse_quantity("100 1/mm^2", "areal density") == 1e8
    assert U.parse_quantity("0.01 1/um^2", "areal density") == 1e10


def test_the_summit_keys_reach_the_asperity_law(tmp_path):
    from test_lubricant_file import ROUGH, _file

    from diffwear.config import load

    path = _file(tmp_path, "summits", (ROUGH, ROUGH + ', summit_density = "400 1/mm^2", '
                                       'summit_radius = "150 um"'))
    gt = load(str(path)).mechanism.element("crank_rod").law.summits
    assert float(gt.summit_density) == pytest.approx(4e8, rel=1e-12)
    assert float(gt.summit_radius) == pytest.approx(150e-6, rel=1e-12)
    # the rig's steel pin (default) on its PTFE bushing
    assert float(gt.modulus) == pytest.approx(float(composite_modulus(STEEL, PTFE)), rel=1e-12)
    shipped = load("rig_lubricated").mechanism.element("crank_rod").law.summits
    assert float(shipped.summit_radius) == pytest.approx(0.65e-3, rel=1e-12)
    assert float(shipped.summit_density * shipped.summit_radius * shipped.roughness) == (
        pytest.approx(0.04, rel=1e-12))


@pytest.mark.parametrize("extra, words", [
    ('summit_density = "0 1/m^2"',
     ["joints[1].lubricant.summit_density", "'0 1/m^2'", "out of range"]),
    ('summit_radius = "-5 um"', ["joints[1].lubricant.summit_radius", "'-5 um'"]),
    ('summit_density = "1e9 1/m^2"',
     ["joints[1].lubricant.summit_density", "eta beta sigma = 0.423",
      "eta beta sigma in [0.01, 0.1]", "2.37e+07 to 2.37e+08 1/m^2"]),
    ('summit_density = "2e8 1/m^2", summit_radius = "10 um"',
     ["joints[1].lubricant.summit_density", "eta beta sigma = 0.0013", "[0.01, 0.1]"]),
    ('summit_radius = "1 um"',
     ["joints[1].lubricant.summit_radius", "sigma / beta = 0.65", "[1e-06, 0.1]",
      "6.5 um to 650000 um"]),
    ('summit_density = "1e10 1/s"',
     ["joints[1].lubricant.summit_density", "'1/s' is a rate unit"]),
])
def test_bad_summit_keys_exit_2_naming_the_key_and_the_range(tmp_path, capsys, extra, words):
    from test_lubricant_file import ROUGH, _file

    path = _file(tmp_path, "bad", (ROUGH, f"{ROUGH}, {extra}"))
    out = tmp_path / "out"
    assert main(["run", str(path), "--cycles", "2000", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    for w in words:
        assert w in err, (w, err)
    assert not out.exists()
