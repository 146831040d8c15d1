"""What both journal-bearing films (`ShortBearingFilm`, `LongBearingFilm`)
must do, checked on each: derivatives against central differences, finite
values and derivatives at the bushing centre and for offsets whose squares
underflow, the centred film's closed forms (squeeze damper, cross-coupled
stiffness, Petroff torque), the film as a contact law, and bad parameters
refused.  Each film's own physics (closed forms, quadratures of its pressure
field, scaling) is in tests/test_lubrication.py and tests/test_long_bearing.py.

Near e = 0 both films are F = -pi K / c (e_dot - omega k x e / 2) to first
order, K their scale: mu R L^3 / (2 c^2) for the short bearing, 6 mu R^3 L /
c^2 for the long one."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.contact import (
    BushingProfile,
    CoulombFriction,
    LongBearingFilm,
    PinKinematics,
    ShortBearingFilm,
)
from diffwear.errors import InputError

# R = 10 mm, c = 50 um, an SAE 30 oil near 60 C (mu ~ 0.04 Pa s); a short
# (Ocvirk) bearing of L = 8 mm (L/D = 0.4) and a long (Sommerfeld) one of
# L = 80 mm (L/D = 4).  (Keyed by name: a test id "long" would read as the
# marker of the long tests.)
MU, R, C = 0.04, 0.010, 50e-6
FILMS = {
    "ocvirk": (ShortBearingFilm, 0.008, lambda length: MU * R * length**3 / (2 * C**2)),
    "sommerfeld": (LongBearingFilm, 0.080, lambda length: 6 * MU * R**3 * length / C**2),
}
OMEGA = 60.0


def _kin(offset, rate=(0.0, 0.0), omega=100.0):
    return PinKinematics(offset=jnp.asarray(offset, dtype=float),
                         offset_rate=jnp.asarray(rate, dtype=float),
                         omega=jnp.asarray(omega, dtype=float),
                         pin_radius=jnp.asarray(R), bushing_radius=jnp.asarray(R + C))


def _polar(eps, angle):
    return C * eps * np.array([np.cos(angle), np.sin(angle)])


def _scale(name):
    _, length, k = FILMS[name]
    return k(length)


def _centre_functions(name):
    """The film's force and torque near the centre (offset and viscosity as
    one argument, the rate as another): value, jacfwd, jacrev, compiled."""
    cls, length, _ = FILMS[name]

    def outputs(params, rate):
        ex, ey, mu = params
        f = cls(mu, length, C).film(_kin(jnp.stack([ex, ey]), rate, OMEGA))
        return jnp.concatenate([f.force, jnp.atleast_1d(f.torque)])

    return {"value": jax.jit(outputs), "jacfwd": jax.jit(jax.jacfwd(outputs)),
            "jacrev": jax.jit(jax.jacrev(outputs))}


CENTRE = {name: _centre_functions(name) for name in FILMS}
PETROFF = {name: -2 * np.pi * MU * OMEGA * R**3 * FILMS[name][1] / C for name in FILMS}


@pytest.mark.parametrize("name", FILMS)
@pytest.mark.parametrize("eps", [0.2, 0.75])
def test_jacobian_matches_central_differences(name, eps):
    """Forward mode in mu, c and e against central differences (1e-6)."""
    cls, length, _ = FILMS[name]

    @jax.jit
    def force_of(params):
        mu, c, ex, ey = params
        return cls(mu, length, c).film(_kin(jnp.stack([ex, ey]), (1.2e-3, -0.4e-3), 95.0)).force

    x0 = np.array([MU, C, *_polar(eps, 2.1)])
    jac = np.asarray(jax.jit(jax.jacfwd(force_of))(jnp.asarray(x0)))
    steps = 1e-6 * np.array([MU, C, C, C])
    fd = np.empty((2, 4))
    for j, h in enumerate(steps):
        dx = np.zeros(4)
        dx[j] = h
        fd[:, j] = (np.asarray(force_of(jnp.asarray(x0 + dx)))
                    - np.asarray(force_of(jnp.asarray(x0 - dx)))) / (2 * h)
    scale = np.abs(fd).max(axis=0)
    np.testing.assert_array_less(np.abs(jac - fd), 1e-6 * np.broadcast_to(scale, fd.shape))


@pytest.mark.parametrize("name", FILMS)
@pytest.mark.parametrize("rate", [(0.0, 0.0), (1e-3, 0.5e-3)])
def test_no_nan_at_the_centre(name, rate):
    """At e = 0: finite values and derivatives; the value is the centred film,
    the squeeze damper -pi K e_dot / c and Petroff's torque."""
    x0, rate = jnp.array([0.0, 0.0, MU]), jnp.asarray(rate)
    for what, fun in CENTRE[name].items():
        assert np.all(np.isfinite(np.asarray(fun(x0, rate)))), what
    value = np.asarray(CENTRE[name]["value"](x0, rate))
    np.testing.assert_allclose(value[:2], -np.pi * _scale(name) * np.asarray(rate) / C,
                               rtol=1e-12, atol=0.0)
    assert value[2] == pytest.approx(PETROFF[name], rel=1e-12)


@pytest.mark.parametrize("name", FILMS)
def test_tiny_offsets_and_rates_stay_finite(name):
    """Offsets and rates whose squares underflow (1e-170 m): the film to first
    order in eps, with finite derivatives."""
    e, rate = np.array([1e-170, -3e-170]), np.array([2e-170, 1e-170])
    x0 = jnp.array([*e, MU])
    for what, fun in CENTRE[name].items():
        assert np.all(np.isfinite(np.asarray(fun(x0, jnp.asarray(rate))))), what
    value = np.asarray(CENTRE[name]["value"](x0, jnp.asarray(rate)))
    assert value[2] == pytest.approx(PETROFF[name], rel=1e-12)
    perp_e = np.array([-e[1], e[0]])
    np.testing.assert_allclose(value[:2],
                               -np.pi * _scale(name) / C * (rate - OMEGA * perp_e / 2),
                               rtol=1e-12)


@pytest.mark.parametrize("name", FILMS)
def test_offset_derivative_has_a_limit_at_the_centre(name):
    """Along a ray towards e = 0 the Jacobian in e tends to a limit (the film is
    linear in e to first order): the same at |e| = 1e-9 c, 1e-20 m and 1e-150 m,
    with no round-off growing like 1 / |e| from the direction of e."""
    direction = np.array([1.0, -3.0]) / np.sqrt(10)
    rate = jnp.array([2e-3, 1e-3])
    jacs = [np.asarray(CENTRE[name]["jacfwd"](jnp.array([*(size * direction), MU]),
                                              rate))[:2, :2]
            for size in (1e-9 * C, 1e-20, 1e-150)]
    for jac in jacs[1:]:
        np.testing.assert_allclose(jac, jacs[0], rtol=1e-6)


@pytest.mark.parametrize("name", FILMS)
def test_centred_spinning_film_has_the_cross_coupled_stiffness(name):
    """e_dot = 0 near e = 0: F = pi K omega / (2 c) k x e to first order, so
    dF/de = pi K omega / (2 c) [[0, -1], [1, 0]], also at e = 0 exactly."""
    stiffness = np.pi * _scale(name) * OMEGA / (2 * C)
    expected = stiffness * np.array([[0.0, -1.0], [1.0, 0.0]])
    for e in (np.zeros(2), np.array([0.3, -0.2]) * 1e-9 * C):
        jac = np.asarray(CENTRE[name]["jacfwd"](jnp.array([*e, MU]), jnp.zeros(2)))[:2, :2]
        np.testing.assert_allclose(jac, expected, rtol=1e-6, atol=1e-9 * stiffness)


@pytest.mark.parametrize("name", FILMS)
def test_evaluate_returns_the_film_force_and_no_contact_pressure(name):
    cls, length, _ = FILMS[name]
    law = cls(MU, length, C)
    kin = _kin(_polar(0.5, 0.3), (1e-3, 0.0), 100.0)
    res = law.evaluate(kin, law.initial_memory(), BushingProfile.circular(C, 36),
                       CoulombFriction())
    film = law.film(kin)
    np.testing.assert_array_equal(np.asarray(res.force), np.asarray(film.force))
    assert float(res.torque) == float(film.torque)
    assert float(res.normal_load) == pytest.approx(float(jnp.linalg.norm(film.force)), rel=1e-14)
    assert np.all(np.asarray(res.pressure) == 0.0) and res.pressure.shape == (36,)


@pytest.mark.parametrize("name", FILMS)
@pytest.mark.parametrize("kwargs, words", [
    (dict(viscosity=0.0), "viscosity"),
    (dict(viscosity=-0.1), "viscosity"),
    (dict(length=0.0), "length"),
    (dict(clearance=-1e-5), "clearance"),
    (dict(clearance=float("nan")), "clearance"),
    (dict(max_eccentricity_ratio=1.0), "eccentricity ratio"),
    (dict(saturation_width=0.96), "saturation width"),
    (dict(viscosity=[0.04, 0.05]), "viscosity"),
])
def test_bad_inputs_are_refused_naming_the_quantity(name, kwargs, words):
    cls, length, _ = FILMS[name]
    args = dict(viscosity=MU, length=length, clearance=C) | kwargs
    with pytest.raises(InputError, match=words):
        cls(**args)
