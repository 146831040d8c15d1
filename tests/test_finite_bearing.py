"""The finite-length hydrodynamic film (`FiniteBearingFilm`) against Raimondi &
Boyd's tables, the short (Ocvirk) bearing as L/D -> 0, an independent
Reynolds-condition solution of the long bearing as L/D -> infinity, its
complementarity conditions, and central finite differences of its load."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from long_bearing_closed_form import long_bearing
from scipy.integrate import quad

from diffwear.contact import FiniteBearingFilm, PinKinematics, ShortBearingFilm
from diffwear.contact.finite_bearing import reynolds_forces, reynolds_pressure
from diffwear.contact.raimondi_boyd import RAIMONDI_BOYD
from diffwear.contact.reynolds_grid import _apply, _resolved_eccentricity
from diffwear.errors import InputError

# A plain journal bearing: R = 10 mm, c = 20 um, mu = 0.02 Pa s, 100 rad/s.
MU, R, C, OMEGA = 0.02, 0.010, 20e-6, 100.0


def _kin(eps, rate=(0.0, 0.0), omega=OMEGA, angle=0.4, clearance=C):
    n = jnp.array([np.cos(angle), np.sin(angle)])
    return PinKinematics(offset=eps * clearance * n,
                         offset_rate=jnp.asarray(rate, dtype=float),
                         omega=jnp.asarray(omega, dtype=float),
                         pin_radius=jnp.asarray(R),
                         bushing_radius=jnp.asarray(R + clearance))


@eqx.filter_jit
def _steady(eps, length_over_diameter):
    """(S, attitude angle [deg]) of the steadily loaded film: Sommerfeld number
    S = (R / c)^2 mu N / P, N = omega / 2 pi [rev/s], P = W / (2 R L)."""
    length = 2.0 * R * length_over_diameter
    film = FiniteBearingFilm(MU, length, C).film(_kin(eps))
    load = jnp.linalg.norm(film.force)
    s = (R / C) ** 2 * MU * OMEGA / (2 * jnp.pi) / (load / (2 * R * length))
    return s, jnp.degrees(jnp.arctan2(film.tangential, -film.radial))


# Raimondi & Boyd's table (full journal bearing, Reynolds cavitation; source
# in `diffwear.contact.raimondi_boyd`).  Each value is also within 1.3 % (S) and
# 1.2 % (phi) of this solver on a 192 x 24 grid, twice the default in both
# directions.
CASES = [(ld, eps, *v) for ld, table in RAIMONDI_BOYD.items() for eps, v in table.items()]


def test_x64_is_on():
    assert jnp.zeros(1).dtype == jnp.float64


@pytest.mark.parametrize("ld, eps, s_table, phi_table", CASES)
def test_sommerfeld_number_and_attitude_match_raimondi_boyd(ld, eps, s_table, phi_table):
    s, phi = _steady(jnp.asarray(eps), jnp.asarray(ld))
    assert float(s) == pytest.approx(s_table, rel=0.02)
    assert float(phi) == pytest.approx(phi_table, rel=0.02)


def test_the_load_grows_with_eccentricity_and_length():
    s = np.array([[float(_steady(jnp.asarray(eps), jnp.asarray(ld))[0])
                   for eps in (0.3, 0.6, 0.9)] for ld in (0.25, 0.5, 1.0)])
    assert np.all(np.diff(s, axis=1) < 0)  # S ~ 1 / load falls with eps
    assert np.all(np.diff(s, axis=0) < 0)  # and with L/D (load per area grows)


# ------------------------------------------------------------- the two limits

@eqx.filter_jit
def _short_and_finite(eps, rate, length):
    kin = _kin(eps, rate=rate)
    return ShortBearingFilm(MU, length, C).film(kin), FiniteBearingFilm(MU, length, C).film(kin)


@pytest.mark.parametrize("eps", [0.2, 0.5, 0.8, 0.9])
def test_short_bearing_limit(eps):
    """L/D = 1/40: the short (Ocvirk) film's load and attitude to 1 %, in a
    general dynamic state too (squeeze, wedge and whirl, the positive half away
    from the supply line)."""
    length = jnp.asarray(2 * R / 40.0)
    for rate in [(0.0, 0.0), (0.3 * C * OMEGA, -0.1 * C * OMEGA)]:
        short, finite = _short_and_finite(jnp.asarray(eps), jnp.asarray(rate), length)
        assert float(jnp.linalg.norm(finite.force)) == pytest.approx(
            float(jnp.linalg.norm(short.force)), rel=0.01)
        cos_angle = (finite.force @ short.force
                     / (jnp.linalg.norm(finite.force) * jnp.linalg.norm(short.force)))
        assert float(cos_angle) > np.cos(0.01)
        assert float(finite.torque) == pytest.approx(float(short.torque), rel=0.01)


def test_pure_squeeze_matches_the_short_bearing_at_small_length():
    """No spin, the pin approaching the bushing along the line of centres at
    eps_dot = 0.5 /s: the short bearing's squeeze film -K A I_cc, A = 2 eps_dot,
    K = mu R L^3 / (2 c^2), I_cc the integral of cos^2 psi / (1 - eps cos psi)^3
    over the half facing the approach, -pi/2 .. pi/2 (by quadrature)."""
    ld, eps = 1.0 / 40.0, 0.6
    length = 2 * R * ld
    kin = _kin(eps, rate=0.5 * C * np.array([np.cos(0.4), np.sin(0.4)]), omega=0.0)
    k = MU * R * length**3 / (2 * C**2)
    i_cc = quad(lambda p: np.cos(p) ** 2 / (1 - eps * np.cos(p)) ** 3, -np.pi / 2, np.pi / 2,
                epsrel=1e-12)[0]
    closed = -k * (2 * 0.5) * i_cc
    finite = FiniteBearingFilm(MU, length, C).film(kin)
    assert float(finite.radial) == pytest.approx(closed, rel=0.01)
    assert abs(float(finite.tangential)) < 1e-6 * abs(closed)


_forces = jax.jit(lambda eps, ld, n_theta=96, n_z=12: reynolds_forces(
    eps, 0.0, eps, ld, n_theta=n_theta, n_z=n_z), static_argnames=("n_theta", "n_z"))


@pytest.mark.extended  # ~45 s on 2 cores: grids of 96 x 48 and 96 x 96
@pytest.mark.parametrize("eps", [0.2, 0.5, 0.8])
def test_long_bearing_limit_with_reynolds_cavitation(eps):
    """L/D -> infinity: the load per length approaches the infinitely long
    bearing's (Reynolds condition) as 1 - a D / L (the end leakage lives in a
    layer of fixed width in zeta = z / R); the extrapolation of L/D = 8 and 16
    to D / L = 0 matches it to 1 % in load and attitude angle."""
    f_n, f_t, _ = long_bearing(eps)
    ratios = []
    for ld, n_z in [(8.0, 48), (16.0, 96)]:
        g_n, g_t = _forces(eps, ld, n_z=n_z)
        long_n, long_t = 2 * ld * eps * f_n, 2 * ld * eps * f_t
        ratios.append((np.hypot(g_n, g_t) / np.hypot(long_n, long_t),
                       np.arctan2(g_t, -g_n) / np.arctan2(long_t, -long_n)))
    (load_8, phi_8), (load_16, phi_16) = ratios
    assert float(2 * load_16 - load_8) == pytest.approx(1.0, abs=0.01)
    assert float(2 * phi_16 - phi_8) == pytest.approx(1.0, abs=0.01)
    assert 0.9 < float(load_16) < 1.0  # and the finite bearing carries less


# ------------------------------------------------- the complementarity problem

def test_pressure_is_a_complementarity_solution():
    """P >= 0, K P + q >= 0 and P (K P + q) = 0 on the grid, in a state with
    squeeze (the positive region is not the steady one)."""
    eps, squeeze, wedge, ld = 0.7, 0.4, 0.5, 0.6
    p, op, passes = jax.jit(reynolds_pressure)(eps, squeeze, wedge, ld)
    f = wedge * jnp.sin(op.psi) - squeeze * jnp.cos(op.psi)
    w = _apply(op, p) + op.volume * f[None, :]
    scale = float(jnp.max(jnp.abs(op.volume * f[None, :])))
    assert float(jnp.min(p)) >= 0.0
    groove = np.ones(p.shape[1], bool)
    groove[p.shape[1] // 2] = False  # the supply line carries its reaction
    assert float(jnp.min(w[:, groove])) > -1e-10 * scale
    assert float(jnp.max(jnp.abs(p * w))) < 1e-10 * scale * float(jnp.max(p))
    assert 1 < int(passes) < 30


@pytest.mark.extended  # ~10 s: a 192 x 24 grid
def test_grid_convergence_near_contact():
    """At eps = 0.99 the default grid's load is within 1.5 % of a grid twice
    as fine in both directions."""
    coarse = _forces(0.99, 0.7)
    fine = _forces(0.99, 0.7, n_theta=192, n_z=24)
    assert float(np.hypot(*coarse)) == pytest.approx(float(np.hypot(*fine)), rel=0.015)


# ------------------------------------------------------------- derivatives

def test_load_derivatives_match_central_differences():
    """d|F|/d(eps, mu, L, c) by the implicit derivative at the converged
    active set, against central differences."""
    def load(eps, mu, length, clearance):
        film = FiniteBearingFilm(mu, length, clearance)
        return jnp.linalg.norm(film.film(_kin(eps, clearance=clearance)).force)

    x = (0.7, MU, 0.012, C)
    grads = jax.jit(jax.grad(load, argnums=(0, 1, 2, 3)))(*x)
    load = jax.jit(load)
    for k, g in enumerate(grads):
        h = 1e-5 * x[k]
        up = list(x)
        down = list(x)
        up[k] += h
        down[k] -= h
        fd = (load(*up) - load(*down)) / (2 * h)
        assert float(g) == pytest.approx(float(fd), rel=1e-5)


@pytest.mark.extended  # ~10 s
def test_force_derivative_in_the_pin_state():
    """d F / d(e, e_dot) against central differences (the film's damping and
    stiffness)."""
    film = FiniteBearingFilm(MU, 0.012, C)

    def force(state):
        return film.film(PinKinematics(offset=state[:2], offset_rate=state[2:],
                                       omega=jnp.asarray(OMEGA), pin_radius=jnp.asarray(R),
                                       bushing_radius=jnp.asarray(R + C))).force

    x = jnp.array([0.5 * C, 0.4 * C, 0.2 * C * OMEGA, -0.1 * C * OMEGA])
    jac = jax.jit(jax.jacfwd(force))(x)
    force = jax.jit(force)
    for k in range(4):
        h = 1e-6 * (C if k < 2 else C * OMEGA)
        fd = (force(x.at[k].add(h)) - force(x.at[k].add(-h))) / (2 * h)
        np.testing.assert_allclose(jac[:, k], fd, rtol=1e-4,
                                   atol=1e-6 * float(jnp.max(jnp.abs(fd))))


# ------------------------------------------------------------- bad input

def test_grid_too_coarse_for_the_eccentricity_is_an_input_error():
    top = _resolved_eccentricity(32)
    with pytest.raises(InputError, match=r"n_theta = 32 .*0\.99.*allowed: n_theta >= \d+"):
        FiniteBearingFilm(MU, 0.01, C, max_eccentricity_ratio=0.99, n_theta=32)
    FiniteBearingFilm(MU, 0.01, C, max_eccentricity_ratio=0.9 * top, n_theta=32)
    with pytest.raises(InputError, match="even"):
        FiniteBearingFilm(MU, 0.01, C, n_theta=97)
    with pytest.raises(InputError, match="n_z"):
        FiniteBearingFilm(MU, 0.01, C, n_z=1)


# ------------------------------------------------------------- the default law

@pytest.mark.parametrize("ld, eps_max", [(0.09, 0.8), (0.3, 0.2), (0.05, 0.95), (0.03, 0.98)])
def test_the_short_film_is_picked_only_where_it_is_within_4_5_percent(ld, eps_max):
    """`film_law_for` picks the short film on its boundary (L/D)^2 = 0.05 (1 - eps)
    and inside it; there its load is within 4.5 % of the finite film's at every
    eps up to eps_max, and just outside it the finite film is picked."""
    from diffwear.contact.finite_bearing import film_law_for

    assert film_law_for(ld, eps_max) == ("short" if ld**2 <= 0.05 * (1 - eps_max)
                                         else "finite")
    edge = np.sqrt(0.05 * (1 - eps_max))
    assert film_law_for(edge * 0.999, eps_max) == "short"
    assert film_law_for(edge * 1.01, eps_max) == "finite"
    for eps in np.linspace(0.2, eps_max, 3):
        short, finite = _short_and_finite(jnp.asarray(eps), jnp.zeros(2),
                                          jnp.asarray(2 * R * edge * 0.999))
        ratio = float(jnp.linalg.norm(short.force) / jnp.linalg.norm(finite.force))
        assert 1.0 <= ratio < 1.045, (eps, ratio)


def test_a_run_names_a_short_film_out_of_its_range(tmp_path):
    """The shipped lubricated rig (L/D = 0.69, eps up to 1 - sigma / c = 0.98)
    names the short film out of its range, and the run says so; with a
    0.3 mm long bushing (L/D = 0.016, the short film by default), the finite
    film, or no ``bearing`` (the finite film by default) it does not."""
    from diffwear.choices import SHIPPED_MECHANISMS
    from diffwear.config import load
    from diffwear.contact.finite_bearing import film_out_of_range
    from diffwear.mechanism_file.wear import bearing_name

    text = (SHIPPED_MECHANISMS / "rig_lubricated.toml").read_text()
    assert 'roughness = "0.65 um" }' in text
    notes = []
    for k, extra in enumerate((', bearing = "short"', ', length = "0.3 mm"',
                               ', bearing = "finite"', "")):
        path = tmp_path / f"rig{k}.toml"
        path.write_text(text.replace('roughness = "0.65 um" }',
                                     'roughness = "0.65 um"' + extra + " }"))
        joint = load(path).mechanism.element("crank_rod")
        notes.append(film_out_of_range(bearing_name(joint.law), joint.law, joint.pin_radius))
    assert "L/D = 0.689" in notes[0] and "0.98" in notes[0] and 'bearing = "finite"' in notes[0]
    assert notes[1] is None and notes[2] is None and notes[3] is None


# ------------------------------------------------------------- the steady table

@pytest.fixture(scope="module")
def steady_pair():
    film = FiniteBearingFilm(MU, 0.013, C, max_eccentricity_ratio=0.995)
    return film, eqx.filter_jit(lambda f: f.steady(R))(film)


@eqx.filter_jit
def _solved_and_tabled(film, table, eps, omega):
    kin = _kin(eps, omega=omega, angle=1.1)
    return film.film(kin).force, table.film(kin).force


@pytest.mark.extended  # ~30 s on 2 cores: the table's 56 solves
def test_the_steady_table_is_the_solve_with_the_centre_at_rest(steady_pair):
    """`SteadyFiniteFilm` (56 solves, cubic in w = sqrt(-ln(1 - eps))) against the
    finite film's own solve, both senses of rotation, to 1e-3 (of the load at
    eps = 0.1 near the centre, where the load vanishes)."""
    film, table = steady_pair
    floor = float(jnp.linalg.norm(_solved_and_tabled(film, table, jnp.asarray(0.1),
                                                     jnp.asarray(OMEGA))[0]))
    for eps in [0.0, 0.03, 0.2, 0.55, 0.85, 0.95, 0.99, 0.995]:
        for omega in (OMEGA, -0.3 * OMEGA):
            solved, tabled = _solved_and_tabled(film, table, jnp.asarray(eps),
                                                jnp.asarray(omega))
            assert float(jnp.linalg.norm(tabled - solved)) <= 1e-3 * max(
                float(jnp.linalg.norm(solved)), 1e-3 * floor), (eps, omega)


@pytest.mark.slow  # ~60-90 s on 2 cores: one table and its Newton solves (--long)
def test_the_quasi_static_joint_balances_the_load_on_the_finite_film():
    """A film-borne pin (roughness 1 nm: no asperity contact) of a
    `LubricatedQuasiStaticJoint` on the finite film: at its equilibrium the
    finite film's own solve (not the table the joint uses) carries the load to
    1e-3, at a light and a heavy load."""
    from diffwear.contact import (
        ArchardWear,
        ClearanceJoint,
        CoulombFriction,
        ElasticFoundation,
        MixedLubrication,
    )
    from diffwear.quasistatic import LubricatedQuasiStaticJoint

    film = FiniteBearingFilm(MU, 0.012, C)
    law = MixedLubrication(film, ElasticFoundation(1e13, 0.012), 1e-9)
    joint = ClearanceJoint("j", "a", [0.0, 0.0], "b", [0.0, 0.0], R, R + C, law,
                           friction=CoulombFriction(0.1), wear=ArchardWear(1e-14),
                           n_theta=90)
    solve = eqx.filter_jit(lambda w: LubricatedQuasiStaticJoint.from_joint(joint).pin_offset(
        w, jnp.asarray(OMEGA), jnp.full(90, C)))
    for load in (20.0, 2000.0):
        w = jnp.array([0.3, -1.0]) * load / np.hypot(0.3, 1.0)
        e, ok = solve(w)
        assert float(ok) == 1.0
        kin = PinKinematics(offset=e, offset_rate=jnp.zeros(2), omega=jnp.asarray(OMEGA),
                            pin_radius=jnp.asarray(R), bushing_radius=jnp.asarray(R + C))
        # the joint's film is saturated at lambda = 1, eps_max = 0.995 (not the
        # film's own default, 0.95)
        force = eqx.filter_jit(lambda k: law.saturated_film().film(k).force)(kin)
        assert float(jnp.linalg.norm(force + w)) < 1e-3 * load
        assert 0.05 < float(jnp.linalg.norm(e)) / C < 0.995


# ------------------------------------------------------------- the soft bore

def test_peak_pressure_of_the_finite_film_tends_to_the_short_film_s():
    """L/D = 1/40: the finite film's largest grid pressure against the short
    film's closed-form peak 3 mu L^2 / (4 c^2) eps omega max sin / (1 - eps cos)^3,
    to 1 %."""
    length = 2 * R / 40.0
    for eps in (0.3, 0.8):
        short = ShortBearingFilm(MU, length, C).steady_peak_pressure(eps, OMEGA, R)
        film = FiniteBearingFilm(MU, length, C)
        finite = eqx.filter_jit(lambda e, f=film: f.steady_peak_pressure(e, OMEGA, R))(
            jnp.asarray(eps))
        assert float(finite) == pytest.approx(float(short), rel=0.01)


def test_the_soft_bore_check_compares_the_deflection_with_the_film():
    """p / k_f against a quarter of the film thickness, sample by sample."""
    from diffwear.cli.run import _soft_bore

    f = {"min_film_thickness": np.array([2e-6, 1e-6]),
         "bore_deflection": np.array([0.4e-6, 0.2e-6]),
         "film_peak_pressure": np.array([4e6, 2e6])}
    assert _soft_bore(f) is None  # 0.4 <= 0.5 and 0.2 <= 0.25 um
    f["bore_deflection"] = np.array([0.4e-6, 0.3e-6])
    note = _soft_bore(f)
    assert "2 MPa" in note and "0.3 um" in note and "1 um" in note and "not self-consistent" in note
