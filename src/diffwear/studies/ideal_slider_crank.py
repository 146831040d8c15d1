"""Study ``ideal-slider-crank``: thesis Chapter 2 (Table 2-1, Figs. 2-5 .. 2-10).

Simulates the ideal slider-crank for 2 s (one revolution at pi rad/s) and
compares the dynamic solution with the kinematic one.
"""

from __future__ import annotations

import time

import diffrax
import jax
import jax.numpy as jnp
import numpy as np

from .. import plots
from ..dynamics import (
    Baumgarte,
    along_trajectory,
    consistent_state,
    kinematic_analysis,
    reaction_wrench,
    simulate,
)
from ..io import OutputDir
from ..presets import TABLE_2_1, slider_crank
from ..report import Report, Table
from ._report import write_report

NAME = "ideal-slider-crank"
DESCRIPTION = ("Ch. 2: ideal slider-crank (Table 2-1), 2 s at pi rad/s: kinematics, dynamics, "
               "reactions")

DURATION = 2.0  # s
N_SAVE = 801
# Fig. 2-8 shows alpha = beta = 0, 5, 100 1/s; 250 1/s is the thesis default.
BAUMGARTE_SWEEP = (0.0, 5.0, 100.0, 250.0)
SWEEP_RTOL = 1e-6  # a looser tolerance makes the unstabilised drift visible in 2 s


def _timed(fn, *args):
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - t0


def run(out: OutputDir, *, duration: float = DURATION, log=print) -> dict:
    mech, q_guess = slider_crank(TABLE_2_1)
    y0 = consistent_state(mech, q_guess)
    ts = jnp.linspace(0.0, duration, N_SAVE)
    sim = jax.jit(lambda m, y: simulate(m, y, duration, ts=ts))
    log(f"[{NAME}] compiling and integrating {duration} s ...")
    traj, first = _timed(sim, mech, y0)
    traj, wall = _timed(sim, mech, y0)
    traj.raise_if_failed(NAME)
    compile_time = max(first - wall, 0.0)

    q, qd, _ = jax.vmap(mech.split)(traj.ys)
    qdd, lam, _ = jax.jit(along_trajectory)(mech, traj.ts, traj.ys)
    force = jax.vmap(lambda qq, ll, t: reaction_wrench(mech, qq, ll, t, "crank_rod", "rod"))(
        q, lam, ts
    )
    viol = jnp.max(jnp.abs(jax.vmap(mech.phi)(q, ts)), axis=1)
    qk, qdk, qddk = kinematic_analysis(mech, ts, q_guess)
    t = np.asarray(ts)
    crank_angle = np.asarray(q[:, 2])
    fmag = np.hypot(np.asarray(force[:, 0]), np.asarray(force[:, 1]))

    out.csv("reaction_crank_rod.csv", {
        "t_s": t, "crank_angle_rad": crank_angle,
        "fx_N": np.asarray(force[:, 0]), "fy_N": np.asarray(force[:, 1]),
    })
    out.csv("crank_com.csv", {
        "t_s": t, "x_m": q[:, 0], "y_m": q[:, 1], "vx_m_s": qd[:, 0], "vy_m_s": qd[:, 1],
        "ax_m_s2": qdd[:, 0], "ay_m_s2": qdd[:, 1],
    })

    sweep = {}
    for ab in BAUMGARTE_SWEEP:
        ctrl = diffrax.PIDController(rtol=SWEEP_RTOL, atol=SWEEP_RTOL)
        tr = simulate(mech, y0, duration, ts=ts, baumgarte=Baumgarte(ab, ab),
                      stepsize_controller=ctrl).raise_if_failed(f"{NAME} (alpha=beta={ab})")
        qq = tr.ys[:, : mech.n_coords]
        # second row of the crank-rod joint (thesis "second kinematic constraint")
        rows = mech.constraint_rows("crank_rod")
        sweep[f"alpha{ab:g}_beta{ab:g}_m"] = np.asarray(
            jax.vmap(mech.phi)(qq, ts)[:, rows.start + 1]
        )
    out.csv("constraint_violation.csv", {"t_s": t, "max_abs_phi_m": viol, **sweep})

    figs = {
        "fig2_5_crank_com_kinematic.png": plots.stacked(
            out.file("fig2_5_crank_com_kinematic.png"), t, [
                ("position [m]", {"x": qk[:, 0], "y": qk[:, 1]}),
                ("velocity [m/s]", {"vx": qdk[:, 0], "vy": qdk[:, 1]}),
                ("acceleration [m/s²]", {"ax": qddk[:, 0], "ay": qddk[:, 1]}),
            ], xlabel="time [s]", title="Kinematic analysis: crank COM (cf. thesis Fig. 2-5)"),
        "fig2_6_slider_kinematic.png": plots.stacked(out.file("fig2_6_slider_kinematic.png"), t, [
            ("position [m]", {"x": qk[:, 6]}), ("velocity [m/s]", {"vx": qdk[:, 6]}),
            ("acceleration [m/s²]", {"ax": qddk[:, 6]}),
        ], xlabel="time [s]", title="Kinematic analysis: slider (cf. thesis Fig. 2-6)"),
        "fig2_8_baumgarte.png": plots.stacked(out.file("fig2_8_baumgarte.png"), t, [
            ("|Φ₂| [m]", {k.replace("_m", ""): np.abs(v) + 1e-20 for k, v in sweep.items()}),
        ], xlabel="time [s]", logy=[True],
            title=f"Constraint drift vs Baumgarte gains (rtol {SWEEP_RTOL:g}; cf. Fig. 2-8)"),
        "fig2_9_crank_com_dynamic.png": plots.stacked(out.file("fig2_9_crank_com_dynamic.png"), t, [
            ("position [m]", {"x dyn": q[:, 0], "y dyn": q[:, 1]}),
            ("velocity [m/s]", {"vx dyn": qd[:, 0], "vy dyn": qd[:, 1]}),
            ("acceleration [m/s²]", {"ax dyn": qdd[:, 0], "ay dyn": qdd[:, 1],
                                     "ax kin": qddk[:, 0]}),
        ], xlabel="time [s]", title="Dynamic analysis: crank COM (cf. thesis Fig. 2-9)"),
        "fig2_10_reaction_crank_rod.png": plots.stacked(
            out.file("fig2_10_reaction_crank_rod.png"), np.degrees(crank_angle), [
                ("force on rod [N]", {"Fx": force[:, 0], "Fy": force[:, 1], "|F|": fmag}),
            ], xlabel="crank angle [deg]",
            title="Crank-rod joint reaction (cf. thesis Fig. 2-10)"),
    }

    kin_err = float(np.max(np.abs(np.asarray(q[:, :2] - qk[:, :2]))))
    summary = {
        "study": NAME,
        "duration_s": duration,
        "max_constraint_violation": float(viol.max()),
        "max_joint_force_N": float(fmag.max()),
        "max_dynamic_minus_kinematic_crank_com_m": kin_err,
        "integrator_steps": int(traj.num_steps),
        "wall_time_s": wall,
        "compile_time_s": compile_time,
        "files": sorted(set(out.files)) + ["report.md", "summary.json"],
    }
    report = Report(NAME, [
        "Ideal slider-crank of thesis Table 2-1 (half-lengths l1 = 1 m, l2 = 1.75 m; "
        "masses 10/15/30 kg), crank at pi rad/s, gravity -y, Baumgarte alpha = beta = 250 1/s, "
        "Tsit5 with rtol = atol = 1e-8.",
        Table(("quantity", "value"), [
            ("max constraint violation", f"{summary['max_constraint_violation']:.3e} m"),
            ("max crank-rod joint force", f"{summary['max_joint_force_N']:.1f} N"),
            ("dynamic vs kinematic crank COM", f"{kin_err:.2e} m"),
            ("integrator steps", summary["integrator_steps"]),
            ("run time (after compile)", f"{wall:.3f} s"),
            ("compile time", f"{compile_time:.2f} s")])])
    write_report(out, report, figs, summary)
    log(f"[{NAME}] max joint force {summary['max_joint_force_N']:.1f} N; "
        f"report: {out.path / 'report.md'}")
    return summary
