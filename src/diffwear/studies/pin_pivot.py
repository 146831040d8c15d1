"""Study ``pin-pivot``: the thesis's pin-pivot wear test and simulation (Ch. 4,
Tables 4-1..4-3, Fig. 4-9).

A steel pin oscillating +-30 deg in a steel pivot under 60 MPa projected
pressure; both bodies wear (Archard, k = 1.0e-5 mm^3/(N m)); FEM contact with
both bodies elastic (`diffwear.studies.pin_pivot_integrator`).  Like the thesis: 100,000
simulated sweeps at 10 steps per sweep, then a linear extrapolation of the
max pin wear to the test's 408,000 test cycles = 816,000 sweeps.  Also: a
direct run of twice the sweeps (checks the linear extrapolation), k = 1.2e-5,
the other load frame, steps per sweep, mesh, compliance, extrapolation factor
and size.
"""

from __future__ import annotations

import dataclasses
import math
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check_int_option
from ..io import OutputDir
from ..plots import pin_pivot as plots
from ..report import Bullets, Figure, Report, Section, Table, render
from .pin_pivot_integrator import (
    SWEEPS_PER_TEST_CYCLE,
    THESIS_K,
    THESIS_K_HIGH,
    THESIS_SIM_SWEEPS,
    THESIS_TEST_CYCLES,
    PinPivot,
    PinPivotSetup,
    linear_extrapolation,
    run_wear,
    steady_line,
)

NAME = "pin-pivot"
DESCRIPTION = ("Ch. 4: steel pin in a steel pivot, +-30 deg, 60 MPa, both bodies wear (FEM); "
               "408,000 test cycles")

#: Extrapolation factor A (one computed sweep = A sweeps).  Measured on the
#: default model (100,000 sweeps, n_theta 60): A = 250 and 500 give the same
#: max pin wear to 1e-4 and a smooth pressure (peak ~95 MPa); at A = 1000 the
#: pressure turns wavy (peaks ~280 MPa: the instability of thesis
#: Fig. 4-10b), although the max depth still agrees to 1e-3.  At n_theta 120
#: the limit is lower (A = 250 smooth, 500 wavy; A = 50, 100, 250 agree to 1e-4).
EXTRAPOLATION = 250

TARGET_SWEEPS = THESIS_TEST_CYCLES * SWEEPS_PER_TEST_CYCLE  # 816,000

THESIS = {  # Tables 4-1, 4-3 and the Ch. 4 summary
    "simulated, k 1.0e-5 (Table 4-3)": 1.867,
    "simulated, k 1.2e-5 (Ch. 4 summary)": 2.028,
    "measured (Table 4-1)": 2.00,
}
THESIS_TIME_MIN = 206  # Table 4-3, "step update" simulation time


def _run(model, sweeps, extrapolation):
    t0 = time.perf_counter()
    res = run_wear(model, sweeps, extrapolation)
    jax.block_until_ready(res.h_pin)
    return res, time.perf_counter() - t0


def _extrapolated(res, target):
    pin, s_pin = linear_extrapolation(res.sweeps, res.max_pin, target)
    pivot, s_piv = linear_extrapolation(res.sweeps, res.max_pivot, target)
    return pin, pivot, s_pin, s_piv


def _row(label, res, run_s, pin_816, pivot_816) -> dict:
    """One row of the sensitivity table (depths in mm, pressure in MPa)."""
    return {"case": label, "max_pin_mm_simulated": 1e3 * float(res.max_pin[-1]),
            "max_pivot_mm_simulated": 1e3 * float(res.max_pivot[-1]),
            "max_pin_mm_at_816000": 1e3 * pin_816, "max_pivot_mm_at_816000": 1e3 * pivot_816,
            "peak_pressure_MPa_last_sweep": float(res.peak_pressure[-1]) / 1e6,
            "run_s": run_s}


def run(out: OutputDir, *, cycles: int = THESIS_SIM_SWEEPS, sensitivity: bool = True,
        log=print) -> dict:
    """``cycles``: simulated sweeps before the linear extrapolation (the
    thesis's "cycles" of Table 4-2: 100,000).  A smaller value scales every
    run of the study down in proportion (the direct run too), for tests.
    ``sensitivity=False`` skips the sensitivity runs (tests)."""
    check_int_option("pin-pivot: --cycles (simulated sweeps)", cycles, 2 * EXTRAPOLATION)
    t_start = time.perf_counter()
    direct_sweeps = 2 * cycles  # 816,000 would wear the pin to ~0.6 R: beyond the model
    setup = PinPivotSetup()
    log(f"[{NAME}] building the pin and pivot FE models (n_theta {setup.n_theta}) ...")
    t0 = time.perf_counter()
    model = PinPivot.build(setup)
    build_time = time.perf_counter() - t0

    log(f"[{NAME}] {cycles:,} sweeps at A = {EXTRAPOLATION} (compiling) ...")
    base, first = _run(model, cycles, EXTRAPOLATION)
    base, run_time = _run(model, cycles, EXTRAPOLATION)  # again, compiled: the run time
    pin_816, pivot_816, slope_pin, slope_piv = _extrapolated(base, TARGET_SWEEPS)
    pin_408, pivot_408, _, _ = _extrapolated(base, THESIS_TEST_CYCLES)

    log(f"[{NAME}] direct run of {direct_sweeps:,.0f} sweeps ...")
    direct, direct_time = _run(model, direct_sweeps, EXTRAPOLATION)
    line_pin_direct, _ = linear_extrapolation(base.sweeps, base.max_pin, direct_sweeps)

    def variant(label, mod, sweeps=cycles, extrapolation=EXTRAPOLATION):
        res, dt = _run(mod, sweeps, extrapolation)
        pin, pivot, _, _ = _extrapolated(res, TARGET_SWEEPS)
        log(f"[{NAME}]   {label}: max pin {1e3 * float(res.max_pin[-1]):.4f} mm at {sweeps:,.0f} "
            f"sweeps ({dt:.1f} s)")
        return _row(label, res, dt, pin, pivot)

    log(f"[{NAME}] sensitivity runs ...")
    rows = [_row("base (as above)", base, run_time, pin_816, pivot_816)]
    if sensitivity:
        rows += _sensitivity(variant, model, setup)
    scaling = [(r["radius_m"], r["max_pin_mm_at_816000"]) for r in rows if "radius_m" in r]
    for r in rows:
        r.pop("radius_m", None)

    # final contact pressure at mid-stroke (phi = 0), the pivot's frame
    sol, p_pivot, _ = eqx.filter_jit(model.solve)(base.h_pivot, base.h_pin, jnp.asarray(0.0))
    sol.raise_if_failed(f"{NAME}: final contact")
    angle = np.degrees(np.angle(np.exp(1j * np.asarray(model.theta))))
    mm = 1e3
    out.csv("profiles.csv", {
        "angle_deg": angle,
        "pin_depth_mm_simulated": mm * np.asarray(base.h_pin),
        "pivot_depth_mm_simulated": mm * np.asarray(base.h_pivot),
        "pin_depth_mm_direct": mm * np.asarray(direct.h_pin),
        "pivot_depth_mm_direct": mm * np.asarray(direct.h_pivot),
        "pressure_MPa_mid_stroke_end": np.asarray(p_pivot) / 1e6,
    })
    out.csv("history.csv", {
        "sweeps": np.asarray(base.sweeps), "max_pin_mm": mm * np.asarray(base.max_pin),
        "max_pivot_mm": mm * np.asarray(base.max_pivot),
        "peak_pressure_MPa": np.asarray(base.peak_pressure) / 1e6,
    })
    if sensitivity:  # numbers only: rows in the order of the report's table
        out.csv("sensitivity.csv", {k: [r[k] for r in rows] for k in rows[0] if k != "case"})
    plots.profile_figure(
        out.file("wear_profiles.png"), angle_deg=angle,
        simulated={f"pin, {cycles:,} sweeps": mm * np.asarray(base.h_pin),
                   f"pivot, {cycles:,} sweeps": mm * np.asarray(base.h_pivot)},
        direct={f"pin, {direct_sweeps:,.0f} sweeps (direct)": mm * np.asarray(direct.h_pin),
                f"pivot, {direct_sweeps:,.0f} sweeps (direct)": mm * np.asarray(direct.h_pivot)},
        pressure=np.asarray(p_pivot) / 1e6,
        title=f"{NAME}: wear profiles (R {mm * setup.pin_radius:g} mm, load fixed to the pivot)")
    plots.history_figure(
        out.file("wear_history.png"), sweeps=np.asarray(base.sweeps),
        max_pin_mm=mm * np.asarray(base.max_pin), max_pivot_mm=mm * np.asarray(base.max_pivot),
        fit_pin=steady_line(base.sweeps, base.max_pin),
        fit_pivot=steady_line(base.sweeps, base.max_pivot),
        target=TARGET_SWEEPS,
        direct=(np.asarray(direct.sweeps), mm * np.asarray(direct.max_pin),
                mm * np.asarray(direct.max_pivot)),
        thesis=THESIS, title=f"{NAME}: max wear vs sweeps (cf. thesis Fig. 4-9)")

    implied_radius = setup.pin_radius * THESIS["simulated, k 1.0e-5 (Table 4-3)"] / (mm * pin_816)
    total = time.perf_counter() - t_start
    summary = {
        "study": NAME,
        "setup": dataclasses.asdict(setup),
        "force_N": setup.force,
        "simulated_sweeps": cycles,
        "extrapolation_factor_A": base.extrapolation,
        "target_sweeps": TARGET_SWEEPS,
        "target_test_cycles": THESIS_TEST_CYCLES,
        "max_pin_mm_simulated": mm * float(base.max_pin[-1]),
        "max_pivot_mm_simulated": mm * float(base.max_pivot[-1]),
        "max_pin_mm_at_408000_test_cycles": mm * pin_816,
        "max_pivot_mm_at_408000_test_cycles": mm * pivot_816,
        "max_pin_mm_at_408000_sweeps": mm * pin_408,
        "max_pivot_mm_at_408000_sweeps": mm * pivot_408,
        "steady_slope_pin_mm_per_1000_sweeps": mm * 1e3 * slope_pin,
        "steady_slope_pivot_mm_per_1000_sweeps": mm * 1e3 * slope_piv,
        "direct_sweeps": direct_sweeps,
        "max_pin_mm_direct": mm * float(direct.max_pin[-1]),
        "max_pivot_mm_direct": mm * float(direct.max_pivot[-1]),
        "max_pin_mm_direct_by_linear_extrapolation": mm * line_pin_direct,
        "worn_volume_mm3_pin": 1e9 * float(base.volume(model, "pin")),
        "worn_volume_mm3_pivot": 1e9 * float(base.volume(model, "pivot")),
        "archard_volume_mm3_k_sum_N_ds": 1e9 * float(model.wear_coefficient * base.load_sliding),
        "peak_pressure_MPa_last_sweep": float(base.peak_pressure[-1]) / 1e6,
        "contact_arc_deg_end_mid_stroke": math.degrees(float(sol.contact_arc)),
        "pin_radius_reproducing_1.867_mm": implied_radius,
        "sensitivity": rows,
        "thesis": {
            "predicted_max_pin_mm_k_1.0e-5": THESIS["simulated, k 1.0e-5 (Table 4-3)"],
            "predicted_max_pin_mm_k_1.2e-5": THESIS["simulated, k 1.2e-5 (Ch. 4 summary)"],
            "measured_max_pin_mm": THESIS["measured (Table 4-1)"],
            "test_cycles": THESIS_TEST_CYCLES, "simulated_sweeps": THESIS_SIM_SWEEPS,
            "steps_per_sweep": 10, "wear_coefficient_mm3_per_Nm": THESIS_K * 1e9,
            "simulation_time_min": THESIS_TIME_MIN,
            "sources": "Tables 4-1, 4-2, 4-3; Ch. 4 'Experimental validation' and summary; "
                       "Fig. 4-9; steel Table 3-2",
        },
        "build_s": build_time,
        "compile_and_first_run_s": first,
        "run_s": run_time,
        "direct_run_s": direct_time,
        "wall_time_s": total,
        "files": sorted(set(out.files)) + ["report.md", "summary.json"],
    }
    out.text("report.md", render(_report(summary, setup, cycles, direct_sweeps, rows, scaling)))
    out.json("summary.json", summary)
    log(f"[{NAME}] max pin wear at 408,000 test cycles: {mm * pin_816:.3f} mm (thesis 1.867 "
        f"simulated, ~2.00 measured); report: {out.path / 'report.md'}")
    return summary


def _sensitivity(variant, model, setup):
    """The base run with one change each (rows of the report's table)."""
    rows = [variant("k = 1.2e-5 mm^3/(N m)",
                    eqx.tree_at(lambda m: m.wear_coefficient, model,
                                jnp.asarray(THESIS_K_HIGH, dtype=float))),
            variant("load fixed to the pin (pivot turns)",
                    dataclasses.replace(model, load_frame="pin"))]
    for steps in (5, 20):  # A scaled so that the wear added per step stays the same
        a_steps = EXTRAPOLATION * steps / setup.steps_per_sweep  # A ds fixed: A ~ steps
        rows.append(variant(f"{steps} steps per sweep (A = {a_steps:g})",
                            dataclasses.replace(model, steps=steps), extrapolation=a_steps))
    for factor in (0.5, 2.0):
        rows.append(variant(f"compliance x {factor:g}",
                            eqx.tree_at(lambda m: m.contact.compliance, model,
                                        model.contact.compliance * factor)))
    rows.append(variant(f"A = {EXTRAPOLATION // 2}", model, extrapolation=EXTRAPOLATION // 2))
    rows.append(variant(f"mesh: n_theta {2 * setup.n_theta} (steps of 2 nodes)",
                        PinPivot.build(setup.replace(n_theta=2 * setup.n_theta))))
    for f in (0.5, 2.0):
        scaled = setup.replace(pin_radius=f * setup.pin_radius, clearance=f * setup.clearance,
                               pivot_outer_radius=f * setup.pivot_outer_radius,
                               length=f * setup.length)
        row = variant(f"all dimensions x {f:g} (R = {1e3 * scaled.pin_radius:g} mm)",
                      PinPivot.build(scaled))
        rows.append({**row, "radius_m": scaled.pin_radius})
    fixed_c = setup.replace(pin_radius=2 * setup.pin_radius,
                            pivot_outer_radius=2 * setup.pivot_outer_radius)
    rows.append(variant("R x 2, clearance kept (10 um)", PinPivot.build(fixed_c)))
    return rows


def _report(s, setup, cycles, direct_sweeps, rows, scaling) -> Report:
    mm = 1e3
    r_mm = mm * setup.pin_radius
    k_rows = [r for r in rows if r["case"].startswith("k = 1.2e-5")]
    k_high = f"{k_rows[0]['max_pin_mm_at_816000']:.3f} mm" if k_rows else "(sensitivity runs off)"
    k_ratio = (f"{k_rows[0]['max_pin_mm_at_816000'] / s['max_pin_mm_at_408000_test_cycles']:.3f} "
               "here") if k_rows else "not run"
    bend = 100 * (s["max_pin_mm_direct"] / s["max_pin_mm_direct_by_linear_extrapolation"] - 1)
    size = ""
    if scaling:
        (r1, d1), (r2, d2) = scaling
        size = (f"Scaling every dimension: R = {mm * r1:g} mm -> {d1:.3f} mm, R = {r_mm:g} mm -> "
                f"{s['max_pin_mm_at_408000_test_cycles']:.3f} mm, R = {mm * r2:g} mm -> "
                f"{d2:.3f} mm (depth / R constant).  ")
    setup_table = Table(("quantity", "value", "source"), [
        ("pin radius R", f"{r_mm:g} mm (D = {2 * r_mm:g} mm)", "our choice: the thesis gives "
         "the dimensions only in Fig. 4-1; a lab-scale pin (see *Size* below)"),
        ("radial clearance c", f"{1e6 * setup.clearance:g} um", "our choice: a close running "
         "fit of a 10 mm pin; matters only at the start (wear exceeds it within a few "
         "thousand sweeps)"),
        ("pivot outer radius (held)", f"{mm * setup.pivot_outer_radius:g} mm", "our choice (3 R)"),
        ("contact length L", f"{mm * setup.length:g} mm", "cancels at fixed projected pressure"),
        ("pin held at a bore of", f"{setup.bore_fraction:g} R",
         "model choice (`diffwear.fem.pin`)"),
        ("load", "fixed to the pivot, along angle 0; the pin turns",
         "our reading of Fig. 4-1; the other frame is a sensitivity row"),
        ("steps per sweep", setup.steps_per_sweep, "Table 4-2"),
        ("FE mesh", f"{setup.n_theta} nodes around; {setup.n_r_pivot} Q9 layers (pivot), "
         f"{setup.n_r_pin} (pin)", "our choice"),
        ("extrapolation factor A", f"{s['extrapolation_factor_A']:g} (constant)",
         "ours; thesis: adaptive, ~3,900 -> ~6,000 (Fig. 4-8)")])
    result_table = Table(("quantity", "diffwear", "thesis"), [
        (f"max pin wear after {cycles:,} sweeps (simulated)",
         f"{s['max_pin_mm_simulated']:.4f} mm",
         "<= 0.24 mm (Fig. 4-9's axis; 1.867 / 8.16 = 0.229)"),
        (f"max pivot wear after {cycles:,} sweeps", f"{s['max_pivot_mm_simulated']:.4f} mm",
         "plotted in Fig. 4-9, no value"),
        ("**max pin wear, 408,000 test cycles (816,000 sweeps), linear extrapolation**",
         f"**{s['max_pin_mm_at_408000_test_cycles']:.3f} mm**",
         "**1.867 mm** (k 1.0e-5); measured ~2.00 mm"),
        ("max pivot wear, same", f"{s['max_pivot_mm_at_408000_test_cycles']:.3f} mm", "-"),
        ("max pin wear, k = 1.2e-5, same", k_high, "2.028 mm"),
        ("max pin / pivot wear at 408,000 *sweeps* (the other count)",
         f"{s['max_pin_mm_at_408000_sweeps']:.3f} / {s['max_pivot_mm_at_408000_sweeps']:.3f} mm",
         "-"),
        (f"direct simulation of {direct_sweeps:,.0f} sweeps: max pin (line from the "
         f"{cycles:,}-sweep run) / pivot",
         f"{s['max_pin_mm_direct']:.4f} ({s['max_pin_mm_direct_by_linear_extrapolation']:.4f}) / "
         f"{s['max_pivot_mm_direct']:.4f} mm", "-"),
        (f"worn volume per body after {cycles:,} sweeps (pin / pivot / k sum N ds)",
         f"{s['worn_volume_mm3_pin']:.4g} / {s['worn_volume_mm3_pivot']:.4g} / "
         f"{s['archard_volume_mm3_k_sum_N_ds']:.4g} mm^3", "-"),
        ("peak pressure in the last sweep", f"{s['peak_pressure_MPa_last_sweep']:.1f} MPa",
         "smooth (Fig. 4-7a)"),
        (f"run time of the {cycles:,} sweeps (after compiling)", f"{s['run_s']:.1f} s",
         "206 min (Table 4-3, ANSYS)"),
        ("whole study (build, compile, all runs below)", f"{s['wall_time_s']:.0f} s", "-")])
    sensitivity_table = Table(
        ("case", f"max pin at {cycles:,} sweeps [mm]", "max pin at 816,000 [mm]",
         "max pivot at 816,000 [mm]", "peak pressure, last sweep [MPa]", "run [s]"),
        [(r["case"], f"{r['max_pin_mm_simulated']:.4f}", f"{r['max_pin_mm_at_816000']:.3f}",
          f"{r['max_pivot_mm_at_816000']:.3f}", f"{r['peak_pressure_MPa_last_sweep']:.0f}",
          f"{r['run_s']:.1f}") for r in rows])
    return Report(NAME, [
        "Thesis Chapter 4 (Tables 4-1..4-3, Fig. 4-9): a steel pin oscillating +-30 deg in a "
        "steel pivot, dry, under a constant load of 60 MPa projected pressure "
        f"(F = p D L = {s['force_N']:.0f} N here); both bodies wear by Archard's law "
        "(k = 1.0e-5 mm^3/(N m) = 1e-14 1/Pa); the contact pressure comes from a plane-strain "
        "Q9 FE model of both bodies (steel E 206.8 GPa, nu 0.29, Table 3-2), frictionless.",
        Section("Setup (ours where the thesis is silent)", [
            setup_table,
            "**Cycles.** The thesis defines a *test cycle* as -30 -> 30 -> -30 deg and a "
            "*simulated cycle* as one sweep -30 -> 30 deg (Ch. 4, *Experimental validation*), "
            "so the test's 408,000 test cycles are 816,000 sweeps.  The thesis simulated "
            "100,000 sweeps and extrapolated linearly to 1.867 mm.  That 1.867 mm is at "
            "816,000 sweeps: Fig. 4-9's wear axis ends at 0.24 mm at 100,000 sweeps, and "
            "x 8.16 gives ~1.9 mm, while extrapolating to 408,000 sweeps would give ~1 mm, not "
            "the value the thesis compares with the measured ~2.00 mm (7 % low).  We do the "
            f"same: simulate {cycles:,} sweeps, fit a line to the max depth over the second "
            "half of the run and read it at 816,000 sweeps."]),
        Section("Result", [
            result_table,
            "Our pin is a modelling choice, and at a fixed projected pressure the predicted "
            "depth is proportional to the pin size (below): the comparison with 1.867 mm tests "
            "the method, not the number.  With every dimension scaled, the model would give the "
            f"thesis's 1.867 mm at R = {mm * s['pin_radius_reproducing_1.867_mm']:.2f} mm; we "
            "did not tune to that.  In our model the wear is an exact function of k x (sweeps) "
            "(the contact is quasi-static, so k only sets the pace), hence k = 1.2e-5 gives "
            f"~1.2 x the depth ({k_ratio}; not exactly 1.2 because the history is not yet "
            "linear); the thesis's 2.028 / 1.867 = 1.086 is not that ratio (its adaptive "
            "extrapolation and fit are not reported in enough detail to say why).",
            f"The history still bends upward at {cycles:,} sweeps: the direct run of "
            f"{direct_sweeps:,.0f} sweeps ends {bend:+.1f} % off the line fitted to the first "
            f"{cycles:,}, so the linear extrapolation (the thesis's method) likely "
            "underestimates the depth at 816,000 sweeps.",
            "The pin's max wear is close to the pivot's: with the load fixed to the pivot, the "
            "pivot's wear stays under the load while the pin's spreads over the +-30 deg stroke "
            "plus the contact arc; both bodies lose the same volume (same k, same normal load, "
            "same sliding)."]),
        Section("Sensitivity (each row: the base run with one change)", [
            sensitivity_table,
            "**Size.** At a fixed projected pressure the force per unit length is 2 R p, the "
            "contact pressures depend only on the shape (ratios c/R, h/R, p/E), and the sliding "
            "distance per sweep is R x 60 deg: the wear depth scales with R.  " + size +
            "Keeping the clearance while doubling R changes the answer only through the run-in "
            "(row *R x 2, clearance kept*).",
            "**Steps per sweep, mesh, A, compliance.** Each changes one ingredient of the "
            "numerics; the table shows by how much the answer moves.  Both compliances are "
            "computed on the unworn meshes; halving or doubling them bounds the effect of the "
            "elasticity (and so of its dependence on the worn geometry, order h / wall).  The "
            "load frame is a modelling choice: with the load fixed to the pin (the test's "
            "'fixed pin inside an oscillating pivot', if its load stayed fixed in space) the "
            "pin takes the concentrated wear.",
            "**Linear extrapolation.** The thesis simulated 100,000 sweeps and extrapolated "
            "linearly (Fig. 4-9: the wear is ~linear once steady).  We check the line against "
            f"a direct run of {direct_sweeps:,.0f} sweeps (table above).  A direct run to "
            "816,000 sweeps is out of reach of this model at our size: the pin and pivot "
            "together would wear by more than the pin radius (the offset exceeds R), and long "
            "before that the small-wear assumptions (pin wear read along the ray, unworn "
            "compliance) fail."]),
        Section("Not modelled", [
            "Friction (the thesis states none for this test); the thesis's adaptive "
            "extrapolation (a constant A, checked above); remeshing of the worn bodies (the "
            "compliance is the unworn one).  The load is read as 60 MPa on the projected area "
            "D L (our reading of Table 4-1); the thesis's 'cross-sectional pressure' could also "
            "mean another area, which would change F and the depth in proportion."]),
        Section("Files", [
            Bullets([
                "`profiles.csv`: pin and pivot wear profiles [mm] after the simulated sweeps "
                "and the direct run of twice as many, each in its own body's frame (angle from "
                "the load direction at mid-stroke); contact pressure at mid-stroke at the end.",
                "`history.csv`: max pin / pivot wear and peak pressure after each computed "
                "sweep.",
                "`sensitivity.csv`: the sensitivity table.",
                "`wear_profiles.png`, `wear_history.png` (cf. Fig. 4-9)."]),
            Figure("wear_profiles.png"), Figure("wear_history.png")]),
    ])
