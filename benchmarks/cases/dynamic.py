"""Dynamic simulation cases: the ideal Table 2-1 slider-crank, one clearance
cycle per contact law and clearance, the whole ``rig-21400`` wear evolution,
and one rig wear cycle on each wear-cycle integrator."""

from __future__ import annotations

from collections.abc import Callable

from harness import time_jitted, timed


def ideal_slider_crank(repeats: int) -> dict:
    """Thesis Table 2-1 slider-crank, 2 s (one revolution), the study's settings:
    Tsit5, rtol = atol = 1e-8, Baumgarte 250 1/s, 801 saved times."""
    import jax
    import jax.numpy as jnp

    from diffwear.dynamics import consistent_state, simulate
    from diffwear.presets import TABLE_2_1, slider_crank

    duration = 2.0  # s
    mech, q_guess = slider_crank(TABLE_2_1)
    y0 = consistent_state(mech, q_guess)
    ts = jnp.linspace(0.0, duration, 801)
    sim = jax.jit(lambda m, y: simulate(m, y, duration, ts=ts))
    traj, metrics = time_jitted(sim, (mech, y0), repeats)
    traj.raise_if_failed("benchmark ideal slider-crank")
    return {
        "simulated_s": duration,
        **metrics,
        "run_s_per_simulated_s": metrics["run_s"] / duration,
        "integrator_steps": int(traj.num_steps),
        "repeats": repeats,
    }


_CLEARANCE_FNS: dict = {}


def clearance_cycle(law: str, clearance_mm: float) -> Callable[[int], dict]:
    """One crank cycle (the second: the first holds the start-up transient) of
    the Table 2-1 slider-crank with a clearance crank-rod joint, as in the
    ``clearance-sweep`` study (Tsit5, PID, rtol = atol = 1e-6)."""

    def case(repeats: int) -> dict:
        import diffrax
        import jax

        from diffwear.dynamics import simulate
        from diffwear.presets import clearance_slider_crank
        from diffwear.studies.clearance_sweep import ATOL, PERIOD, RTOL

        mech, y0 = clearance_slider_crank(law, clearance_mm * 1e-3)
        ctrl = diffrax.PIDController(rtol=RTOL, atol=ATOL, pcoeff=0.3, icoeff=0.4)
        fresh = law not in _CLEARANCE_FNS
        if fresh:  # one compilation per law: the clearance is an array leaf
            _CLEARANCE_FNS[law] = jax.jit(lambda m, y, t0: simulate(
                m, y, t0 + PERIOD, t0=t0, stepsize_controller=ctrl))
        fn = _CLEARANCE_FNS[law]
        warm, first = timed(fn, mech, y0, 0.0)  # the start-up cycle (and the compilation)
        warm.raise_if_failed("benchmark warm-up", mech)
        traj, metrics = time_jitted(fn, (mech, warm.y_final, PERIOD), repeats)
        # compile time of the law's first case; later cases reuse the executable
        metrics["compile_s"] = max(first - metrics["run_s"], 0.0) if fresh else 0.0
        traj.raise_if_failed(f"benchmark {law} {clearance_mm} mm", mech)
        steps = int(traj.num_steps)
        return {"simulated_s": PERIOD, **metrics, "run_s_per_cycle": metrics["run_s"],
                "run_s_per_simulated_s": metrics["run_s"] / PERIOD,
                "integrator_steps": steps, "steps_per_cycle": steps,
                "us_per_step": metrics["run_s"] / steps * 1e6, "repeats": repeats}

    return case


def rig_21400(repeats: int, integrator: str = "tsit5") -> dict:
    """The whole ``rig-21400`` wear evolution (constant A = 428, 50 wear cycles
    after one warm-up cycle), its cycles on ``integrator`` at its tolerance
    (`wear.cycle.CYCLE_INTEGRATORS`), compiled once; one or two steady repeats."""
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import N_THETA, PERIOD, RIG_JOINT, TARGET_DYNAMIC, _setup
    from diffwear.wear import worn_volume

    mech0, mech, y0 = _setup()
    mech_of_p = common.mech_builder(mech0, RIG_JOINT, N_THETA)
    import jax

    model = common.dynamic_model(RIG_CYCLES, TARGET_DYNAMIC, integrator)
    fn = jax.jit(lambda p, y: model.evolve(mech_of_p(p), (common.JOINT,), y, period=PERIOD,
                                           cycles=RIG_CYCLES,
                                           wall_thickness=RIG_JOINT.wall))
    res, metrics = time_jitted(fn, (common.params_of(RIG_JOINT), y0), min(repeats, 2))
    res.check("benchmark rig-21400")
    dyn = int(res.stats["dynamic_cycles"])
    el = mech.element(common.JOINT)
    return {"simulated_s": dyn * PERIOD, **metrics, "dynamic_cycles": dyn,
            "run_s_per_cycle": metrics["run_s"] / dyn,
            "run_s_per_simulated_s": metrics["run_s"] / (dyn * PERIOD),
            "max_wear_depth_mm": float(res.depth[0].max()) * 1e3,
            "wear_volume_mm3": float(worn_volume(res.depth[0], el.bushing_radius,
                                                 el.law.depth)) * 1e9,
            "repeats": min(repeats, 2)}


def rig_cycle_integrators(repeats: int) -> dict:
    """One rig wear cycle (after the warm-up) on each wear-cycle integrator at
    its tolerance (Tsit5 rtol 1e-6, Rodas4 1e-4: `wear.cycle.CYCLE_INTEGRATORS`)
    against Tsit5 at rtol = atol = 1e-10: steps, time per cycle and per step,
    and the errors of the end state (q, qd; relative to the largest entry) and
    of the cycle's wear increment (relative to its peak).  The evolution's
    agreement (what the wear answer needs) is in the rig-21400 cases."""
    import diffrax
    import jax
    import numpy as np

    from diffwear.dynamics import simulate
    from diffwear.studies.rig_21400 import PERIOD, _setup
    from diffwear.wear.cycle import CYCLE_INTEGRATORS, cycle_integrator

    _, mech, y0 = _setup()
    n = 2 * mech.n_coords

    def cycle(solver, tol):
        ctrl = diffrax.PIDController(rtol=tol, atol=tol, pcoeff=0.3, icoeff=0.4)
        return jax.jit(lambda m, y, t0: simulate(m, y, t0 + PERIOD, t0=t0, solver=solver,
                                                 stepsize_controller=ctrl))

    ys = cycle(None, 1e-8)(mech, y0, 0.0).y_final
    ref = np.asarray(cycle(None, 1e-10)(mech, ys, PERIOD).y_final)
    dwear_ref = ref[n:] - np.asarray(ys)[n:]
    out: dict = {}
    for name in CYCLE_INTEGRATORS:
        solver, tol = cycle_integrator(name)
        traj, m = time_jitted(cycle(solver, tol), (mech, ys, PERIOD), repeats)
        traj.raise_if_failed(f"benchmark rig cycle {name}", mech)
        y1 = np.asarray(traj.y_final)
        steps = int(traj.num_steps)
        out.update({
            f"{name}_rtol": tol, f"{name}_run_s": m["run_s"], f"{name}_compile_s": m["compile_s"],
            f"{name}_steps": steps, f"{name}_accepted_steps": int(traj.num_accepted_steps),
            f"{name}_us_per_step": m["run_s"] / steps * 1e6,
            f"{name}_err_state": float(np.abs(y1[:n] - ref[:n]).max() / np.abs(ref[:n]).max()),
            f"{name}_err_wear": float(np.abs(y1[n:] - np.asarray(ys)[n:] - dwear_ref).max()
                                      / np.abs(dwear_ref).max())})
    # headline: the fastest integrator, Rodas4
    out.update({"compile_s": out["rodas4_compile_s"], "run_s": out["rodas4_run_s"],
                "run_s_per_cycle": out["rodas4_run_s"], "integrator_steps": out["rodas4_steps"],
                "us_per_step": out["rodas4_us_per_step"],
                "speedup_rodas4_over_tsit5": out["tsit5_run_s"] / out["rodas4_run_s"],
                "repeats": repeats})
    return out
