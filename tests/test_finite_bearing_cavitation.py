"""The finite film's mass-conserving cavitation condition (JFO in Elrod &
Adams' p-theta form, `diffwear.contact.mass_conserving`) against the Reynolds
(Swift-Stieber) one where they must agree, an independent flux balance of
every control volume, the long bearing's closed-form film content and
central finite differences of its load."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from long_bearing_closed_form import long_bearing

from diffwear.contact import FiniteBearingFilm, PinKinematics
from diffwear.contact.finite_bearing import _film_forces, reynolds_pressure
from diffwear.contact.mass_conserving import (
    convected_content,
    flux_balance,
    mass_conserving_pressure,
)
from diffwear.contact.reynolds_grid import CLUSTERING
from diffwear.errors import InputError

# A plain journal bearing: R = 10 mm, c = 20 um, mu = 0.02 Pa s, 100 rad/s.
MU, R, C, OMEGA = 0.02, 0.010, 20e-6, 100.0

_reynolds = jax.jit(reynolds_pressure, static_argnames=("n_theta", "n_z", "supply_groove"))
_jfo = jax.jit(mass_conserving_pressure, static_argnames=("n_theta", "n_z", "supply_groove"))


def _kin(eps, rate=(0.0, 0.0), omega=OMEGA, angle=0.4):
    n = jnp.array([np.cos(angle), np.sin(angle)])
    return PinKinematics(offset=eps * C * n, offset_rate=jnp.asarray(rate, dtype=float),
                         omega=jnp.asarray(omega, dtype=float), pin_radius=jnp.asarray(R),
                         bushing_radius=jnp.asarray(R + C))


def _net_outflow(eps, squeeze, wedge, half_length, p, theta):
    """Each cell's net outflow of oil, from the faces' fluxes (numpy, written
    from the discretisation in `finite_bearing`'s notes, not from its
    operators): the pressure flow -H^3 dP/dn through the four faces (P = 0
    beyond the last row, none through the symmetry plane), the full film's
    Couette and squeeze source (the cell's B sin psi - A cos psi times its
    area), less the void's upwind Couette flux B / eps H_face (1 - theta)
    and its squeeze term -A cos psi (1 - theta).  The groove's cells (a
    source) are left out."""
    n_z, n = p.shape
    ds, dz = 2 * np.pi / n, half_length / n_z
    a = CLUSTERING * eps
    s = ds * np.arange(n)
    psi, jac = s - a * np.sin(s), 1 - a * np.cos(s)
    psi_f, jac_f = s + ds / 2 - a * np.sin(s + ds / 2), 1 - a * np.cos(s + ds / 2)
    h, h_f = 1 - eps * np.cos(psi), 1 - eps * np.cos(psi_f)
    dzeta = np.full((n_z, 1), dz)
    dzeta[0] = dz / 2
    # pressure flow through face i + 1/2 (towards i + 1) and from row j to j + 1
    east = -dzeta * h_f**3 / jac_f * (np.roll(p, -1, axis=1) - p) / ds
    above = np.vstack([p[1:], np.zeros((1, n))])
    north = -ds * jac * h**3 * (above - p) / dz
    below = np.vstack([np.zeros((1, n)), north[:-1]])
    pressure = east - np.roll(east, 1, axis=1) + north - below
    source = ds * jac * dzeta * (wedge * np.sin(psi) - squeeze * np.cos(psi))
    r = 1 - theta
    up = r if wedge >= 0 else np.roll(r, -1, axis=1)  # upstream of face i + 1/2
    void = wedge / eps * dzeta * h_f * up
    void_net = void - np.roll(void, 1, axis=1) - ds * jac * dzeta * squeeze * np.cos(psi) * r
    out = pressure + source - void_net
    out[:, n // 2] = 0.0
    return out


# ----------------------------------------------- where the film is full

@pytest.mark.parametrize("squeeze", [0.0, 0.02])
def test_the_conditions_agree_where_the_film_does_not_cavitate(squeeze):
    """eps = 0.05, L/D = 1, the groove at P_s = 1 (the wedge alone peaks at
    0.018): the pressure is positive on every node (at least 2e-3 next to the
    ends), the mass-conserving film is full (theta = 1) and the two conditions
    give the same pressure to round-off."""
    eps, ld, supply = 0.05, 1.0, 1.0
    p_r, _, _ = _reynolds(eps, squeeze, eps, ld, supply_pressure=supply)
    p_m, theta, _, _ = _jfo(eps, squeeze, eps, ld, supply_pressure=supply)
    assert float(jnp.min(p_r)) > 1e-3 * supply
    assert float(jnp.max(jnp.abs(theta - 1.0))) == 0.0
    assert float(jnp.max(jnp.abs(p_m - p_r))) < 1e-13 * float(jnp.max(p_r))


# ----------------------------------------------- mass conservation

# A whirling, approaching pin (L/D = 0.6, eps = 0.6, A = 2 eps_dot = -0.4 /s,
# B = 0.3 /s): the gap opens on the minimum film's side, the cavitated oil
# reaches full film before the groove.
STATE = (0.6, -0.4, 0.3, 0.6)


def test_every_control_volume_balances_its_oil_under_the_mass_conserving_condition():
    p, theta, op, passes = _jfo(*STATE)
    p, theta = np.asarray(p), np.asarray(theta)
    scale = float(jnp.max(op.volume)) * 0.4
    cavitated = theta < 1.0
    assert cavitated.sum() > 50  # a cavitated region, partly filled
    assert np.all(p[cavitated] == 0.0) and np.all(theta[p > 0] == 1.0)
    assert float(np.min(p)) >= 0.0 and float(np.max(theta)) <= 1.0
    out = _net_outflow(*STATE, p, theta)
    assert float(np.max(np.abs(out))) < 1e-11 * scale
    assert 1 < int(passes) < 20


def test_the_reynolds_condition_creates_oil_where_the_film_reforms():
    """The Reynolds film with the content convected through its cavitated
    cells: those balance (by construction), but the full film next to them
    carries away more oil than arrives, by up to 0.76 of the full film's
    largest Couette flux through a cell face (the void fraction arriving
    there, up to 0.97).  (The mass-conserving film's load here is 1.7 %
    higher and its attitude angle 103.0 deg against 107.0 deg.)"""
    p, op, _ = _reynolds(*STATE)
    theta = np.asarray(convected_content(*STATE, p))
    p = np.asarray(p)
    out = _net_outflow(*STATE, p, theta)
    scale = float(jnp.max(op.volume)) * 0.4
    cavitated = (p == 0.0)
    cavitated[:, p.shape[1] // 2] = False
    assert float(np.max(np.abs(out[cavitated]))) < 1e-11 * scale
    eps, _, wedge, half_length = STATE
    face = half_length / p.shape[0] * wedge / eps * (1 + eps)  # dzeta B / eps H_max
    assert float(np.max(out)) > 0.5 * face
    assert float(np.min(out)) > -1e-11 * scale  # created, never lost
    # the module's own balance (from its operators) is this one
    np.testing.assert_allclose(np.asarray(flux_balance(*STATE, p, theta)), out,
                               atol=1e-11 * scale)
    # the oil is created where the convected void meets the full film
    created = out > 1e-6 * scale
    assert np.all(np.roll(cavitated, 1, axis=1)[created] | np.roll(cavitated, -1, axis=1)[created])


# ------------------------------------------- the steadily loaded bearing

@eqx.filter_jit
def _load_and_attitude(film, eps):
    f = film.film(_kin(eps))
    return jnp.linalg.norm(f.force), jnp.degrees(jnp.arctan2(f.tangential, -f.radial))


@pytest.mark.parametrize("eps", [0.2, 0.5, 0.7, 0.9])
def test_the_steady_bearing_is_the_same_under_both_conditions(eps):
    """Groove at the maximum film, L/D = 1: the cavitated oil reaches the
    groove before any full film, so JFO's rupture boundary is Swift-Stieber's
    and the reformation is at the groove: the two conditions' load and
    attitude angle agree (to 1e-9 on this grid: the same pressurised set)."""
    reynolds = FiniteBearingFilm(MU, 2 * R, C)
    jfo = FiniteBearingFilm(MU, 2 * R, C, cavitation="mass-conserving")
    w_r, phi_r = _load_and_attitude(reynolds, jnp.asarray(eps))
    w_m, phi_m = _load_and_attitude(jfo, jnp.asarray(eps))
    assert float(w_m) == pytest.approx(float(w_r), rel=1e-9)
    assert float(phi_m) == pytest.approx(float(phi_r), rel=1e-9)


@pytest.mark.parametrize("eps", [0.3, 0.6])
def test_the_long_bearing_matches_the_closed_form_film_and_its_content(eps):
    """One row (n_z = 1) of half length 1e6 R: the axial flow vanishes and the
    grid solves the long bearing.  Its forces match the quadrature to 3e-4
    (second order in the grid) and its content in the cavitated region
    theta = H* / H to 0.01 (first order: the upwind flux), halving as the
    grid is refined."""
    f_n, f_t, h_star = long_bearing(eps)
    half = 1e6
    errors = []
    for n in (96, 192):
        p, theta, op, _ = _jfo(eps, 0.0, 1.0, half, n_theta=n, n_z=1)
        g_n, g_t = np.asarray(_film_forces(op, p)) / half  # volume = ds J half / 2, both halves
        assert g_n == pytest.approx(f_n, rel=1e-3 if n == 96 else 3e-4)
        assert g_t == pytest.approx(f_t, rel=1e-3 if n == 96 else 3e-4)
        h = 1 - eps * np.cos(np.asarray(op.psi))
        cavitated = np.asarray(theta[0]) < 1.0
        assert cavitated.sum() > n / 4
        errors.append(float(np.max(np.abs(np.asarray(theta[0])[cavitated]
                                          - h_star / h[cavitated]))))
    assert errors[1] < 0.01
    assert errors[1] == pytest.approx(errors[0] / 2, rel=0.1)


# ------------------------------------------------------------- derivatives

@pytest.mark.parametrize("rate", [(0.0, 0.0), (-0.2 * C * OMEGA, 0.1 * C * OMEGA)])
def test_load_derivatives_match_central_differences(rate):
    """d|F|/d eps and d|F|/d mu of the mass-conserving film by the implicit
    derivative at the converged active set, against central differences, for
    the centre at rest and for a moving centre (squeeze and whirl)."""
    def load(eps, mu):
        film = FiniteBearingFilm(mu, 0.012, C, cavitation="mass-conserving")
        return jnp.linalg.norm(film.film(_kin(eps, rate=rate)).force)

    x = (0.7, MU)
    grads = jax.jit(jax.grad(load, argnums=(0, 1)))(*x)
    load = jax.jit(load)
    for k, g in enumerate(grads):
        h = 1e-5 * x[k]
        up, down = list(x), list(x)
        up[k] += h
        down[k] -= h
        fd = (load(*up) - load(*down)) / (2 * h)
        assert float(g) == pytest.approx(float(fd), rel=1e-5)


# ------------------------------------------------------------- bad input

def test_an_unknown_condition_or_no_groove_is_an_input_error():
    with pytest.raises(InputError, match=r"cavitation 'jfo'.*'reynolds' \| 'mass-conserving'"):
        FiniteBearingFilm(MU, 0.01, C, cavitation="jfo")
    with pytest.raises(InputError, match="needs the supply groove"):
        FiniteBearingFilm(MU, 0.01, C, cavitation="mass-conserving", supply_groove=False)
