"""The lubricated joint (`MixedLubrication`): the quasi-static equilibrium
against the short bearing's eccentricity-Sommerfeld relation and the dry
joint, its implicit derivatives against central differences, the load
sharing of film and asperities, a lubricated slider-crank in the dynamic
model (film kept at high viscosity, asperities touched at low), and the
wear life against the viscosity with its derivative."""

from __future__ import annotations

import math

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from lubricated_pin import KF, MU, C, L, R, pin_joint

from diffwear.contact import (
    ArchardWear,
    CoulombFriction,
    ElasticFoundation,
    MixedLubrication,
    PinKinematics,
    ShortBearingFilm,
    contact_history,
    default_film,
)
from diffwear.errors import InputError
from diffwear.quasistatic import LubricatedQuasiStaticJoint
from diffwear.quasistatic.joint import pin_offset


def _short_bearing_load(eps, mu=MU, omega=100.0):
    """Steady short-bearing load (Hamrock, Schmid & Jacobson)."""
    return (mu * omega * R * L**3 * eps / (4 * C**2 * (1 - eps**2) ** 2)
            * math.sqrt(16 * eps**2 + math.pi**2 * (1 - eps**2)))


@pytest.fixture(scope="module")
def solve():
    """The quasi-static offset of a lubricated joint, compiled once."""
    return eqx.filter_jit(lambda j, w, om, c: j.pin_offset(w, om, c))


# ------------------------------------------------------------ equilibrium
@pytest.mark.parametrize("eps", [0.1, 0.3, 0.5, 0.7, 0.8, 0.9])
def test_film_borne_journal_follows_the_sommerfeld_relation(solve, eps):
    """Film alone (asperities far): under the steady short-bearing load
    W(eps) the journal settles at eccentricity eps, at the attitude
    tan phi = pi sqrt(1 - eps^2) / (4 eps) from the load line, leading it in
    the sense of rotation."""
    omega, angle = 100.0, 0.4
    w = _short_bearing_load(eps, omega=omega)
    load = w * jnp.array([math.cos(angle), math.sin(angle)])  # pin on the bushing
    qs = LubricatedQuasiStaticJoint.from_joint(pin_joint(sigma=1e-9))
    e, ok = solve(qs, load, jnp.asarray(omega), qs.dry.clearance)
    assert float(ok) == 1.0
    assert float(jnp.linalg.norm(e)) / C == pytest.approx(eps, rel=1e-8)
    phi = math.atan2(math.pi * math.sqrt(1 - eps**2), 4 * eps)
    turn = math.atan2(float(e[1]), float(e[0])) - angle
    turn = (turn + math.pi) % (2 * math.pi) - math.pi
    assert turn == pytest.approx(phi, abs=1e-8)


def test_without_a_film_the_joint_sits_where_the_asperities_alone_balance_the_load(solve):
    """Vanishing viscosity: the equilibrium is where the asperities on the
    foundation alone carry the load, friction included, found by a second
    solver (SciPy's fsolve on the Greenwood-Tripp pressure in series with
    the foundation, solved node by node with SciPy: tests/test_greenwood_tripp.py)."""
    from scipy import optimize
    from test_greenwood_tripp import _asperity_force_reference

    sigma, omega = 0.5e-6, 3.0
    j = pin_joint(mu=1e-15, sigma=sigma)
    qs = LubricatedQuasiStaticJoint.from_joint(j)
    load = jnp.array([-800.0, 300.0])
    e, ok = solve(qs, load, jnp.asarray(omega), qs.dry.clearance)
    dry = qs.dry
    e_dry, _ = pin_offset(dry.clearance, load,
                          dry.foundation.contact_stiffness(dry.bushing_radius),
                          dry.foundation.penetration_width)

    def balance(x):
        force, _ = _asperity_force_reference(j.law, x * C, omega, 180, 0.1,
                                             float(j.friction.slip_width))
        return (force + np.asarray(load)) / 800.0

    ref = optimize.fsolve(balance, np.asarray(e_dry) / C, xtol=1e-13) * C
    assert float(ok) == 1.0
    np.testing.assert_allclose(np.asarray(e), ref, rtol=1e-8, atol=1e-15)
    # the asperity layer's compliance in series: deeper than the dry joint on the
    # bare bore
    assert float(jnp.linalg.norm(e)) > float(jnp.linalg.norm(e_dry))


def test_mixed_equilibrium_balances_film_and_asperities(solve):
    """A load beyond the film's capacity at lambda_c: film and asperities
    both carry, their forces sum to minus the load, lambda < 3, and the wear
    pressure is the asperities' alone."""
    sigma, omega = 0.5e-6, 100.0
    j = pin_joint(sigma=sigma)
    qs = LubricatedQuasiStaticJoint.from_joint(j)
    load = jnp.array([0.0, -1.5 * _short_bearing_load(1.0 - 3.0 * sigma / C)])
    e, ok = solve(qs, load, jnp.asarray(omega), qs.dry.clearance)
    kin = PinKinematics(e, jnp.zeros(2), jnp.asarray(omega), jnp.asarray(R), jnp.asarray(R + C))
    parts = j.law.lubrication(kin, jnp.zeros(0), j.profile, j.friction)
    assert float(ok) == 1.0
    np.testing.assert_allclose(np.asarray(parts.film.force + parts.asperity.force),
                               -np.asarray(load), rtol=0, atol=1e-8 * float(jnp.abs(load).max()))
    assert 1.0 < float(parts.film_ratio) < 3.0
    assert 0.0 < float(parts.asperity_share) < 1.0
    res = j.law.evaluate(kin, jnp.zeros(0), j.profile, j.friction)
    np.testing.assert_array_equal(np.asarray(res.pressure), np.asarray(parts.asperity.pressure))
    assert float(res.normal_load) == pytest.approx(float(parts.asperity_load), rel=1e-14)


def test_a_separated_film_puts_no_pressure_on_the_bushing():
    """lambda = 10: the summits' Gaussian tail leaves no pressure that
    matters (< 1e-12 Pa), so nothing wears."""
    j = pin_joint(sigma=0.5e-6)
    kin = PinKinematics(jnp.array([0.9 * C, 0.0]), jnp.zeros(2), jnp.asarray(100.0),
                        jnp.asarray(R), jnp.asarray(R + C))
    parts = j.law.lubrication(kin, jnp.zeros(0), j.profile, j.friction)
    assert float(parts.film_ratio) == pytest.approx(0.1 * C / 0.5e-6, rel=1e-9)
    assert 0.0 <= float(jnp.min(parts.asperity.pressure))
    assert float(jnp.max(parts.asperity.pressure)) < 1e-12
    assert float(parts.asperity_share) < 1e-20
    assert float(parts.film_load) > 0.0


def test_offset_derivatives_match_central_differences(solve):
    """de/d(viscosity), de/d(load) and de/d(roughness) by the implicit rule
    against central differences of the solver (relative step 1e-6), where
    film and asperities share the load (past the film's saturation: the
    rough surfaces carry little before, and de/d(roughness) is then too small
    for central differences)."""
    sigma, omega = 0.5e-6, 100.0
    load = jnp.array([200.0, -1.3 * _short_bearing_load(1.0 - sigma / C)])

    def offset(mu, w, s):
        qs = LubricatedQuasiStaticJoint.from_joint(pin_joint(mu=mu, sigma=s))
        return qs.pin_offset(w, jnp.asarray(omega), qs.dry.clearance)[0]

    x = (jnp.asarray(MU), load, jnp.asarray(sigma))
    jac = eqx.filter_jit(jax.jacfwd(offset, argnums=(0, 1, 2)))(*x)
    f = eqx.filter_jit(offset)
    for k, d in enumerate(jac):
        d = np.asarray(d).reshape(2, -1)
        for i in range(d.shape[1]):
            step = 1e-6 * max(float(jnp.abs(x[k]).max()), 1e-30)
            dx = jnp.zeros_like(x[k]).reshape(-1).at[i].set(step).reshape(x[k].shape)
            plus = [x[m] + dx if m == k else x[m] for m in range(3)]
            minus = [x[m] - dx if m == k else x[m] for m in range(3)]
            fd = (np.asarray(f(*plus)) - np.asarray(f(*minus))) / (2 * step)
            np.testing.assert_allclose(d[:, i], fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())


def test_bad_lubrication_inputs_are_refused():
    efm = ElasticFoundation(KF, L)
    film = ShortBearingFilm(MU, L, C)
    with pytest.raises(InputError, match="film law"):
        MixedLubrication(efm, efm, 1e-6)
    with pytest.raises(InputError, match="ElasticFoundation"):
        MixedLubrication(film, film, 1e-6)
    with pytest.raises(InputError, match="roughness"):
        MixedLubrication(film, efm, -1e-6)
    with pytest.raises(InputError, match="lambda_b"):
        MixedLubrication(film, efm, 1e-6, boundary_ratio=3.5)


def test_the_film_is_saturated_where_the_surfaces_meet():
    """eps_max = 1 - lambda_b sigma / c, kept in [0.5, 0.995]."""
    efm = ElasticFoundation(KF, L)
    for sigma, expected in [(1e-6, 0.98), (1e-9, 0.995), (40e-6, 0.5)]:
        law = MixedLubrication(ShortBearingFilm(MU, L, C), efm, sigma)
        assert float(law.saturated_film().max_eccentricity_ratio) == pytest.approx(expected)


def test_film_thickness_is_never_negative_and_the_overlap_is_the_interference():
    """A pin pressed 2 um past the round bore: the film thickness is 0, lambda 0,
    and the 2 um are the asperities' interference; with a gap left, the film is
    the gap and there is no interference."""
    from diffwear.contact import BushingProfile, PinKinematics

    law = pin_joint().law
    profile = BushingProfile.circular(C, 180)
    for depth, film, overlap in [(C + 2e-6, 0.0, 2e-6), (C - 3e-6, 3e-6, 0.0)]:
        kin = PinKinematics(offset=jnp.array([0.0, -depth]), offset_rate=jnp.zeros(2),
                            omega=jnp.asarray(50.0), pin_radius=jnp.asarray(R),
                            bushing_radius=jnp.asarray(R + C))
        parts = law.lubrication(kin, jnp.zeros(0), profile, CoulombFriction(0.1))
        assert float(parts.min_film_thickness) == pytest.approx(film, abs=1e-12)
        assert float(parts.film_ratio) == pytest.approx(film / 0.1e-6, abs=1e-6)
        assert float(parts.interference) == pytest.approx(overlap, abs=1e-12)


# ------------------------------------------------------------ dynamics
def test_lubricated_slider_crank_keeps_its_film_at_high_viscosity_and_touches_at_low():
    """Table 2-1 slider-crank, crank-rod joint lubricated (c = 0.1 mm,
    sigma = 1 um, the finite film a file gets at L/D = 0.32), one crank
    revolution on Rodas4: at 0.5 Pa s the pin rides on the film (lambda > 1
    throughout, the asperities carry under a thousandth of what they carry
    at 0.02 Pa s), at 0.02 Pa s the pin is pressed past the mean surfaces
    (lambda < 0) and the asperities carry load."""
    from diffwear.dynamics import simulate
    from diffwear.dynamics.rosenbrock import Rodas4
    from diffwear.presets import clearance_slider_crank

    mech, y0 = clearance_slider_crank("efm", clearance=0.1e-3, n_theta=90)
    el = mech.element("crank_rod")
    c = float(el.bushing_radius - el.pin_radius)
    sigma = 1e-6
    ts = jnp.linspace(0.0, 2.0, 801)

    eps_max = MixedLubrication.saturation(sigma, c)

    @eqx.filter_jit
    def run(mu):
        film = default_film(mu, el.law.depth, c, el.pin_radius, eps_max)  # finite, L/D 0.32
        law = MixedLubrication(film, el.law, sigma)
        m = eqx.tree_at(lambda m: m.element("crank_rod").law, mech, law)
        tr = simulate(m, y0, 2.0, ts=ts, solver=Rodas4(),
                      stepsize_controller=diffrax.PIDController(rtol=1e-8, atol=1e-8))
        h = contact_history(m, "crank_rod", tr.ys)
        film_ratio = (c - jnp.linalg.norm(h.offset, axis=1)) / sigma
        return film_ratio, h.normal_load, tr.result

    thick, load_thick, ok_thick = run(jnp.asarray(0.5))
    thin, load_thin, ok_thin = run(jnp.asarray(0.02))
    assert ok_thick == diffrax.RESULTS.successful and ok_thin == diffrax.RESULTS.successful
    # the thick oil keeps a film (mixed at worst: lambda > 1, where the summits'
    # Gaussian tail carries little), the thin one lets the pin onto its asperities
    assert float(thick[1:].min()) > 1.0
    assert float(load_thick.max()) < 1e-3 * float(load_thin.max())
    assert float(thin.min()) < 0.0
    assert float(load_thin.max()) > 0.0


# ------------------------------------------------------------ wear life
@pytest.fixture(scope="module")
def rig_life():
    """Life of the Ch. 7 rig's lubricated joint to 50 um against the
    viscosity (quasi-static model, coarse settings; the film a file gets,
    finite at L/D = 0.69), compiled once."""
    from diffwear.contact import default_film
    from diffwear.models import QuasiStatic
    from diffwear.studies import rig_21400

    _, mech, y0 = rig_21400._setup()
    el = mech.element("crank_rod")
    c = el.bushing_radius - el.pin_radius
    eps_max = MixedLubrication.saturation(0.4e-6, c)
    model = QuasiStatic(steps=10, samples=60)

    def lubricated(mu):
        film = default_film(mu, el.law.depth, c, el.pin_radius, eps_max)
        law = MixedLubrication(film, el.law, 0.4e-6)
        return eqx.tree_at(lambda m: m.element("crank_rod").law, mech, law)

    def life(mu):
        return model.life(lubricated(mu), ("crank_rod",), y0, period=2.0, limit=0.05e-3)

    def dry():
        return model.life(mech, ("crank_rod",), y0, period=2.0, limit=0.05e-3)

    return eqx.filter_jit(life), eqx.filter_jit(dry), life


@pytest.mark.extended
def test_life_rises_with_viscosity_and_tends_to_the_dry_life(rig_life):
    life, dry, _ = rig_life
    mus = [1e-5, 1e-3, 3e-3, 1e-2, 2e-2]
    lives = [float(life(jnp.asarray(mu)).life[0]) for mu in mus]
    assert np.all(np.isfinite(lives))
    assert np.all(np.diff(lives) > 0), lives
    assert lives[0] == pytest.approx(float(dry().life[0]), rel=2e-3)
    assert lives[-1] > 3.0 * lives[0]


@pytest.mark.slow  # a life's tangent and two more lives on the orbit: ~6 min
def test_life_derivative_in_viscosity_matches_central_differences(rig_life):
    """d(life)/d(mu) by forward-mode autodiff against central differences,
    within 1e-4.  The step is 1e-6 relative: the discrete life has kinks
    (nodes entering the asperity contact's C1 onset) that make central
    differences of 1e-4 .. 1e-2 wander by up to 0.3 %; from 3e-5 down they
    agree with each other to 1e-6."""
    life, _, plain = rig_life
    mu = 1e-2
    _, dlife = eqx.filter_jit(lambda m: jax.jvp(lambda x: plain(x).life[0], (m,),
                                                  (jnp.ones(()),)))(jnp.asarray(mu))

    h = 1e-6 * mu
    fd = (float(life(jnp.asarray(mu + h)).life[0])
          - float(life(jnp.asarray(mu - h)).life[0])) / (2 * h)
    assert float(dlife) > 0.0
    assert float(dlife) == pytest.approx(fd, rel=1e-4)


def test_dynamic_wear_cycle_comes_from_the_asperities_only():
    """One crank revolution of the lubricated slider-crank on the dynamic
    model's wear cycle (`wear_cycle`, Rodas4 at 1e-8): next to no wear while the
    film carries (0.5 Pa s), wear once the asperities touch (0.02 Pa s), and
    the dry joint wears more than either; the wear's Archard bookkeeping
    (load x sliding) is the asperities'."""
    from diffwear.dynamics.rosenbrock import Rodas4
    from diffwear.presets import clearance_slider_crank
    from diffwear.wear import wear_cycle

    mech, y0 = clearance_slider_crank("efm", clearance=0.1e-3, n_theta=90,
                                      wear=ArchardWear(5.05e-13))
    el = mech.element("crank_rod")
    c = float(el.bushing_radius - el.pin_radius)

    @eqx.filter_jit
    def cycle(m):
        return wear_cycle(m, "crank_rod", y0, 0.0, 2.0, rtol=1e-8, atol=1e-8, solver=Rodas4())

    def lubricated(mu):
        law = MixedLubrication(ShortBearingFilm(mu, el.law.depth, c), el.law, 1e-6)
        return eqx.tree_at(lambda m: m.element("crank_rod").law, mech, law)

    thick, thin, dry = cycle(lubricated(0.5)), cycle(lubricated(0.02)), cycle(mech)
    assert bool(thick.ok) and bool(thin.ok) and bool(dry.ok)
    assert float(jnp.max(thick.depth_increment)) < 1e-4 * float(jnp.max(thin.depth_increment))
    assert float(thick.load_sliding) < 1e-4 * float(thin.load_sliding)
    assert float(jnp.max(thin.depth_increment)) > 0.0
    assert float(jnp.max(dry.depth_increment)) > float(jnp.max(thin.depth_increment))
    assert float(dry.load_sliding) > float(thin.load_sliding) > 0.0


@pytest.mark.extended
def test_oil_film_damps_the_dry_joints_impacts_at_speed():
    """The behaviour Flores, Ambrosio, Claro & Lankarani (Mech. Mach. Theory
    41 (2006) 247) report for a fast slider-crank with a lubricated crank-rod
    joint, as stated properties: with the dry joint the pin hits the wall
    (force peaks several times the running load, the pin past the clearance
    circle); with a 0.4 Pa s film the journal orbit stays inside the
    clearance and the peaks are damped.  A slider-crank of their size (crank
    50 mm, rod 120 mm, 0.30 / 0.21 / 0.14 kg, 5000 rpm, c = 0.5 mm, R = 10 mm,
    L = 40 mm; steel), three revolutions, the last one compared."""
    from diffwear.contact import STEEL
    from diffwear.dynamics import simulate
    from diffwear.dynamics.rosenbrock import Rodas4
    from diffwear.presets import SliderCrankParameters, clearance_slider_crank

    p = SliderCrankParameters(l1=0.05, m1=0.30, inertia1=1e-4, l2=0.12, m2=0.21,
                              inertia2=2.5e-4, m3=0.14, omega=5000 * 2 * math.pi / 60)
    mech, y0 = clearance_slider_crank("efm", clearance=0.5e-3, p=p, pin_radius=0.01,
                                      depth=0.04, materials=(STEEL, STEEL), n_theta=90)
    el = mech.element("crank_rod")
    c = float(el.bushing_radius - el.pin_radius)
    period = 2 * math.pi / p.omega
    ts = jnp.linspace(0.0, 3 * period, 3001)

    @eqx.filter_jit
    def run(m):
        tr = simulate(m, y0, 3 * period, ts=ts, solver=Rodas4(), max_steps=500_000,
                      stepsize_controller=diffrax.PIDController(rtol=1e-8, atol=1e-9))
        h = contact_history(m, "crank_rod", tr.ys)
        return h.force_magnitude, jnp.linalg.norm(h.offset, axis=1) / c, tr.result

    law = MixedLubrication(ShortBearingFilm(0.4, 0.04, c), el.law, 1e-6)
    lubricated = eqx.tree_at(lambda m: m.element("crank_rod").law, mech, law)
    last = np.asarray(ts) > 2 * period
    (f_dry, eps_dry, ok_dry), (f_oil, eps_oil, ok_oil) = run(mech), run(lubricated)
    assert ok_dry == diffrax.RESULTS.successful and ok_oil == diffrax.RESULTS.successful
    f_dry, f_oil = np.asarray(f_dry)[last], np.asarray(f_oil)[last]
    assert float(jnp.max(eps_dry)) > 1.0           # the dry pin presses into the wall
    assert float(jnp.max(eps_oil[1:])) < 0.95      # the journal orbit stays inside
    assert f_dry.max() > 5.0 * np.median(f_dry)    # impacts
    assert f_oil.max() < 0.5 * f_dry.max()         # damped
    assert f_oil.max() < 2.5 * np.median(f_oil)


@pytest.mark.slow  # the whole study on the orbit: ~5 min
def test_the_lubricated_rig_study_is_the_shipped_file_and_wears_less_than_the_dry_rig(
        tmp_path):
    """``diffwear study rig-lubricated``: the shipped file's joint (its oil,
    roughness and finite film, leaf by leaf) on the rig, 21,400 cycles.  On
    the finite film the oil cannot carry the rig's peak load: boundary
    lubrication there (lambda_min = 0), the asperities carry most of the
    load, and the bushing wears less than dry but of its order; the study's
    wear is the shipped file's run (`diffwear run rig_lubricated --cycles
    21400`: 0.2874 mm on the 2-core CPU), a second route to the same number."""
    import json

    from diffwear.cli import main
    from diffwear.config import load
    from diffwear.studies import STUDIES, rig_21400, rig_lubricated

    law = load("rig_lubricated").mechanism.element("crank_rod").law
    ours = rig_lubricated.lubricated(rig_21400._setup()[1]).element("crank_rod").law
    assert type(ours.film) is type(law.film)
    for a, b in zip(jax.tree.leaves(ours.film), jax.tree.leaves(law.film), strict=True):
        np.testing.assert_array_equal(a, b)
    assert float(law.film.viscosity) == rig_lubricated.VISCOSITY
    assert float(law.roughness) == rig_lubricated.ROUGHNESS
    assert "rig-lubricated" in STUDIES
    assert main(["study", "rig-lubricated", "--out", str(tmp_path / "s"), "--quiet"]) == 0
    s = json.loads((tmp_path / "s" / "summary.json").read_text())
    assert s["lubricant"]["film_ratio_min"] == 0.0
    # no film left: the pin presses the asperities past the mean surfaces (the
    # file run's film_crank_rod.csv: 5.9-8.7 um on the unworn bushing)
    assert s["lubricant"]["max_interference_um"] == pytest.approx(8.69, rel=1e-2)
    assert 0.5 < s["lubricant"]["asperity_load_share"] < 0.8
    assert s["max_wear_depth_mm"] == pytest.approx(0.2874, rel=1e-3)
    assert 0.5 * s["dry"]["max_wear_depth_mm"] < s["max_wear_depth_mm"] < s["dry"][
        "max_wear_depth_mm"]
    assert (tmp_path / "s" / "film.png").exists()
