"""The lubrication guide's stored finite-film data (written by
design_studies/lubrication_figure_data.py, drawn by docs/figures.py): the
Raimondi & Boyd comparison against the table, a fresh solve against stored
rows, and the validity map against the short film's closed form and the
`film_law_for` criterion."""

from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.contact import FiniteBearingFilm, PinKinematics
from diffwear.contact.finite_bearing import SHORT_BEARING_LIMIT, film_law_for, reynolds_forces
from diffwear.contact.raimondi_boyd import RAIMONDI_BOYD

STORE = Path(__file__).resolve().parents[1] / "design_studies" / "results" / "studies" / \
    "lubrication"
# the plain bearing of the stored comparison (lubrication_figure_data.py, as
# tests/test_finite_bearing.py): R = 10 mm, c = 20 um, mu = 0.02 Pa s, 100 rad/s
MU, R, C, OMEGA = 0.02, 0.010, 20e-6, 100.0


def _read(name):
    data = np.genfromtxt(STORE / name, delimiter=",", names=True)
    return {k: np.atleast_1d(data[k]) for k in data.dtype.names}


def test_stored_finite_film_matches_raimondi_boyd():
    """Every table point (L/D = 1/4, 1/2, 1; eps = 0.2 .. 0.9) is a stored row,
    within 1.5 % in S and in the attitude angle."""
    d = _read("raimondi_boyd.csv")
    checked = 0
    for ld, table in RAIMONDI_BOYD.items():
        for eps, (s, phi) in table.items():
            row = np.flatnonzero(np.isclose(d["length_over_diameter"], ld)
                                 & np.isclose(d["eps"], eps))
            assert row.size == 1, (ld, eps)
            assert d["sommerfeld"][row[0]] == pytest.approx(s, rel=0.015), (ld, eps)
            assert d["attitude_deg"][row[0]] == pytest.approx(phi, rel=0.015), (ld, eps)
            checked += 1
    assert checked == 15


@eqx.filter_jit
def _sommerfeld(eps, length):
    kin = PinKinematics(offset=eps * C * jnp.array([1.0, 0.0]), offset_rate=jnp.zeros(2),
                        omega=jnp.asarray(OMEGA), pin_radius=jnp.asarray(R),
                        bushing_radius=jnp.asarray(R + C))
    film = FiniteBearingFilm(MU, length, C, max_eccentricity_ratio=0.995).film(kin)
    # S = (R / c)^2 mu N / P, N = omega / 2 pi, P = W / (2 R L)
    s = (R / C) ** 2 * MU * OMEGA / (2 * jnp.pi) * 2 * R * length / jnp.linalg.norm(film.force)
    return s, jnp.degrees(jnp.arctan2(film.tangential, -film.radial))


@pytest.mark.parametrize("ld, eps", [(0.5, 0.3), (1.0, 0.97)])
def test_a_fresh_solve_gives_the_stored_comparison(ld, eps):
    d = _read("raimondi_boyd.csv")
    row = np.flatnonzero(np.isclose(d["length_over_diameter"], ld) & np.isclose(d["eps"], eps))
    s, phi = _sommerfeld(jnp.asarray(eps), jnp.asarray(2 * R * ld))
    assert float(s) == pytest.approx(d["sommerfeld"][row[0]], rel=1e-6)
    assert float(phi) == pytest.approx(d["attitude_deg"][row[0]], rel=1e-6)


_forces = jax.jit(reynolds_forces, static_argnames=("n_theta", "n_z"))


@pytest.mark.parametrize("row", [0, 150])
def test_a_fresh_solve_gives_the_stored_map(row):
    """Two stored nodes of the validity map (their L/D, eps and rows along the
    half length) solved again: the load and attitude to the 7 digits stored."""
    d = _read("validity_map.csv")
    ld, eps, n_z = d["length_over_diameter"][row], d["eps"][row], int(d["n_z"][row])
    f_n, f_t = _forces(eps, 0.0, eps, ld, n_theta=96, n_z=n_z)
    assert float(np.hypot(f_n, f_t)) == pytest.approx(d["load"][row], rel=1e-6)
    assert float(np.degrees(np.arctan2(f_t, -f_n))) == pytest.approx(d["attitude_deg"][row],
                                                                     rel=1e-6)


def _short_load(ld, eps):
    """The short (Ocvirk) film's steady load in the map's units, 6 mu omega R^4
    / c^2: mu omega R L^3 / c^2 eps sqrt(16 eps^2 + pi^2 (1 - eps^2)) / (4 (1 -
    eps^2)^2) (Hamrock, Schmid & Jacobson) over 6 mu omega R^4 / c^2."""
    return (8.0 * ld**3 / 6.0 * eps * np.sqrt(16 * eps**2 + np.pi**2 * (1 - eps**2))
            / (4 * (1 - eps**2) ** 2))


def test_the_map_agrees_with_the_short_film_criterion():
    """At the map's smallest L/D (0.05) the short film is the finite film to
    1 % up to eps = 0.8; at every stored node where `film_law_for` picks the
    short film, its load is within 4.5 % of the finite film's; at L/D = 1 the
    short film is off by more than 30 % at every eps."""
    d = _read("validity_map.csv")
    ld, eps = d["length_over_diameter"], d["eps"]
    ratio = _short_load(ld, eps) / d["load"]
    first = (ld == ld.min()) & (eps <= 0.8)
    assert first.sum() == 9 and np.all(np.abs(ratio[first] - 1) <= 0.0101)
    inside = np.array([film_law_for(a, e) == "short" for a, e in zip(ld, eps)])
    assert np.all(inside == (ld**2 <= SHORT_BEARING_LIMIT * (1 - eps)))
    assert inside.sum() >= 30
    assert np.all(np.abs(ratio[inside] - 1) < 0.045)
    near_one = np.isclose(ld, ld[np.argmin(np.abs(ld - 1.0))]) & (eps >= 0.2)
    assert np.all(ratio[near_one] > 1.3)


@pytest.mark.parametrize("folder, name, joint", [("rig", "rig_lubricated", "crank_rod"),
                                                 ("four_bar", "four_bar_lubricated",
                                                  "coupler_rocker")])
def test_the_stored_file_runs_are_of_the_shipped_files(folder, name, joint):
    """The guide's stored runs (rig/, four_bar/) ran the shipped file as it is
    now: its film law, oil and roughness."""
    import json

    from diffwear.config import load
    from diffwear.mechanism_file.wear import bearing_name

    run = json.loads((STORE / folder / "summary.json").read_text())
    assert run["file"] == f"src/diffwear/config/mechanisms/{name}.toml"
    law = load(name).mechanism.element(joint).law
    assert run["joints"][joint]["lubricant"] == {
        "viscosity_Pa_s": float(law.film.viscosity), "roughness_um": float(law.roughness) * 1e6,
        "bearing": bearing_name(law)}
    assert bearing_name(law) == "finite"
