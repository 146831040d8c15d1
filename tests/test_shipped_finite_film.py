"""The finite film's shipped moving-journal tables (`ShippedFiniteFilm`):
against direct Reynolds solves at L/D between the tables' nodes, their
derivatives against central differences, the file's default film law
(`film_law_for`), the quasi-static orbit on the finite film (its squeeze
included) under a constant load against the steady finite film, and a file
without ``bearing`` run end to end."""

from __future__ import annotations

import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from test_lubricant_file import LUBRICATED, ROUGH

from diffwear.cli import main
from diffwear.config import load
from diffwear.config.loader import loads as load_text
from diffwear.contact import (
    ArchardWear,
    ClearanceJoint,
    CoulombFriction,
    ElasticFoundation,
    FiniteBearingFilm,
    MixedLubrication,
    PinKinematics,
    ShippedFiniteFilm,
    ShortBearingFilm,
    default_film,
)
from diffwear.contact.finite_bearing import film_law_for, reynolds_forces
from diffwear.contact.finite_table import SHIPPED_RATIOS, SHIPPED_TOP, shipped_tables
from diffwear.errors import InputError
from diffwear.quasistatic import JointLoads, LubricatedQuasiStaticJoint

# A plain journal bearing: R = 10 mm, c = 20 um, mu = 0.02 Pa s.
MU, R, C = 0.02, 0.010, 20e-6


def _shipped(ratio, eps_max=0.95):
    return ShippedFiniteFilm(FiniteBearingFilm(MU, 2 * R * ratio, C,
                                               max_eccentricity_ratio=eps_max), R)


@jax.jit
def _direct(eps, a, b, ratio):
    return jnp.stack(reynolds_forces(eps, a, b, ratio))


@eqx.filter_jit
def _tabled(film, eps, a, b):
    return jnp.stack(film.dimensionless_forces(eps, a, b))


def test_the_tables_are_the_default_grids_over_their_range():
    tables = shipped_tables()
    assert tables.scaled.shape == (21, 25, 32, 2)
    np.testing.assert_allclose(tables.length_over_diameter, np.geomspace(0.05, 4.0, 21))
    assert np.all(np.isfinite(tables.scaled)) and np.all(np.diff(tables.log_envelope[:, -1]) > 0)


# (L/D, eps, phi = atan2(A, B)) between the L/D nodes (the rig's 0.69, near the
# geometric midpoints 0.30 and 2.2 of their intervals) and between the eps
# nodes, up to the mixed law's saturation: wedge, squeeze, reversed and mixed
# drives
CASES = [(0.69, 0.35, 0.0), (0.69, 0.93, 0.5 * np.pi), (0.69, 0.993, 0.0),
         (0.69, 0.8, 2.3), (0.3, 0.6, -0.4), (0.3, 0.985, 0.2),
         (2.2, 0.5, 1.2), (2.2, 0.97, -2.8), (0.078, 0.9, 0.0)]


def _envelope(film, eps):
    """rms of |F| over the drive direction at eps (unit |(A, B)|), from the
    tables: the scale of the force where the film separates and |F| -> 0."""
    phi = jnp.linspace(0.0, 2 * jnp.pi, 64, endpoint=False)
    f = jax.vmap(lambda p: _tabled(film, eps, jnp.sin(p), jnp.cos(p)))(phi)
    return float(jnp.sqrt(jnp.mean(jnp.sum(f**2, axis=-1))))


def test_the_tables_read_the_direct_solves_between_their_nodes():
    """To 1 % of |F|, or of E / 4 where the film separates (|F| < E / 4;
    docs/notes/finite-film-table.md: the shipped tables' error at the L/D
    midpoints, of |F| and of E)."""
    for ratio, eps, phi in CASES:
        a, b = np.sin(phi), np.cos(phi)
        film = _shipped(ratio)
        solved = np.asarray(_direct(eps, a, b, ratio))
        tabled = np.asarray(_tabled(film, jnp.asarray(eps), jnp.asarray(a), jnp.asarray(b)))
        scale = max(np.linalg.norm(solved), 0.25 * _envelope(film, jnp.asarray(eps)))
        assert np.linalg.norm(tabled - solved) <= 0.01 * scale, (ratio, eps, phi, tabled, solved)


def _kin(eps, rate, omega, angle=0.4):
    n = jnp.array([np.cos(angle), np.sin(angle)])
    return PinKinematics(offset=eps * C * n, offset_rate=jnp.asarray(rate, dtype=float),
                         omega=jnp.asarray(omega, dtype=float), pin_radius=jnp.asarray(R),
                         bushing_radius=jnp.asarray(R + C))


def test_derivatives_in_viscosity_length_and_eccentricity_match_central_differences():
    """d F / d(mu, L, eps) of the shipped film's force for a moving journal
    (squeeze and wedge) at L/D 0.69, against central differences."""

    def force(x):
        mu, length, eps = x
        film = ShippedFiniteFilm(FiniteBearingFilm(mu, length, C, max_eccentricity_ratio=0.99),
                                 R)
        return film.film(_kin(eps, (2e-4, -1e-4), 70.0)).force

    x = jnp.array([MU, 2 * R * 0.69, 0.83])
    jac = np.asarray(jax.jit(jax.jacfwd(force))(x))
    f = jax.jit(force)
    for k, h in enumerate((1e-6, 1e-7, 1e-6)):
        dx = jnp.zeros(3).at[k].set(h)
        fd = (np.asarray(f(x + dx)) - np.asarray(f(x - dx))) / (2 * h)
        np.testing.assert_allclose(jac[:, k], fd, rtol=1e-5, atol=1e-7 * np.abs(fd).max())


def test_out_of_the_tables_is_an_input_error():
    with pytest.raises(InputError, match=r"L/D = 4.5 is outside the shipped tables; "
                                         r"allowed: 0.05 <= L/D <= 4"):
        _shipped(4.5)
    with pytest.raises(InputError, match=r"L/D = 0.04 is outside"):
        _shipped(0.04)
    with pytest.raises(InputError, match=r"eccentricity ratio = 0.9984 is above the shipped "
                                         rf"tables' top; allowed: <= {SHIPPED_TOP}"):
        _shipped(0.7, eps_max=0.9984)
    with pytest.raises(InputError, match="the Reynolds condition only: n_theta = 48"):
        ShippedFiniteFilm(FiniteBearingFilm(MU, 0.014, C, n_theta=48), R)
    assert SHIPPED_RATIOS[0] == pytest.approx(0.05) and SHIPPED_RATIOS[-1] == pytest.approx(4.0)


# ------------------------------------------------------------ the default film law


def _rig_text(*edits):
    text = LUBRICATED.read_text()
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    return text


def test_the_default_film_is_the_one_that_holds_for_the_joint():
    """Without ``bearing``: the rig's L/D = 13.1 / 19 = 0.69 at eps_max =
    1 - 0.65 / 33 = 0.980 gets the finite film (the short one would need
    (L/D)^2 <= 0.05 (1 - eps_max) = 1e-3), a 0.5 mm long film (L/D 0.026)
    the short one; an explicit short film stays short."""
    assert film_law_for(0.69, 0.997) == "finite"
    assert film_law_for(0.026, 0.98) == "short"
    el = load_text(_rig_text()).mechanism.element("crank_rod")
    film = el.law.film
    assert isinstance(film, ShippedFiniteFilm)
    assert float(film.length_over_diameter) == pytest.approx(13.1 / 19)
    assert float(film.max_eccentricity_ratio) == pytest.approx(1 - 0.65 / 33)
    short = load_text(_rig_text(('roughness = "0.65 um"',
                                 'roughness = "0.65 um", length = "0.5 mm"'))
                      ).mechanism.element("crank_rod")
    assert type(short.law.film) is ShortBearingFilm
    explicit = load_text(_rig_text((ROUGH, ROUGH + ', bearing = "short"'))
                         ).mechanism.element("crank_rod")
    assert type(explicit.law.film) is ShortBearingFilm
    shipped = load("rig_lubricated").mechanism.element("crank_rod")
    assert type(shipped.law.film) is ShippedFiniteFilm


@pytest.mark.parametrize("name, joint", [("rig_lubricated", "crank_rod"),
                                         ("four_bar_lubricated", "coupler_rocker")])
def test_default_film_is_the_film_a_file_gets(name, joint):
    """`default_film` from Python gives the shipped files' films leaf by leaf
    (both finite: L/D 0.69 and 0.83); a 0.5 mm bushing on the rig's 9.5 mm
    pin (L/D = 0.026, (L/D)^2 = 6.9e-4 <= 0.05 (1 - 0.98) = 1e-3) the short
    one; traced geometry cannot choose a law."""
    el = load(name).mechanism.element(joint)
    film, c = el.law.film, el.bushing_radius - el.pin_radius
    eps_max = MixedLubrication.saturation(el.law.roughness, c)
    ours = default_film(film.viscosity, film.length, c, el.pin_radius, eps_max)
    assert type(ours) is type(film) is ShippedFiniteFilm
    for a, b in zip(jax.tree.leaves(ours), jax.tree.leaves(film), strict=True):
        np.testing.assert_array_equal(a, b)
    assert type(default_film(0.01, 0.5e-3, 33e-6, 9.5e-3, 0.98)) is ShortBearingFilm
    with pytest.raises(InputError, match="must be concrete"):
        jax.jit(lambda r: default_film(0.01, 0.01, c, r, 0.98).viscosity)(0.01)


def test_a_default_finite_film_outside_the_tables_says_so():
    with pytest.raises(Exception, match=r"lubricant.length.*L/D = length / \(2 pin radius\) "
                                        r"= 10.53 is outside its shipped tables \(the default "
                                        r"film: the short film is out of its range"):
        load_text(_rig_text(('roughness = "0.65 um"',
                             'roughness = "0.65 um", length = "0.2 m"')))


# ------------------------------------------------------------ the orbit
def _finite_joint(film):
    law = MixedLubrication(film, ElasticFoundation(1e13, 0.014), 0.1e-6)
    return ClearanceJoint("j", "a", [0.0, 0.0], "b", [0.0, 0.0], R, R + C, law,
                          friction=CoulombFriction(0.1), wear=ArchardWear(1e-14), n_theta=90)


def test_the_orbit_under_a_constant_load_is_the_steady_finite_film():
    """A constant load: the orbit on the shipped film (with its squeeze) is a
    fixed point, e_dot = 0 (to the Newton tolerance), and there the direct
    Reynolds solve of the centre at rest carries the load to the tables'
    accuracy (1.5 %; the asperities carry nothing at lambda > 20)."""
    film = FiniteBearingFilm(MU, 0.014, C)  # L/D 0.7
    joint = LubricatedQuasiStaticJoint.from_joint(_finite_joint(film))
    assert isinstance(joint.law.film, ShippedFiniteFilm) and joint.squeeze
    s, load = 12, jnp.array([300.0, -150.0])
    loads = JointLoads(force=jnp.tile(load[None, :], (s, 1)), omega=jnp.full(s, 100.0),
                       period=jnp.asarray(0.1))
    depth = jnp.zeros(joint.n)
    orbit = eqx.filter_jit(lambda j: j.equilibrium(depth, loads))(joint)
    assert bool(orbit.ok) and bool(orbit.orbit_closed)
    e = np.asarray(orbit.offset)
    np.testing.assert_allclose(e, np.tile(e[:1], (s, 1)), rtol=0, atol=1e-10 * C)
    eps = np.linalg.norm(e[0]) / C
    assert 0.5 < eps < 0.95 and float(np.min(orbit.film_ratio)) > 20.0
    direct = FiniteBearingFilm(MU, 0.014, C, max_eccentricity_ratio=0.995).film(
        PinKinematics(offset=jnp.asarray(e[0]), offset_rate=jnp.zeros(2),
                      omega=jnp.asarray(100.0), pin_radius=jnp.asarray(R),
                      bushing_radius=jnp.asarray(R + C)))
    assert float(jnp.linalg.norm(direct.force + load)) <= 0.015 * float(jnp.linalg.norm(load))


# ------------------------------------------------------------ a file without bearing
@pytest.mark.slow  # a whole run (motion, 2000 cycles of wear, the film): 3-9 min on 2 cores
def test_a_file_without_bearing_runs_on_the_finite_film(tmp_path):
    """The lubricated rig without ``bearing`` (the finite film, by default),
    a short motion and 2000 cycles: the run reports the finite film, on which
    the rig's joint is in boundary lubrication near its peak load
    (docs/guide/lubrication.md): the film thins to nothing, the asperities
    carry part of the load and the bushing wears."""
    text = _rig_text(("n_theta = 180", "n_theta = 90"),
                     ('duration = "2 s"', 'duration = "0.01 s"'), ("n_save = 401", "n_save = 11"))
    path = tmp_path / "rig_default_film.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["run", str(path), "--cycles", "2000", "--out", str(out), "--quiet"]) == 0
    joint = json.loads((out / "summary.json").read_text())["joints"]["crank_rod"]
    assert joint["lubricant"]["bearing"] == "finite"
    assert joint["min_film_thickness_um"] == 0.0 and joint["max_interference_um"] > 0.0
    assert 0.0 < joint["asperity_load_share"] < 1.0 and joint["max_wear_depth_mm"] > 0.0
