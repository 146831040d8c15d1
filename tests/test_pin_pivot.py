"""Pin-pivot wear (thesis Ch. 4): the elastic pin against closed forms, the
wear model against hand calculations and bookkeeping, and the study's CLI."""

import jax

jax.config.update("jax_enable_x64", True)

import dataclasses  # noqa: E402

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from diffwear.errors import InputError  # noqa: E402
from diffwear.fem.condense import pressure_load_matrix  # noqa: E402
from diffwear.fem.element import min_jacobian  # noqa: E402
from diffwear.fem.pin import pin_compliance, pin_mesh, solid_disc_compliance  # noqa: E402
from diffwear.studies.pin_pivot_integrator import (  # noqa: E402
    STEEL_E,
    STEEL_NU,
    PinPivot,
    PinPivotSetup,
    linear_extrapolation,
    periodic_sample,
    run_wear,
)

R = 5e-3

#: A small model for the unit tests: 48 nodes (7.5 deg), 4 steps of 15 deg (2 nodes) per sweep.
SMALL = PinPivotSetup(n_theta=48, n_r_pivot=2, n_r_pin=4, steps_per_sweep=4)


@pytest.fixture(scope="module")
def small():
    return PinPivot.build(SMALL)


def _pin_surface_displacement(mesh, mode):
    c = eqx.filter_jit(pin_compliance)(mesh, STEEL_E, STEEL_NU)
    th = np.asarray(mesh.theta)
    return np.asarray(c @ (pressure_load_matrix(mesh) @ jnp.cos(mode * th))), th


def test_pin_mesh_is_not_inverted():
    m = pin_mesh(R, 0.05 * R, 16, 4)
    assert float(jnp.min(jax.vmap(min_jacobian)(m.nodes[m.elements]))) > 0


def test_pin_compliance_matches_solid_disc_closed_form():
    """Inward surface displacement under p cos(n theta) against the solid
    disc (Lame for n = 0, Michell for n >= 2); bore r0 = R / 20."""
    mesh = pin_mesh(R, 0.05 * R, 48, 10)
    # measured: n = 0: 3.6e-3 (the held bore, 1.4 (r0/R)^2), n = 2: 9.5e-3 (3.7 (r0/R)^2),
    # n = 3: 1.6e-3, n = 4: 2.5e-3 (discretisation)
    for mode, tol in [(0, 5e-3), (2, 1.2e-2), (3, 3e-3), (4, 4e-3)]:
        u, th = _pin_surface_displacement(mesh, mode)
        exact = solid_disc_compliance(mode, R, STEEL_E, STEEL_NU) * np.cos(mode * th)
        err = np.max(np.abs(u - exact)) / np.max(np.abs(exact))
        assert err < tol, (mode, err)


def test_pin_bore_effect_vanishes_like_r0_squared():
    """The mode-2 error against the solid disc is the held bore's: it drops
    4x when r0 halves (R/10 -> R/20)."""
    errs = []
    for frac in (0.1, 0.05):
        u, th = _pin_surface_displacement(pin_mesh(R, frac * R, 48, 10), 2)
        exact = solid_disc_compliance(2, R, STEEL_E, STEEL_NU) * np.cos(2 * th)
        errs.append(np.max(np.abs(u - exact)) / np.max(np.abs(exact)))
    assert 3.3 < errs[0] / errs[1] < 4.7, errs  # measured 3.9


def test_solid_disc_closed_form_tends_to_half_plane():
    n = 400  # p cos(k x), k = n / R, on a half-plane: u = 2 (1 - nu^2) p / (E k)
    half_plane = 2 * (1 - STEEL_NU**2) / (STEEL_E * n / R)
    assert abs(solid_disc_compliance(n, R, STEEL_E, STEEL_NU) / half_plane - 1) < 5e-3


def test_periodic_sample_shifts_and_interpolates():
    v = jnp.arange(6.0)
    np.testing.assert_allclose(periodic_sample(v, 2.0), np.roll(np.arange(6.0), -2))
    np.testing.assert_allclose(periodic_sample(v, -0.5)[1], 0.5)
    np.testing.assert_allclose(periodic_sample(v, -0.5)[0], 2.5)  # (5 + 0) / 2


def test_first_sweep_is_archard_hand_calculation(small):
    """One computed sweep at a tiny k (the geometry does not change within
    it): the pivot (load fixed to it) wears k p0(theta) s with p0 the unworn
    contact pressure, the same at every pin angle of the round pin, and
    s = R x 60 deg x A; the pin wears k ds sum_i p0(psi + phi_i)."""
    k, sweeps = 1e-24, 20  # 20 computed sweeps (A = 1), as in the other tests: one compile
    model = eqx.tree_at(lambda m: m.wear_coefficient, small, jnp.asarray(k))
    res = run_wear(model, sweeps, 1.0)
    # independent: one contact solve of the unworn pair (RingContact with the summed compliance)
    sol = model.contact.solve_force(model.force)
    p_pivot = np.asarray(sol.nodal_force / model.pivot_tributary)
    p_pin = np.asarray(sol.nodal_force / model.pin_tributary)
    s_total = sweeps * R * np.radians(60.0)
    np.testing.assert_allclose(res.h_pivot, k * p_pivot * s_total, rtol=1e-9,
                               atol=1e-12 * k * p_pivot.max() * s_total)
    n, step_nodes = SMALL.n_theta, 2  # 15 deg steps at 7.5 deg nodes
    shifts = [-4 + step_nodes * i for i in range(4)] + [4 - step_nodes * i for i in range(4)]
    hand = sum(np.roll(p_pin, -s) for s in shifts) * k * R * np.radians(15.0) * sweeps / 2
    assert n == 48
    np.testing.assert_allclose(res.h_pin, hand, rtol=1e-9, atol=1e-12 * hand.max())
    assert float(p_pivot.max()) > SMALL.projected_pressure  # conformal: peak above F / (D L)


def test_volume_bookkeeping_and_symmetry(small):
    """Both bodies lose k x sum (total normal load x sliding) of volume; after
    whole test cycles of a symmetric oscillation both profiles are symmetric
    about the load direction."""
    res = run_wear(small, 20_000, 1000.0)
    archard = float(small.wear_coefficient * res.load_sliding)
    for body in ("pin", "pivot"):
        assert abs(float(res.volume(small, body)) / archard - 1) < 1e-10
    # the normal load exceeds |F| in a conformal contact
    s_total = 20_000 * R * np.radians(60.0)
    assert res.load_sliding / s_total > 1.05 * SMALL.force
    for h in (np.asarray(res.h_pin), np.asarray(res.h_pivot)):
        mirrored = np.roll(h[::-1], 1)  # h(-theta) on the grid theta_j = 2 pi j / n
        # measured 2.8e-2 (pin), the pivot less: the last sweep's direction is unpaired
        # (1 of 20 computed sweeps at A = 1000, 1.3 um per step on this coarse model)
        assert np.max(np.abs(h - mirrored)) < 4e-2 * h.max()
        assert np.argmax(h) in (0, 1, SMALL.n_theta - 1)  # deepest under the load


def test_wear_depends_on_k_times_sweeps_only(small):
    """Quasi-static: doubling k is doubling the sweeps (same computed sweeps,
    A doubled) to round-off, and at early times the depth is linear in k."""
    k2 = eqx.tree_at(lambda m: m.wear_coefficient, small, 2 * small.wear_coefficient)
    a = run_wear(k2, 2_000, 100.0)
    b = run_wear(small, 4_000, 200.0)
    np.testing.assert_allclose(a.h_pin, b.h_pin, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(a.h_pivot, b.h_pivot, rtol=1e-9, atol=1e-15)
    # early: 2.5e-12 m of wear against ~1e-6 m of elastic approach (1e-18 gave 1e-3)
    early1 = run_wear(eqx.tree_at(lambda m: m.wear_coefficient, small, jnp.asarray(1e-21)),
                      2_000, 100.0)
    early2 = run_wear(eqx.tree_at(lambda m: m.wear_coefficient, small, jnp.asarray(2e-21)),
                      2_000, 100.0)
    np.testing.assert_allclose(early2.h_pivot, 2 * early1.h_pivot, rtol=1e-5,
                               atol=1e-9 * float(early1.h_pivot.max()))


def test_geometric_similarity_depth_scales_with_radius(small):
    """At fixed projected pressure, scaling every dimension by 2 doubles the depth."""
    base = run_wear(small, 20_000, 1000.0)
    big = SMALL.replace(pin_radius=2 * R, clearance=2 * SMALL.clearance,
                        pivot_outer_radius=2 * SMALL.pivot_outer_radius, length=2 * SMALL.length)
    res = run_wear(PinPivot.build(big), 20_000, 1000.0)
    np.testing.assert_allclose(res.h_pin, 2 * base.h_pin, rtol=1e-6,
                               atol=1e-9 * float(base.h_pin.max()))


def test_load_fixed_to_the_pin_swaps_the_roles(small):
    """With the load fixed to the pin, the pin's wear stays under the load and
    the pivot's spreads: the pin is now the deeper one, and it wears about as
    deep as the pivot did with the roles swapped.  The largest depth of this
    coarse model (48 nodes, 4 steps per sweep) is rough in its inputs: a 1e-12
    relative change of k moves it by 0.5 %, 1e-9 by up to 7 % (the contact edge
    jumps a node), while the worn volume moves by < 0.4 %; so the roles are
    compared by volume to 1 % and by depth to 10 %."""
    pin_frame = dataclasses.replace(small, load_frame="pin")
    a = run_wear(small, 20_000, 1000.0)
    b = run_wear(pin_frame, 20_000, 1000.0)
    assert float(a.max_pivot[-1]) > float(a.max_pin[-1])
    assert float(b.max_pin[-1]) > float(b.max_pivot[-1])
    np.testing.assert_allclose(np.sum(b.h_pin), np.sum(a.h_pivot), rtol=1e-2)
    np.testing.assert_allclose(b.max_pin[-1], a.max_pivot[-1], rtol=1e-1)


def test_linear_extrapolation_of_a_line_is_exact():
    s = np.arange(1, 11) * 1e4
    d = 3e-9 * s + 1e-5
    value, slope = linear_extrapolation(s, d, 816_000)
    assert abs(value - (3e-9 * 816_000 + 1e-5)) < 1e-15 and abs(slope - 3e-9) < 1e-20


@pytest.mark.parametrize("field, value, match", [
    ("projected_pressure", 0.0, "projected_pressure"),
    ("projected_pressure", -60e6, "projected_pressure"),
    ("pin_radius", 0.0, "pin_radius"),
    ("pin_radius", float("nan"), "pin_radius"),
    ("length", -1.0, "length"),
    ("clearance", -1e-6, "clearance"),
    ("pivot_outer_radius", 4e-3, "pivot_outer_radius"),
    ("amplitude_deg", 0.0, "amplitude_deg"),
    ("amplitude_deg", 180.0, "amplitude_deg"),
    ("bore_fraction", 1.0, "bore_fraction"),
    ("wear_coefficient", -1e-14, "wear_coefficient"),
    ("poisson_ratio", 0.5, "poisson_ratio"),
    ("load_frame", "ground", "load_frame"),
    ("steps_per_sweep", 0, "steps_per_sweep"),
    ("n_theta", 61, "n_theta"),
])
def test_bad_setup_input_names_the_parameter(field, value, match):
    with pytest.raises(InputError, match=match):
        PinPivotSetup().replace(**{field: value})


def test_bad_run_input(small):
    with pytest.raises(InputError, match="sweeps"):
        run_wear(small, 0, 1.0)
    with pytest.raises(InputError, match="extrapolation"):
        run_wear(small, 100, 0.5)
    with pytest.raises(InputError, match="unknown setup field"):
        PinPivotSetup().replace(radius=1.0)
    with pytest.raises(InputError, match="bore radius"):
        pin_mesh(R, 2 * R, 16, 2)


@pytest.mark.slow  # ~25 s: builds the study's default meshes
def test_study_pin_pivot_writes_its_files(tmp_path):
    """The study at its smallest (2 x A sweeps), without the sensitivity runs."""
    import json

    from diffwear.io import OutputDir
    from diffwear.studies import STUDIES, pin_pivot

    assert STUDIES["pin-pivot"] is pin_pivot
    out = tmp_path / "pp"
    summary = pin_pivot.run(OutputDir(out), cycles=500, sensitivity=False, log=lambda *a: None)
    for name in ("report.md", "summary.json", "profiles.csv", "history.csv",
                 "wear_profiles.png", "wear_history.png"):
        assert (out / name).is_file(), name
    saved = json.loads((out / "summary.json").read_text())
    assert saved["thesis"]["predicted_max_pin_mm_k_1.0e-5"] == 1.867
    assert saved["thesis"]["predicted_max_pin_mm_k_1.2e-5"] == 2.028
    assert saved["target_sweeps"] == 816_000 == 2 * saved["target_test_cycles"]
    assert summary["max_pin_mm_at_408000_test_cycles"] > summary["max_pin_mm_simulated"] > 0
    profiles = np.loadtxt(out / "profiles.csv", delimiter=",", skiprows=1)
    assert profiles.shape == (60, 6) and np.all(profiles[:, 1:5] >= 0)
    assert "1.867" in (out / "report.md").read_text()


def test_cli_lists_pin_pivot(capsys):
    from diffwear.cli import main

    assert main(["study", "--list"]) == 0
    assert "pin-pivot" in capsys.readouterr().out


@pytest.mark.slow
def test_cli_study_pin_pivot_writes_its_files(tmp_path):
    """The whole study through the CLI, scaled down (~1 min on 2 cores)."""
    from diffwear.cli import main

    out = tmp_path / "pp"
    assert main(["study", "pin-pivot", "--out", str(out), "--cycles", "500", "--quiet"]) == 0
    for name in ("report.md", "summary.json", "profiles.csv", "history.csv", "sensitivity.csv",
                 "wear_profiles.png", "wear_history.png"):
        assert (out / name).is_file(), name
