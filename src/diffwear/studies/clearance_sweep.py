"""Study ``clearance-sweep``: thesis Chapters 3 and 6 (Figs. 3-7, 5-4, 6-7, 6-8).

The Table 2-1 slider-crank with the crank-rod joint as a clearance joint,
for each contact law (LN, KV, EFM) and each Table 3-2 clearance, against the
ideal joint's reaction.  Three crank cycles are simulated; statistics use the
last two (the first holds the start-up transient of the centred pin).
"""

from __future__ import annotations

import time

import diffrax
import jax
import jax.numpy as jnp
import numpy as np

from .. import plots
from ..contact import contact_history
from ..dynamics import along_trajectory, consistent_state, reaction_wrench, simulate
from ..io import OutputDir
from ..presets import (
    CLEARANCES_CH3,
    CONTACT_LAWS,
    THESIS_CRANK_SPEED,
    clearance_slider_crank,
    slider_crank,
)
from ..report import Figure, Report, Table, render

NAME = "clearance-sweep"
DESCRIPTION = "Ch. 3/6: crank-rod clearance joint, LN / KV / EFM x 4 clearances vs the ideal joint"

CYCLES = 3
PERIOD = 2.0  # s, one crank revolution at pi rad/s
SAVE_DT = 0.005  # s
TRANSIENT = PERIOD  # s, discarded from statistics
RTOL = ATOL = 1e-6


def _ts(cycles):
    return jnp.linspace(0.0, cycles * PERIOD, int(round(cycles * PERIOD / SAVE_DT)) + 1)


def ideal_force(ts):
    """|reaction| of the ideal crank-rod joint at ``ts`` [N]."""
    mech, q_guess = slider_crank()
    y0 = consistent_state(mech, q_guess)
    traj = simulate(mech, y0, ts[-1], ts=ts).raise_if_failed("ideal joint")
    _, lam, _ = along_trajectory(mech, traj.ts, traj.ys)
    f = jax.vmap(lambda q, l, t: reaction_wrench(mech, q, l, t, "crank_rod", "rod"))(
        traj.ys[:, : mech.n_coords], lam, ts)
    return np.hypot(np.asarray(f[:, 0]), np.asarray(f[:, 1])), np.asarray(traj.ys[:, 2])


def _simulate(mech, y0, ts):
    ctrl = diffrax.PIDController(rtol=RTOL, atol=ATOL, pcoeff=0.3, icoeff=0.4)
    traj = simulate(mech, y0, ts[-1], ts=ts, stepsize_controller=ctrl)
    return traj, contact_history(mech, "crank_rod", traj.ys)


simulate_clearance = jax.jit(_simulate)
"""(trajectory, contact history) of a clearance slider-crank; compiled once
per contact law (the clearance is an array leaf, so it never recompiles)."""


def run_case(law: str, clearance: float, ts):
    """One law and clearance [m]: (trajectory, contact history, wall time, compile time)."""
    mech, y0 = clearance_slider_crank(law, clearance)
    t0 = time.perf_counter()
    traj, hist = jax.block_until_ready(simulate_clearance(mech, y0, ts))
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    traj, hist = jax.block_until_ready(simulate_clearance(mech, y0, ts))
    wall = time.perf_counter() - t0
    traj.raise_if_failed(f"{NAME}: law {law}, clearance {clearance * 1e3:g} mm", mech)
    return traj, hist, wall, max(first - wall, 0.0)


def run(out: OutputDir, *, cycles: int = CYCLES, laws=CONTACT_LAWS, clearances=CLEARANCES_CH3,
        log=print) -> dict:
    ts = _ts(cycles)
    t = np.asarray(ts)
    keep = t >= min(TRANSIENT, t[-1] / 2)
    f_ideal, crank = ideal_force(ts)
    out.csv("force_ideal.csv", {"t_s": t, "crank_angle_rad": crank, "force_N": f_ideal})
    cases: list = []
    curves: dict[str, dict[float, np.ndarray]] = {}
    loci: dict = {}
    # the force figures show the last crank cycle against the crank angle in
    # degrees (not the cumulative angle of all cycles)
    last = t >= t[-1] - 2 * np.pi / float(THESIS_CRANK_SPEED) - 1e-12
    angle_deg = np.degrees(np.mod(crank[last], 2 * np.pi))
    order = np.argsort(angle_deg)
    for law in laws:
        curves[law] = {}
        for c in clearances:
            tag = f"{law}_{c * 1e3:g}"
            log(f"[{NAME}] {law.upper()} clearance {c * 1e3:g} mm ...")
            traj, hist, wall, compile_time = run_case(law, c, ts)
            fm = np.asarray(hist.force_magnitude)
            out.csv(f"force_{tag}.csv", {"t_s": t, "crank_angle_rad": crank, "force_N": fm})
            theta = np.asarray(hist.contact_angle)
            contact = np.asarray(hist.penetration) > 0
            out.csv(f"locus_{tag}.csv", {
                "t_s": t, "theta_rad": theta, "in_contact": contact.astype(float),
                "offset_x_m": hist.offset[:, 0], "offset_y_m": hist.offset[:, 1]})
            curves[law][c] = fm[last][order]
            # radius in units of the clearance: every panel on one scale
            loci[f"{law.upper()}, c = {c * 1e3:g} mm"] = (
                theta[keep & contact], np.hypot(*np.asarray(hist.offset[keep & contact]).T) / c)
            rel = np.sqrt(np.mean((fm[keep] - f_ideal[keep]) ** 2) / np.mean(f_ideal[keep] ** 2))
            cw = np.cos(theta[keep & contact])
            cases.append({
                "law": law, "clearance_mm": c * 1e3,
                "peak_force_N": float(fm[keep].max()),
                "rel_rms_vs_ideal": float(rel),
                "contact_fraction": float(contact[keep].mean()),
                "locus_fraction_near_0": float(np.mean(cw > np.cos(np.pi / 6))),
                "locus_fraction_near_pi": float(np.mean(cw < -np.cos(np.pi / 6))),
                "integrator_steps": int(traj.num_steps),
                "steps_per_cycle": int(traj.num_steps) / cycles,
                "wall_time_s": wall, "wall_time_per_cycle_s": wall / cycles,
                "compile_time_s": compile_time,
            })
    figs = []
    for law in laws:
        name = f"fig3_7_force_{law}.png"
        figs.append(name)
        # largest clearance first (drawn under the others), the ideal joint last (on top)
        panel = {f"c = {c * 1e3:g} mm": curves[law][c] for c in sorted(curves[law])[::-1]}
        panel["ideal joint"] = f_ideal[last][order]
        plots.stacked(out.file(name), angle_deg[order], [("joint force [N]", panel)],
                      xlabel="crank angle [deg] (last cycle)",
                      title=f"{law.upper()} clearance joint against the ideal joint "
                            "(cf. Figs. 3-7, 6-8)")
    figs.append("fig5_4_contact_locus.png")
    plots.polar_loci(out.file("fig5_4_contact_locus.png"), loci,
                     title="Contact locus on the bushing (rod frame; cf. Figs. 5-4, 6-7)",
                     radius_label="|e| / clearance", radius_scale=1.0,
                     rmax=max(float(np.max(r, initial=0.0)) for _, r in loci.values()) or None)
    summary = {"study": NAME, "cycles": cycles, "transient_s": TRANSIENT, "rtol": RTOL,
               "atol": ATOL, "ideal_peak_force_N": float(f_ideal[keep].max()), "cases": cases}
    out.text("report.md", render(Report(NAME, [
        DESCRIPTION + ".",
        f"Ideal joint peak force {summary['ideal_peak_force_N']:.0f} N. Statistics over cycles "
        f"2..{cycles}; Tsit5, rtol = atol = {RTOL:g}.",
        Table(("law", "c [mm]", "peak [N]", "rel. RMS vs ideal", "contact", "steps/cycle",
               "s/cycle"),
              [(k["law"], f"{k['clearance_mm']:g}", f"{k['peak_force_N']:.0f}",
                f"{k['rel_rms_vs_ideal']:.2%}", f"{k['contact_fraction']:.0%}",
                f"{k['steps_per_cycle']:.0f}", f"{k['wall_time_per_cycle_s']:.3f}")
               for k in cases]),
        *(Figure(f) for f in figs)])))
    out.json("summary.json", summary)
    return summary
