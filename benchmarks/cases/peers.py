"""Cases against independent implementations (benchmarks/peers/): the SciPy
rig (NumPy + solve_ivp) and the Exudyn slider-crank (generalized-alpha)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

from harness import QUICK_REPEATS, ROOT, time_jitted

from .cycle_profile import rhs_us


def _load_peer(name: str):
    """A peer module from benchmarks/peers/ (not a package: loaded by path)."""
    import importlib.util

    path = ROOT / "benchmarks" / "peers" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"diffwear_peer_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SCIPY_DYNAMIC = 10  # wear cycles of the full evolution cross-check (A = 21,400 / 10)


def scipy_peer(repeats: int) -> dict:
    """diffwear against `peers/scipy_rig.py` (the same rig, NumPy + solve_ivp RK45
    at the same rtol = atol = 1e-6).  Both run the warm-up cycle from the same
    state, then one wear cycle saving 181 states: joint force and wear increment
    compared.  Full mode adds the evolution over 21,400 cycles with A = 2,140
    (10 wear cycles + warm-up) on both, and both solvers' error against a
    reference cycle at rtol = atol = 1e-10 (equal accuracy)."""
    import jax
    import numpy as np

    from diffwear.contact import contact_history
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import PERIOD, RIG_JOINT, _setup
    from diffwear.wear import Constant, evolve, wear_cycle, worn_volume

    peer = _load_peer("scipy_rig")
    quick = repeats <= QUICK_REPEATS
    mech0, mech, y0 = _setup()
    n_save = 181
    y0_peer = peer.initial_state()
    out: dict = {"state_start_max_abs_diff": float(np.abs(np.asarray(y0) - y0_peer).max())}

    cycle = jax.jit(lambda m, y, t0: wear_cycle(m, common.JOINT, y, t0, PERIOD))
    warm, dw = time_jitted(cycle, (mech, y0, 0.0), repeats)
    saved = jax.jit(lambda m, y, t0: wear_cycle(m, common.JOINT, y, t0, PERIOD, n_save=n_save))
    cyc = saved(mech, warm.y_end, PERIOD)
    f_dw = np.asarray(contact_history(mech, common.JOINT, cyc.ys).force_magnitude)

    rig = peer.Rig()
    t_start = time.perf_counter()
    warm_p = peer.wear_cycle(rig, y0_peer, 0.0)
    peer_cycle_s = time.perf_counter() - t_start
    t_eval = PERIOD + PERIOD * np.linspace(0.0, 1.0, n_save)
    t_eval[-1] = 2 * PERIOD  # solve_ivp wants t_eval inside the span, bit for bit
    sol = peer.wear_cycle(rig, warm_p.y[:, -1], PERIOD, t_eval=t_eval)
    f_peer = rig.joint_force(sol.y.T)
    dh_dw, dh_peer = np.asarray(cyc.depth_increment), sol.y[18:18 + peer.N_THETA, -1]
    peer_attempts = (warm_p.nfev - 2) / 6  # RK45: 6 evaluations per try, 2 to start
    out.update({
        "diffwear_cycle_s": dw["run_s"], "diffwear_compile_s": dw["compile_s"],
        "scipy_cycle_s": peer_cycle_s,
        "speedup_per_cycle": peer_cycle_s / dw["run_s"],
        "diffwear_steps_per_cycle": int(warm.num_steps),
        "scipy_steps_per_cycle": int(round(peer_attempts)),
        "scipy_accepted_steps_per_cycle": int(warm_p.t.size - 1),
        "diffwear_us_per_step": dw["run_s"] / int(warm.num_steps) * 1e6,
        "scipy_us_per_step": peer_cycle_s / peer_attempts * 1e6,
        "diffwear_us_per_rhs": rhs_us(mech, warm.y_end),
        "scipy_us_per_rhs": peer.time_rhs(500 if quick else 2000) * 1e6,
        # agreement of the second cycle (first wear cycle)
        "force_max_rel_diff": float(np.abs(f_dw - f_peer).max() / np.abs(f_dw).max()),
        "force_mean_rel_diff": float(abs(f_dw.mean() / f_peer.mean() - 1)),
        "wear_increment_max_rel_diff": float(np.abs(dh_dw - dh_peer).max() / dh_dw.max()),
        "load_sliding_rel_diff": float(abs(float(cyc.load_sliding) / sol.y[-1, -1] - 1)),
        "mean_joint_force_N": float(f_dw[:-1].mean()),
    })
    out["ratio_rhs_scipy_to_diffwear"] = out["scipy_us_per_rhs"] / out["diffwear_us_per_rhs"]
    out.update({"compile_s": dw["compile_s"], "run_s": dw["run_s"],
                "run_s_per_cycle": dw["run_s"], "integrator_steps": int(warm.num_steps),
                "us_per_step": out["diffwear_us_per_step"], "repeats": repeats})
    if quick:
        return out

    # reference cycle (rtol = atol = 1e-10) for the accuracy of both at 1e-6
    ref = jax.jit(lambda m, y, t0: wear_cycle(m, common.JOINT, y, t0, PERIOD, rtol=1e-10,
                                              atol=1e-10))(mech, y0, 0.0)
    dh_ref = np.asarray(ref.depth_increment)
    out["diffwear_wear_increment_err_vs_ref"] = float(
        np.abs(np.asarray(warm.depth_increment) - dh_ref).max() / dh_ref.max())
    out["scipy_wear_increment_err_vs_ref"] = float(
        np.abs(warm_p.y[18:18 + peer.N_THETA, -1] - dh_ref).max() / dh_ref.max())

    el = mech.element(common.JOINT)
    a = RIG_CYCLES / SCIPY_DYNAMIC
    evo = jax.jit(lambda m, y: evolve(m, common.JOINT, y, RIG_CYCLES, period=PERIOD,
                                      method=Constant(a), wall_thickness=RIG_JOINT.wall))
    res, de = time_jitted(evo, (mech, y0), 1)
    res.check("benchmark scipy-peer evolution")
    depth_dw = float(res.depth[0].max()) * 1e3
    vol_dw = float(worn_volume(res.depth[0], el.bushing_radius, el.law.depth)) * 1e9
    t_start = time.perf_counter()
    ev_p = peer.evolve(RIG_CYCLES, SCIPY_DYNAMIC)
    peer_evo_s = time.perf_counter() - t_start
    out.update({
        "evolution_dynamic_cycles": SCIPY_DYNAMIC + 1,
        "diffwear_evolution_s": de["run_s"], "scipy_evolution_s": peer_evo_s,
        "speedup_evolution": peer_evo_s / de["run_s"],
        "scipy_cycle_s_median": float(np.median(ev_p["cycle_s"])),
        "diffwear_max_depth_mm": depth_dw, "scipy_max_depth_mm": ev_p["max_depth_mm"],
        "diffwear_volume_mm3": vol_dw, "scipy_volume_mm3": ev_p["volume_mm3"],
        "max_depth_rel_diff": abs(depth_dw / ev_p["max_depth_mm"] - 1),
        "volume_rel_diff": abs(vol_dw / ev_p["volume_mm3"] - 1),
    })
    out["speedup_per_cycle"] = out["scipy_cycle_s_median"] / dw["run_s"]
    return out


EXUDYN_STEP = 1e-3  # s, generalized-alpha fixed step of the headline comparison
EXUDYN_STEPS_FULL = (2e-3, 1e-3, 5e-4)  # full mode: the agreement against the step
EXUDYN_SAMPLE = 0.01  # s, compared every 4th of diffwear's 801 times: a multiple of each step


def exudyn_python() -> str | None:
    """The interpreter that runs the Exudyn peer: this one, where the
    project's ``bench`` extra installed exudyn (``pip install -e ".[bench]"``),
    or the one named by ``DIFFWEAR_EXUDYN_PYTHON``; None when it cannot import
    exudyn."""
    exe = os.environ.get("DIFFWEAR_EXUDYN_PYTHON") or sys.executable
    try:
        probe = subprocess.run([exe, "-c", "import exudyn"], capture_output=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return None
    return exe if probe.returncode == 0 else None


# diffwear's routes in the Exudyn comparison: (stabilisation, rtol = atol).
# "baumgarte": the thesis's alpha = beta = 250 1/s on Tsit5 (the study's
# setting is rtol 1e-8); "projection": post-stabilisation, Baumgarte(0, 0) and
# `ConstraintProjection(Tsit5())`.
EXUDYN_DIFFWEAR_ROUTES = (("baumgarte", 1e-8), ("baumgarte", 1e-6), ("projection", 1e-6),
                          ("projection", 1e-7), ("projection", 1e-8))
EXUDYN_REFERENCE_RTOL = 1e-12  # the tight reference every route is measured against


def _slider_crank_outputs(mech, traj, baumgarte=None):
    """Slider x [m], |crank-rod reaction| [N] and driver torque [N m] at the
    saved times of a Table 2-1 slider-crank trajectory (the multipliers with
    the ``baumgarte`` gains it was integrated with)."""
    import jax
    import numpy as np

    from diffwear.dynamics import along_trajectory, reaction_wrench

    q, _, _ = jax.vmap(mech.split)(traj.ys)
    _, lam, _ = jax.jit(along_trajectory)(mech, traj.ts, traj.ys, baumgarte)
    force = jax.vmap(lambda qq, ll, t: reaction_wrench(mech, qq, ll, t, "crank_rod", "rod"))(
        q, lam, traj.ts)
    return (np.asarray(q[:, 6]), np.hypot(np.asarray(force[:, 0]), np.asarray(force[:, 1])),
            np.asarray(lam[:, mech.constraint_rows("driver").start]))


def _output_errors(ref, out) -> dict:
    """Max differences of (slider x, joint force, driver torque) from ``ref``,
    relative to the stroke, the force peak and the torque peak."""
    import numpy as np

    (x0, f0, tq0), (x, f, tq) = ref, out
    return {"slider_x_max_diff_rel_stroke": float(np.abs(x - x0).max() / np.ptp(x0)),
            "joint_force_max_rel_diff": float(np.abs(f - f0).max() / f0.max()),
            "driver_torque_max_rel_diff": float(np.abs(tq - tq0).max() / np.abs(tq0).max())}


def exudyn_peer(repeats: int) -> dict:
    """diffwear's ideal slider-crank (Table 2-1, 2 s, 801 saved times) against
    `peers/exudyn_slider_crank.py`, the same mechanism in Exudyn (implicit
    generalized-alpha, index 3, fixed step ``EXUDYN_STEP``), run as a
    subprocess with `exudyn_python`, at matched accuracy.

    Every run is measured against one tight reference (diffwear, Baumgarte,
    rtol = atol = ``EXUDYN_REFERENCE_RTOL``) at 201 common times (every
    ``EXUDYN_SAMPLE``, on Exudyn's step grid, so nothing is interpolated):
    slider x (max |dx| / stroke), crank-rod reaction |F| and driver torque
    (max difference / peak).  diffwear runs each route of
    ``EXUDYN_DIFFWEAR_ROUTES``; ``matched_*`` is the fastest route whose
    joint-force error is at most Exudyn's.  Times: medians of steady runs (no
    compilation) against Exudyn's median solve (model building,
    ``exudyn_build_s``, apart).  The top-level ``slider_x_...``,
    ``joint_force_...`` and ``driver_torque_...`` keys compare Exudyn with the
    study's route (rtol 1e-8), as the agreement check.  Full mode adds Exudyn
    at the steps ``EXUDYN_STEPS_FULL`` and the clearance joint.  Reports
    ``available: False`` without exudyn."""
    exe = exudyn_python()
    if exe is None:
        return {"available": False,
                "note": "not available (exudyn is not installed: pip install -e \".[bench]\")"}
    import diffrax
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.dynamics import Baumgarte, ConstraintProjection, consistent_state, simulate
    from diffwear.presets import TABLE_2_1, slider_crank

    duration, n_save = 2.0, 801
    mech, q_guess = slider_crank(TABLE_2_1)
    y0 = consistent_state(mech, q_guess)
    ts = jnp.linspace(0.0, duration, n_save)

    def gains(stabilisation: str):
        return Baumgarte(0.0, 0.0) if stabilisation == "projection" else Baumgarte()

    def route(stabilisation: str, tol: float):
        ctrl = diffrax.PIDController(rtol=tol, atol=tol, pcoeff=0.3, icoeff=0.4)
        solver = (ConstraintProjection(diffrax.Tsit5()) if stabilisation == "projection"
                  else diffrax.Tsit5())
        return jax.jit(lambda m, y: simulate(m, y, duration, ts=ts, solver=solver,
                                             baumgarte=gains(stabilisation),
                                             stepsize_controller=ctrl))

    ref_traj = route("baumgarte", EXUDYN_REFERENCE_RTOL)(mech, y0)
    ref_traj.raise_if_failed("benchmark exudyn-peer reference")
    ref = _slider_crank_outputs(mech, ref_traj)
    every = int(round(EXUDYN_SAMPLE / (duration / (n_save - 1))))

    def sampled(outputs):  # on Exudyn's times
        return tuple(np.asarray(a)[::every] for a in outputs)

    t_sampled, ref_sampled = sampled((ts,))[0], sampled(ref)

    routes: dict = {}
    for stabilisation, tol in EXUDYN_DIFFWEAR_ROUTES:
        traj, m = time_jitted(route(stabilisation, tol), (mech, y0), repeats)
        traj.raise_if_failed(f"benchmark exudyn-peer {stabilisation} rtol {tol:g}")
        outputs = _slider_crank_outputs(mech, traj, gains(stabilisation))
        routes[f"{stabilisation}_rtol{tol:g}"] = {
            "run_s": m["run_s"], "compile_s": m["compile_s"], "steps": int(traj.num_steps),
            "outputs": outputs, **_output_errors(ref, outputs)}
    study = routes["baumgarte_rtol1e-08"]

    def peer(step: float) -> dict:
        cmd = [exe, str(ROOT / "benchmarks" / "peers" / "exudyn_slider_crank.py"),
               "--step", repr(step), "--sample", repr(EXUDYN_SAMPLE),
               "--repeats", str(repeats)]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        if proc.returncode != 0:
            raise RuntimeError(f"exudyn peer failed: {proc.stdout[-2000:]}{proc.stderr[-2000:]}")
        d = json.loads(proc.stdout)
        te = np.asarray(d["t"])
        if te.shape != t_sampled.shape or np.abs(te - t_sampled).max() > 1e-9:
            raise RuntimeError(f"exudyn peer sampled at other times ({te.size} samples)")
        ex = tuple(np.asarray(d[k]) for k in ("slider_x", "joint_force", "driver_torque"))
        against_ref = _output_errors(ref_sampled, ex)
        return {
            "exudyn_step_s": step, "exudyn_steps": d["steps"],
            "exudyn_solve_s": d["solve_s"], "exudyn_build_s": d["build_s"],
            "exudyn_newton_iterations": d["newton_iterations"],
            "exudyn_spectral_radius": d["spectral_radius"], "exudyn_version": d["exudyn"],
            "exudyn_driver": d["driver"],
            **_output_errors(sampled(study["outputs"]), ex),
            **{f"exudyn_{k}_vs_reference": v for k, v in against_ref.items()},
            "exudyn_peak_joint_force_N": float(ex[1].max()),
        }

    out = {"available": True, **peer(EXUDYN_STEP)}
    # the fastest diffwear route at least as accurate as Exudyn (joint force)
    target = out["exudyn_joint_force_max_rel_diff_vs_reference"]
    matched = min((name for name, r in routes.items() if r["joint_force_max_rel_diff"] <= target),
                  key=lambda name: routes[name]["run_s"], default=None)
    steps = study["steps"]
    out.update({
        "diffwear_run_s": study["run_s"], "diffwear_compile_s": study["compile_s"],
        "diffwear_steps": steps, "peak_joint_force_N": float(study["outputs"][1].max()),
        "ratio_exudyn_to_diffwear": out["exudyn_solve_s"] / study["run_s"],
        "simulated_s": duration, "compile_s": study["compile_s"], "run_s": study["run_s"],
        "run_s_per_simulated_s": study["run_s"] / duration, "integrator_steps": steps,
        "us_per_step": study["run_s"] / steps * 1e6, "repeats": repeats,
        "diffwear_routes": {name: {k: v for k, v in r.items() if k != "outputs"}
                            for name, r in routes.items()},
        "matched_route": matched,
    })
    if matched is not None:
        r = routes[matched]
        out.update({"matched_run_s": r["run_s"], "matched_steps": r["steps"],
                    "matched_joint_force_max_rel_diff": r["joint_force_max_rel_diff"],
                    "ratio_exudyn_to_diffwear_matched": out["exudyn_solve_s"] / r["run_s"]})
    out["speedup_per_cycle"] = out.get("ratio_exudyn_to_diffwear_matched",
                                       out["ratio_exudyn_to_diffwear"])  # one cycle = the 2 s
    if repeats > QUICK_REPEATS:
        out["step_sweep"] = [peer(h) for h in EXUDYN_STEPS_FULL]
        out["clearance_kv_0.5mm"] = exudyn_clearance_kv(exe)
    return out


EXUDYN_CLEARANCE_STEP = 2e-4  # s; contact at K = 1.7e7 N/m on the rod: ~170 Hz


def exudyn_clearance_kv(exe: str, clearance: float = 0.5e-3) -> dict:
    """The crank-rod clearance joint (Kelvin-Voigt law, as
    ``presets.clearance_slider_crank("kv", 0.5e-3)``) in the Exudyn peer (loads
    with Python user functions; K taken from diffwear's law) against diffwear
    (Tsit5, PID 0.3/0.4, rtol = atol = 1e-6 as the clearance-sweep study), two
    cycles from the centred start: peak |F| of the start-up cycle and of the
    second cycle, the second cycle's mean |F|.  One timed solve each."""
    import diffrax
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.contact import contact_history
    from diffwear.dynamics import simulate
    from diffwear.presets import clearance_slider_crank

    duration, dt = 4.0, EXUDYN_CLEARANCE_STEP
    mech, y0 = clearance_slider_crank("kv", clearance)
    stiffness = float(mech.element("crank_rod").law.stiffness)
    ts = jnp.linspace(0.0, duration, int(round(duration / dt)) + 1)
    ctrl = diffrax.PIDController(rtol=1e-6, atol=1e-6, pcoeff=0.3, icoeff=0.4)
    fn = jax.jit(lambda m, y: simulate(m, y, duration, ts=ts, stepsize_controller=ctrl))
    traj, dw = time_jitted(fn, (mech, y0), 1)
    traj.raise_if_failed("benchmark exudyn-peer clearance", mech)
    f_dw = np.asarray(contact_history(mech, "crank_rod", traj.ys).force_magnitude)
    cmd = [exe, str(ROOT / "benchmarks" / "peers" / "exudyn_slider_crank.py"), "--step", repr(dt),
           "--sample", repr(dt), "--repeats", "1", "--duration", repr(duration),
           "--kv-stiffness", repr(stiffness), "--clearance", repr(clearance)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if proc.returncode != 0:
        raise RuntimeError("exudyn peer (clearance) failed: "
                           f"{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    d = json.loads(proc.stdout)
    t = np.asarray(ts)
    f_ex = np.interp(t, np.asarray(d["t"]), np.asarray(d["joint_force"]))
    first, second = t < 2.0, t >= 2.0
    return {
        "law": "kv", "clearance_m": clearance, "stiffness_N_per_m": stiffness,
        "exudyn_step_s": dt, "exudyn_solve_s": d["solve_s"], "diffwear_run_s": dw["run_s"],
        "diffwear_steps": int(traj.num_steps),
        "ratio_exudyn_to_diffwear": d["solve_s"] / dw["run_s"],
        "diffwear_peak_first_cycle_N": float(f_dw[first].max()),
        "exudyn_peak_first_cycle_N": float(f_ex[first].max()),
        "diffwear_peak_second_cycle_N": float(f_dw[second].max()),
        "exudyn_peak_second_cycle_N": float(f_ex[second].max()),
        "peak_first_cycle_rel_diff": float(abs(f_ex[first].max() / f_dw[first].max() - 1)),
        "peak_second_cycle_rel_diff": float(abs(f_ex[second].max() / f_dw[second].max() - 1)),
        "mean_second_cycle_rel_diff": float(abs(f_ex[second].mean() / f_dw[second].mean() - 1)),
        "max_diff_second_cycle_rel_peak": float(
            np.abs(f_ex - f_dw)[second].max() / f_dw[second].max()),
    }
