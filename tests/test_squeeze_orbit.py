"""The lubricated joint's orbit with the squeeze film (`LubricatedQuasiStaticJoint`,
``squeeze=True``): the steady bearing as its limit under a constant or slow
load, the backward-Euler squeeze against a tight ODE solution of the same
short-bearing film (its pressure integral by quadrature, not the closed
form), the oscillating four-bar in oil (a thicker oil keeps a thicker film
through the reversals and wears less), and the wear's derivative in the
viscosity against central differences."""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from lubricated_pin import MU, C, L, R, pin_joint

from diffwear.choices import SHIPPED_MECHANISMS
from diffwear.config.loader import loads as load_text
from diffwear.mechanism_file.motion import initial_state
from diffwear.mechanism_file.wear import drive_period
from diffwear.models import QuasiStatic
from diffwear.quasistatic import JointLoads, LubricatedQuasiStaticJoint, QuasiStaticJoint


def _joint(mu=MU, sigma=0.1e-6, n=90, squeeze=True):
    return LubricatedQuasiStaticJoint.from_joint(pin_joint(mu, sigma, n), squeeze=squeeze)


def _loads(force, omega, period):
    force = jnp.asarray(force, dtype=float)
    return JointLoads(force=force, omega=jnp.broadcast_to(jnp.asarray(omega, dtype=float),
                                                          force.shape[:1]),
                      period=jnp.asarray(period, dtype=float))


S = 24  # samples of the steady-limit tests (one compilation for both)


@eqx.filter_jit
def _equilibria(joint, loads):
    steady = joint.steady()
    depth = jnp.zeros(joint.n)
    return joint.equilibrium(depth, loads), steady.equilibrium(depth, loads)


# ------------------------------------------------------------ steady limit
def test_under_a_constant_load_the_orbit_is_the_steady_bearing():
    """Constant load and spin: the backward-Euler orbit's fixed point has
    e_dot = 0, so it is the steady equilibrium (to the Newton tolerance)."""
    joint = _joint()
    loads = _loads(jnp.tile(jnp.array([[120.0, -60.0]]), (S, 1)), 100.0, 0.1)
    orbit, steady = _equilibria(joint, loads)
    assert bool(orbit.ok) and bool(steady.ok)
    assert bool(orbit.orbit_closed) and not bool(steady.orbit_closed)
    e_ss = np.asarray(steady.offset[0])
    assert 0.3 < np.linalg.norm(e_ss) / C < 0.95  # a film-borne pin, well off-centre
    np.testing.assert_allclose(np.asarray(orbit.offset), np.tile(e_ss, (S, 1)),
                               rtol=0, atol=1e-10 * C)
    np.testing.assert_allclose(np.asarray(orbit.film_load), np.asarray(steady.film_load),
                               rtol=1e-8)


def test_under_a_slow_load_the_orbit_tends_to_the_steady_bearing():
    """A load whose size swings 50 % over a period T: the orbit lags the
    steady bearing by the squeeze time tau (~ 1e-3 s here), so their gap
    falls like tau / T: below 2e-3 c at T = 10 s and ten times smaller at
    T = 100 s (first order)."""
    joint = _joint()
    phase = 2 * jnp.pi * jnp.arange(S) / S
    force = (100.0 * (1.0 + 0.5 * jnp.sin(phase)))[:, None] * jnp.array([[0.6, -0.8]])
    gaps = []
    for period in (10.0, 100.0):
        orbit, steady = _equilibria(joint, _loads(force, 100.0, period))
        assert bool(orbit.ok) and bool(steady.ok) and bool(orbit.orbit_closed)
        gaps.append(float(jnp.max(jnp.linalg.norm(orbit.offset - steady.offset, axis=1))) / C)
    assert gaps[0] < 2e-3, gaps
    assert gaps[1] == pytest.approx(gaps[0] / 10, rel=0.05), gaps


# ------------------------------------------------------------ pure squeeze
def _squeeze_ode(force, t_end, ts):
    """The pin's approach from the centre under a constant load ``force`` [N]
    along +x with no rotation: the short-bearing film of the module
    tests/test_lubrication.py checks, F_x = -2 K x_dot / c I(eps),
    K = mu R L^3 / (2 c^2), I(eps) the integral of cos^2 psi / (1 - eps
    cos psi)^3 over the half facing the approach (|psi| < pi/2, Gumbel),
    here by 400-point Gauss-Legendre quadrature; so x_dot = c W / (2 K I),
    integrated by Tsit5 at 1e-12."""
    nodes, weights = np.polynomial.legendre.leggauss(400)
    psi, w = jnp.asarray(nodes * np.pi / 2), jnp.asarray(weights * np.pi / 2)
    k = MU * R * L**3 / (2 * C**2)

    def rate(t, x, args):
        eps = x / C
        integral = jnp.sum(w * jnp.cos(psi) ** 2 / (1 - eps * jnp.cos(psi)) ** 3)
        return C * force / (2 * k * integral)

    sol = diffrax.diffeqsolve(diffrax.ODETerm(rate), diffrax.Tsit5(), 0.0, t_end, None,
                              jnp.asarray(0.0), saveat=diffrax.SaveAt(ts=ts),
                              stepsize_controller=diffrax.PIDController(rtol=1e-12,
                                                                        atol=1e-12 * C),
                              max_steps=100_000)
    return np.asarray(sol.ys)


def test_pure_squeeze_approach_matches_the_ode_to_first_order():
    """omega = 0, a constant 100 N: the pin squeezes the oil out from the
    centre to eps ~ 0.9 in T = 25 ms.  The orbit's backward-Euler step
    (`march`) against the ODE of the same film: the error is first order
    in dt (halves when dt halves; 3 % of c at 100 steps), and the two
    step sizes' Richardson extrapolation 2 e_dt/2 - e_dt agrees with the ODE
    to a fifth of the finer error; the pin moves along the load (no wedge, no turn)."""
    joint = _joint()
    force, t_end = 100.0, 25e-3
    march = eqx.filter_jit(lambda j, lo: j.march(lo, j.clearance, jnp.zeros(2)))
    exact = _squeeze_ode(force, t_end, t_end * jnp.arange(1, 201) / 200)
    assert 0.85 < exact[-1] / C < 0.95
    paths = []
    for s in (100, 200):
        loads = _loads(jnp.tile(jnp.array([[force, 0.0]]), (s, 1)), 0.0, t_end)
        es, ok = march(joint, loads)
        assert float(ok) == 1.0
        np.testing.assert_allclose(np.asarray(es[:, 1]), 0.0, atol=1e-12 * C)
        paths.append(np.asarray(es[:, 0]))
    coarse, fine = paths[0], paths[1][1::2]  # both at the coarse times
    errors = [float(np.max(np.abs(p - exact[1::2]))) / C for p in (coarse, fine)]
    richardson = float(np.max(np.abs(2 * fine - coarse - exact[1::2]))) / C
    assert errors[0] < 4e-2, errors
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.1), errors
    assert richardson < 0.2 * errors[1], (errors, richardson)


# ------------------------------------------------------------ four-bar in oil
FOUR_BAR = SHIPPED_MECHANISMS / "four_bar_wear.toml"
WEAR_KEY = 'wear = { coefficient = "5.05e-4 mm^3/(N m)" }'
SAMPLES = 60  # 6 degrees of crank per sample (the shipped runs use 360)


def _four_bar(viscosity=None):
    """The shipped four-bar, its coupler-rocker joint in oil of
    ``viscosity`` [Pa s] (none: dry) on surfaces of sigma = 1 um (a turned
    pin in a bored bushing: 3 sigma = 3 um against the 50 um clearance), on
    the film a file gets by default (the finite film: L/D = 10 / 12)."""
    text = FOUR_BAR.read_text()
    assert WEAR_KEY in text
    if viscosity is not None:
        text = text.replace(WEAR_KEY, WEAR_KEY + "\nlubricant = { viscosity = "
                            f'"{viscosity} Pa s", roughness = "1 um" }}')
    return load_text(text, file="four_bar_wear.toml")


@pytest.fixture(scope="module")
def four_bar():
    """The coupler-rocker joint's loads (60 samples), and its wear cycle
    against the viscosity, compiled once."""
    dry = _four_bar()
    loads = QuasiStatic(samples=SAMPLES).loads(dry.mechanism, ("coupler_rocker",),
                                               initial_state(dry), drive_period(dry))
    assert bool(loads.ok)
    loads = loads.joints[0]
    element = _four_bar(0.5).mechanism.element("coupler_rocker")
    assert type(element.law.film).__name__ == "ShippedFiniteFilm"

    def with_oil(mu):
        return eqx.tree_at(lambda e: e.law.film.viscosity, element, mu)

    @eqx.filter_jit
    def cycle(mu, squeeze=True):
        joint = LubricatedQuasiStaticJoint.from_joint(with_oil(mu), squeeze=squeeze)
        return joint.cycle_wear(jnp.zeros(joint.n), loads)

    dry_joint = QuasiStaticJoint.from_joint(dry.mechanism.element("coupler_rocker"))
    dry_wear = dry_joint.cycle_wear(jnp.zeros(dry_joint.n), loads)
    return loads, cycle, dry_wear


@pytest.mark.extended
def test_the_four_bar_joint_reverses(four_bar):
    loads, _, _ = four_bar
    omega = np.asarray(loads.omega)
    assert omega.max() > 1.0 and omega.min() < -1.0


@pytest.mark.extended  # ~1 min with its fixture: the four-bar's orbits, compiled
def test_a_thicker_oil_keeps_a_thicker_film_through_the_reversals(four_bar):
    """0.5 and 0.005 Pa s: the squeeze film keeps the thicker oil's pin off
    its asperities through both reversals (the steady bearing puts both on
    them: the same zero film), so it keeps a strictly thicker minimum film
    and wears strictly less; both wear no more than the dry joint; no film
    thickness is negative."""
    _, cycle, (dh_dry, sliding_dry, _) = four_bar
    results = {mu: cycle(jnp.asarray(mu)) for mu in (0.5, 0.005)}
    for dh, sliding, eq in results.values():
        assert bool(eq.ok) and bool(eq.orbit_closed)
        assert float(jnp.min(eq.min_film_thickness)) >= 0.0
        assert float(sliding) <= float(sliding_dry)
        assert float(jnp.max(dh)) <= float(jnp.max(dh_dry))
        assert float(jnp.sum(dh)) <= float(jnp.sum(dh_dry))
    (dh_thick, _, thick), (dh_thin, _, thin) = results[0.5], results[0.005]
    assert float(jnp.min(thick.min_film_thickness)) > float(jnp.min(thin.min_film_thickness))
    assert float(jnp.sum(dh_thick)) < float(jnp.sum(dh_thin))
    assert float(jnp.sum(dh_thin)) > 0.0
    # the steady bearing at every sample: at a reversal (omega = 0) both pins sit
    # on their asperities, with the same thinnest film whatever the oil
    (_, _, steady_thick), (_, _, steady_thin) = (cycle(jnp.asarray(mu), squeeze=False)
                                                 for mu in (0.5, 0.005))
    h_thick = float(jnp.min(steady_thick.min_film_thickness))
    h_thin = float(jnp.min(steady_thin.min_film_thickness))
    assert h_thick == pytest.approx(h_thin, rel=1e-6)
    assert h_thick < 3e-6 and float(jnp.max(steady_thick.normal_load)) > 0.0
    assert float(jnp.min(thick.min_film_thickness)) > 3e-6  # lambda > 3 throughout


@pytest.mark.extended  # ~1.5 min: forward and reverse mode compiled
def test_wear_derivative_in_viscosity_matches_central_differences(four_bar):
    """d(wear volume per cycle)/d(mu) at 0.005 Pa s, forward and reverse
    mode through the orbit's implicit derivative, against central
    differences (step 1e-4 relative)."""
    _, cycle, _ = four_bar

    def volume(mu):
        dh, _, _ = cycle(mu)
        return jnp.sum(dh)

    mu = jnp.asarray(0.005)
    _, forward = eqx.filter_jit(lambda m: jax.jvp(volume, (m,), (jnp.ones(()),)))(mu)
    reverse = eqx.filter_jit(jax.grad(volume))(mu)
    h = 1e-4 * mu
    fd = (float(volume(mu + h)) - float(volume(mu - h))) / (2 * float(h))
    assert fd < 0.0  # thicker oil, less wear
    assert float(forward) == pytest.approx(fd, rel=1e-4)
    assert float(reverse) == pytest.approx(float(forward), rel=1e-9)
