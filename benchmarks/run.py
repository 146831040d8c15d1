#!/usr/bin/env python3
"""diffwear performance benchmarks.

    python benchmarks/run.py [--quick] [--json PATH] [--case NAME ...]

Each registered case (`CASES`: name -> function(repeats) -> metrics) builds
its problem, times the first call of its jitted function (compile + run) and
``repeats`` steady calls, and returns a flat dict of metrics.  The table goes
to stdout as markdown, the full results (with machine and version metadata)
to JSON, by default ``benchmarks/results/latest.json`` (gitignored).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "src") not in sys.path:  # benchmark this checkout, installed or not
    sys.path.insert(0, str(ROOT / "src"))

DEFAULT_JSON = ROOT / "benchmarks" / "results" / "latest.json"
REPEATS, QUICK_REPEATS = 5, 2


def timed(fn: Callable, *args):
    """(fn(*args), wall seconds), waiting for JAX's asynchronous dispatch."""
    import jax

    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - t0


def time_jitted(fn: Callable, args: Sequence, repeats: int) -> tuple[object, dict]:
    """Time a jitted ``fn``: first call, then the median of ``repeats`` calls.

    Returns the last output and {compile_s, run_s, run_s_all}; compile_s is the
    first call minus the steady run time.
    """
    out, first = timed(fn, *args)
    runs = []
    for _ in range(repeats):
        out, wall = timed(fn, *args)
        runs.append(wall)
    run = statistics.median(runs)
    return out, {"compile_s": max(first - run, 0.0), "run_s": run, "run_s_all": runs}


# ------------------------------------------------------------------- cases
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
                                           wall_thickness=RIG_JOINT.wall).detail)
    res, metrics = time_jitted(fn, (common.params_of(RIG_JOINT), y0), min(repeats, 2))
    res.check("benchmark rig-21400")
    dyn = int(res.dynamic_cycles)
    el = mech.element(common.JOINT)
    return {"simulated_s": dyn * PERIOD, **metrics, "dynamic_cycles": dyn,
            "run_s_per_cycle": metrics["run_s"] / dyn,
            "run_s_per_simulated_s": metrics["run_s"] / (dyn * PERIOD),
            "max_wear_depth_mm": float(res.depth.max()) * 1e3,
            "wear_volume_mm3": float(worn_volume(res.depth, el.bushing_radius,
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


def rig_21400_fem_route(repeats: int) -> dict:
    """``rig-21400`` by the FEM wear route (docs "FEM contact and the FEM wear
    route": FE ring contact for the wear pressure, 65 samples per cycle) next
    to the EFM route, both as the study runs them by default: their cycles on
    the study's integrator (`rig_21400.INTEGRATOR`, Rodas4 at rtol 1e-4; the
    FEM route's cycles step onto its samples), the FEM route with
    `default_model`.  Each compiled once, then ``min(repeats, 3)`` timed runs
    (a run is 1-10 s: the median keeps a load spike on the shared machine
    out of the ratio); ``ratio_fem_to_efm`` is the route's cost measure
    (target <= 5; thesis 11 h / 7 h = 1.6)."""
    import jax

    from diffwear.models import FemRoute
    from diffwear.models.dynamic import as_evolution
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import (
        INTEGRATOR,
        N_THETA,
        PERIOD,
        RIG_JOINT,
        TARGET_DYNAMIC,
        _setup,
    )
    from diffwear.wear.chunked import RunTimes
    from diffwear.wear.fem_route import default_model

    mech0, _, y0 = _setup()
    mech_of_p = common.mech_builder(mech0, RIG_JOINT, N_THETA)
    efm = common.dynamic_model(RIG_CYCLES, TARGET_DYNAMIC, INTEGRATOR)
    fem_model = default_model(RIG_JOINT)
    fem = FemRoute(fem=fem_model, extrapolation=efm.extrapolation, cycle=efm.cycle,
                   dynamic_cycles=efm.dynamic_cycles)
    p = common.params_of(RIG_JOINT)
    n_runs = min(repeats, 3)
    out: dict = {"integrator": INTEGRATOR, "refresh_interval": float(fem_model.refresh_interval),
                 "samples_per_cycle": fem_model.n_samples + 1}
    for tag, model in (("efm", efm), ("fem", fem)):
        # the computation the study compiles (`Dynamic.run`: the evolver's
        # solve; the study runs its slots in chunks with checkpoints, the same
        # result), in one jitted call
        run = jax.jit(lambda p, y, model=model: model.evolver(
            mech_of_p(p), common.JOINT, RIG_CYCLES, period=PERIOD,
            wall_thickness=RIG_JOINT.wall).solve(y))
        res, m = time_jitted(run, (p, y0), n_runs)
        res.check(f"benchmark rig-21400 {tag} route")
        nums = common.route_numbers(as_evolution(res), RIG_JOINT,
                                    RunTimes(m["compile_s"], m["run_s"], {}))
        out.update({f"{tag}_{k}": v for k, v in nums.items()})
        out[f"{tag}_run_s_all"] = m["run_s_all"]
    # the route's change against its run before it moved to Rodas4 (relative)
    out.update({f"fem_change_{k}": out[f"fem_{k}"] / v - 1.0
                for k, v in FEM_ROUTE_ON_TSIT5.items()})
    change = {k: 100.0 * out[f"fem_change_{k}"] for k in FEM_ROUTE_ON_TSIT5}
    note = (f"FEM route against its Tsit5 run: max depth {change['max_wear_depth_mm']:+.1f} %, "
            f"+-4 deg mean {change['arc_peak_depth_mm']:+.2f} %, "
            f"volume {change['wear_volume_mm3']:+.2f} %")
    return {"compile_s": out["fem_compile_time_s"], "run_s": out["fem_wall_time_s"],
            "note": note, "dynamic_cycles": out["fem_dynamic_cycles_simulated"],
            "ratio_fem_to_efm": out["fem_wall_time_s"] / out["efm_wall_time_s"], **out,
            "repeats": n_runs}


# The FEM route's rig-21400 run before its cycles moved to Rodas4 (Tsit5 at
# rtol 1e-6, the samples interpolated, the compliance rebuilt every cycle, J
# from every 8th sample): its stored run, from the study's start
# (design_studies/results/studies/rig-21400-fem before it was regenerated;
# benchmarks/records/fem_route_scatter.json, "before", run 0).  Its grid
# maximum is one draw of a profile with node-scale roughness (+-2 % between
# runs); the +-4 deg mean and the volume by ~0.4 %.
FEM_ROUTE_ON_TSIT5 = {"max_wear_depth_mm": 0.461346, "arc_peak_depth_mm": 0.456383,
                      "wear_volume_mm3": 106.2749}


SWEEP_CHUNK = 16


def vmap_sweep(repeats: int) -> dict:
    """64-point sweep (8 clearances 0.01..2 mm x 8 friction coefficients) of one
    KV clearance slider-crank cycle (`sweep.models.ClearanceForce`, 100 saves),
    vmapped in chunks of 16, against 64 single jitted runs; the sweep without
    and with ``order_by`` (estimates: smaller clearance = more steps, the
    brief's guess; larger friction = more steps) and with the measured step
    counts as an oracle order.  ``lockstep_efficiency``: useful
    integrator steps / steps run in lockstep (chunk size x slowest member),
    from the step counts, so independent of the machine load.  One pass each
    (``repeats`` unused: a pass is 64 runs)."""
    import math

    import jax
    import numpy as np

    from diffwear.sweep import sweep
    from diffwear.sweep.models import ClearanceForce

    model = ClearanceForce(law="kv", cycles=1, transient_cycles=0, samples_per_cycle=100)
    # mu first: grid-order chunks of 16 mix all clearances (2 mu values each)
    grid = {"mu": np.linspace(0.02, 0.3, 8), "clearance": np.geomspace(0.01e-3, 2e-3, 8)}
    out: dict = {"points": 64, "chunk_size": SWEEP_CHUNK}

    def efficiency(res):
        steps = res["integrator_steps"][res.info["order"]].reshape(-1, SWEEP_CHUNK)
        return float(steps.sum() / (SWEEP_CHUNK * steps.max(axis=1)).sum())

    runs = {}
    for tag, order_by in (("unordered", None),
                          ("order_by", lambda p: -math.log(p["clearance"])),
                          ("order_by_mu", lambda p: p["mu"]),
                          ("oracle", "steps")):
        if order_by == "steps":
            steps = dict(zip(zip(runs["unordered"]["clearance"], runs["unordered"]["mu"]),
                             runs["unordered"]["integrator_steps"]))
            order_by = lambda p, steps=steps: steps[(p["clearance"], p["mu"])]  # noqa: E731
        res = sweep(model, model.defaults, grid, chunk_size=SWEEP_CHUNK, order_by=order_by)
        runs[tag] = res
        out[f"sweep_{tag}_s"] = res.info["run_s"]
        out[f"sweep_{tag}_compile_s"] = res.info["compile_s"]
        out[f"points_per_s_{tag}"] = 64 / res.info["run_s"]
        out[f"lockstep_efficiency_{tag}"] = efficiency(res)

    one = jax.jit(model)
    rows = runs["unordered"].table()
    first, t_first = timed(one, {k: rows[0][k] for k in model.param_names})
    single, rel = [], []
    for row in rows:
        ref, wall = timed(one, {k: row[k] for k in model.param_names})
        single.append(wall)
        # equal up to the integration tolerance only (batched rounding, see `sweep`)
        rel.append(abs(float(ref["rms_force_N"]) / row["rms_force_N"] - 1.0))
    total = sum(single)
    out.update({
        "single_runs_s": total, "single_compile_s": max(t_first - single[0], 0.0),
        "points_per_s_single": 64 / total,
        **{f"ratio_sweep_{t}_to_single": out[f"sweep_{t}_s"] / total
           for t in ("unordered", "order_by", "order_by_mu", "oracle")},
        "max_rel_diff_rms_force_sweep_vs_single": max(rel),
        "median_rel_diff_rms_force_sweep_vs_single": float(np.median(rel)),
        "max_rel_diff_at_clearance_mm_mu": [rows[int(np.argmax(rel))]["clearance"] * 1e3,
                                            rows[int(np.argmax(rel))]["mu"]],
        "integrator_steps": int(runs["unordered"]["integrator_steps"].sum()),
        "steps_min_max": [int(runs["unordered"]["integrator_steps"].min()),
                          int(runs["unordered"]["integrator_steps"].max())],
        "compile_s": out["sweep_unordered_compile_s"], "run_s": out["sweep_unordered_s"],
        "repeats": 1,
    })
    return out


# Wear cycles (+1 warm-up) of the gradient case.  Not 5 (A = 4,280): that
# evolution is unconverged (max depth 0.74 mm against 0.58 at A = 2,140) and not
# smooth in the parameters - central differences at steps 1e-3 and 1e-2 differ
# by up to 20x there, so no gradient can be checked (measured at commit c371919).
GRAD_DYNAMIC, GRAD_DYNAMIC_QUICK = 10, 1
GRAD_FD_STEPS = (1e-3, 1e-2)  # relative central-difference steps of the check


def rig_gradient(repeats: int, integrator: str = "tsit5", rtol: float | None = None) -> dict:
    """Jacobian of the rig-21400 result (smooth max depth [mm], volume [mm^3];
    `sweep.models.RigWear` outputs) w.r.t. (k, clearance, depth, diameter),
    as relative changes p = p0 (1 + x), through warm-up + 10 wear cycles (quick:
    1) with constant A = 21,400 / 10.  Timed: the forward run; forward mode
    (`jax.jacfwd`, diffrax ``ForwardMode``: 4 tangents vmapped); one tangent
    (`jax.jvp`); and (full mode only: its compilation takes ~2 min) reverse mode
    (`jax.jacrev`, ``RecursiveCheckpointAdjoint``).  Checked against central
    differences with relative steps 1e-3 and 1e-2.  One timed call each.
    ``rtol``: the cycles' rtol = atol instead of the integrator's preset
    (tangents are not error-controlled: benchmarks/experiments/tangent_accuracy.py)."""
    import diffrax
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.presets import RIG_CYCLES
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import N_THETA, PERIOD, RIG_JOINT, _setup
    from diffwear.wear import Constant, CycleSettings, evolve, smooth_max, worn_volume
    from diffwear.wear.cycle import cycle_integrator

    quick = repeats <= QUICK_REPEATS
    solver, tol = cycle_integrator(integrator)
    tol = tol if rtol is None else rtol
    dyn = GRAD_DYNAMIC_QUICK if quick else GRAD_DYNAMIC
    mech0, _, y0 = _setup()
    p0 = common.params_of(RIG_JOINT)
    mech_of_p = common.mech_builder(mech0, RIG_JOINT, N_THETA)

    def outputs(adjoint):
        def f(x):
            p = p0 * (1.0 + x)
            m = mech_of_p(p)
            r = evolve(m, common.JOINT, y0, RIG_CYCLES, period=PERIOD,
                       method=Constant(RIG_CYCLES / dyn), wall_thickness=RIG_JOINT.wall,
                       cycle=CycleSettings(tol, tol, solver, adjoint))
            el = m.element(common.JOINT)
            # RigWear's outputs: smooth max (temperature 0.1 um) and volume
            return jnp.stack([smooth_max(r.depth, 1e-7) * 1e3,
                              worn_volume(r.depth, el.bushing_radius, el.law.depth) * 1e9])
        return f

    x0 = jnp.zeros(4)
    fwd = jax.jit(outputs(None))
    base, m_fwd = time_jitted(fwd, (x0,), max(repeats, 2))
    fm = outputs(diffrax.ForwardMode())
    jac_fwd, m_jf = time_jitted(jax.jit(jax.jacfwd(fm)), (x0,), 1)
    jvp1 = jax.jit(lambda x: jax.jvp(fm, (x,), (jnp.eye(4)[1],))[1])
    _, m_j1 = time_jitted(jvp1, (x0,), 1)
    jac_fwd = np.asarray(jac_fwd)
    out = {"dynamic_cycles": dyn + 1, "integrator": integrator, "rtol": tol,
           "parameters": ["k", "clearance", "depth", "diameter"],
           "outputs": ["max_depth_mm", "volume_mm3"], "value": np.asarray(base).tolist(),
           "forward_s": m_fwd["run_s"], "forward_compile_s": m_fwd["compile_s"],
           "jacfwd_s": m_jf["run_s"], "jacfwd_compile_s": m_jf["compile_s"],
           "jvp1_s": m_j1["run_s"], "jvp1_compile_s": m_j1["compile_s"],
           "ratio_jacfwd_to_forward": m_jf["run_s"] / m_fwd["run_s"],
           "ratio_jvp1_to_forward": m_j1["run_s"] / m_fwd["run_s"],
           "jacobian_fwd": jac_fwd.tolist()}
    if not quick:
        jac_rev, m_jr = time_jitted(jax.jit(jax.jacrev(outputs(None))), (x0,), 1)
        jac_rev = np.asarray(jac_rev)
        out.update({"jacrev_s": m_jr["run_s"], "jacrev_compile_s": m_jr["compile_s"],
                    "ratio_jacrev_to_forward": m_jr["run_s"] / m_fwd["run_s"],
                    "jacobian_rev": jac_rev.tolist(),
                    "max_rel_diff_fwd_vs_rev": float(
                        np.max(np.abs(jac_fwd - jac_rev)) / np.max(np.abs(jac_fwd)))})
    # central differences; per output, relative to that output's largest entry
    scale = np.abs(jac_fwd).max(axis=1, keepdims=True)
    for h in GRAD_FD_STEPS:
        fd = np.stack([(np.asarray(fwd(x0.at[i].set(h))) - np.asarray(fwd(x0.at[i].set(-h))))
                       / (2 * h) for i in range(4)], axis=1)
        out[f"jacobian_fd_{h:g}"] = fd.tolist()
        out[f"max_rel_diff_fwd_vs_fd_{h:g}"] = float(np.max(np.abs(jac_fwd - fd) / scale))
        # entry by entry (relative to each entry): the clearance entries are the worst
        out[f"max_entry_rel_diff_fwd_vs_fd_{h:g}"] = float(np.max(np.abs(jac_fwd / fd - 1)))
        if "jacobian_rev" in out:
            out[f"max_entry_rel_diff_rev_vs_fd_{h:g}"] = float(
                np.max(np.abs(np.asarray(out["jacobian_rev"]) / fd - 1)))
    out.update({"compile_s": m_jf["compile_s"], "run_s": m_jf["run_s"],
                "ratio_gradient_to_forward": m_jf["run_s"] / m_fwd["run_s"],
                "repeats": 1})
    return out


def rig_cycle_gradient(repeats: int) -> dict:
    """Jacobian of one settled rig wear cycle (after a warm-up at rtol 1e-8)
    w.r.t. (k, clearance, depth, diameter) as relative changes p = p0 (1 + x):
    outputs the cycle's peak wear-depth increment (smooth max, temperature
    1e-3 um) [um] and worn-volume increment [mm^3].  Rodas4 at rtol = atol =
    1e-6 (the gradient route; its tangents are not error-controlled), forward
    mode (`jax.jacfwd`, diffrax ``ForwardMode``), with the step's Jacobian
    differentiated (the exact derivative of the discrete solution), held at
    the unperturbed run (no second derivatives; the method applied to the
    sensitivity equation with an approximate Jacobian, first order in the
    step), and ``sensitivity="ros2"`` (the sensitivity equation stepped by
    ROS2 along each step: two tangent evaluations a step instead of six;
    second order; the gradient route timed against the goal).  Checked
    against the exact tangents and central differences (relative step 1e-3).
    Forward and Jacobians are timed in turn, so that a change in the
    machine's load reaches all of them; the ratios are medians of the
    per-round ratios."""
    import diffrax
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.dynamics import Rodas4, simulate
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import N_THETA, PERIOD, RIG_JOINT, _setup
    from diffwear.wear import smooth_max, worn_volume
    from diffwear.wear.cycle import wear_cycle

    tol = 1e-6
    mech0, mech, y0 = _setup()
    p0 = common.params_of(RIG_JOINT)
    mech_of_p = common.mech_builder(mech0, RIG_JOINT, N_THETA)
    tight = diffrax.PIDController(rtol=1e-8, atol=1e-8)
    y_settled = jax.jit(lambda y: simulate(mech, y, PERIOD, stepsize_controller=tight).y_final)(y0)

    def outputs(solver, adjoint):
        def f(x):
            m = mech_of_p(p0 * (1.0 + x))
            r = wear_cycle(m, common.JOINT, y_settled, PERIOD, PERIOD, rtol=tol, atol=tol,
                           adjoint=adjoint, solver=solver)
            el = m.element(common.JOINT)
            return jnp.stack([smooth_max(r.depth_increment, 1e-9) * 1e6,
                              worn_volume(r.depth_increment, el.bushing_radius,
                                          el.law.depth) * 1e9])
        return f

    exact = Rodas4()
    held = dataclasses.replace(exact, differentiate_jacobian=False)
    ros2 = dataclasses.replace(held, sensitivity="ros2")
    fns = {"forward": jax.jit(outputs(exact, None)),
           "jacfwd_exact": jax.jit(jax.jacfwd(outputs(exact, diffrax.ForwardMode()))),
           "jacfwd_held": jax.jit(jax.jacfwd(outputs(held, diffrax.ForwardMode()))),
           "jacfwd_ros2": jax.jit(jax.jacfwd(outputs(ros2, diffrax.ForwardMode())))}
    x0 = jnp.zeros(4)
    values, first, runs = {}, {}, {k: [] for k in fns}
    for k, f in fns.items():
        values[k], first[k] = timed(f, x0)
    for _ in range(max(repeats, 2)):
        for k, f in fns.items():
            runs[k].append(timed(f, x0)[1])
    run = {k: statistics.median(v) for k, v in runs.items()}
    jac_exact, jac_held = np.asarray(values["jacfwd_exact"]), np.asarray(values["jacfwd_held"])
    jac_ros2 = np.asarray(values["jacfwd_ros2"])
    h = 1e-3
    fd = np.stack([(np.asarray(fns["forward"](x0.at[i].set(h)))
                    - np.asarray(fns["forward"](x0.at[i].set(-h)))) / (2 * h)
                   for i in range(4)], axis=1)
    scale = np.abs(jac_exact).max(axis=1, keepdims=True)
    out = {"rtol": tol, "parameters": ["k", "clearance", "depth", "diameter"],
           "outputs": ["peak_depth_increment_um", "volume_increment_mm3"],
           "value": np.asarray(values["forward"]).tolist(),
           "jacobian_exact": jac_exact.tolist(), "jacobian_held": jac_held.tolist(),
           "jacobian_ros2": jac_ros2.tolist(), "jacobian_fd_0.001": fd.tolist(),
           "max_rel_diff_held_vs_exact": float(np.max(np.abs(jac_held - jac_exact) / scale)),
           "max_rel_diff_ros2_vs_exact": float(np.max(np.abs(jac_ros2 - jac_exact) / scale)),
           "max_rel_diff_exact_vs_fd": float(np.max(np.abs(jac_exact - fd) / scale)),
           "max_rel_diff_held_vs_fd": float(np.max(np.abs(jac_held - fd) / scale)),
           "max_rel_diff_ros2_vs_fd": float(np.max(np.abs(jac_ros2 - fd) / scale))}
    for k in fns:
        out[f"{k}_s"], out[f"{k}_s_all"] = run[k], runs[k]
        out[f"{k}_compile_s"] = max(first[k] - run[k], 0.0)
    ratio = {k: statistics.median(j / f for j, f in zip(runs[k], runs["forward"])) for k in fns}
    out.update({"ratio_exact_to_forward": ratio["jacfwd_exact"],
                "ratio_held_to_forward": ratio["jacfwd_held"],
                "ratio_ros2_to_forward": ratio["jacfwd_ros2"],
                "compile_s": out["jacfwd_ros2_compile_s"], "run_s": run["jacfwd_ros2"],
                "ratio_gradient_to_forward": ratio["jacfwd_ros2"],
                "repeats": max(repeats, 2)})
    return out


# Stability boundary of Tsit5 / Dormand-Prince 5(4) along the negative real axis
# (Hairer & Wanner, Solving ODEs II, Fig. IV.2.1: ~3.3; the imaginary-axis
# extent is similar): an explicit step needs dt <= 3.3 / |lambda|.
EXPLICIT_STABILITY_RADIUS = 3.3


def rig_profile(repeats: int) -> dict:
    """Where a rig wear cycle's time goes (one cycle after the warm-up, the
    wear-cycle settings: Tsit5, PID 0.3/0.4, rtol = atol = 1e-6): accepted and
    rejected steps, time per step and per `vector_field` call, the share of the
    time spent in the RHS (6 calls per Tsit5 step), the EFM contact frequency
    sqrt(k_contact / m) / 2 pi (k_contact: half-circle EFM stiffness; m: the
    rod mass, diffwear's damping mass), and the explicit-stability floor on the
    steps: the largest |eigenvalue| of d(vector_field)/dy at 73 states over the
    cycle, integrated as sum |lambda_max| dt / 3.3."""
    import diffrax
    import jax
    import numpy as np

    from diffwear.dynamics import simulate
    from diffwear.dynamics.equations import Baumgarte, vector_field
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import PERIOD, _setup
    from diffwear.wear.cycle import CYCLE_ATOL, CYCLE_RTOL

    mech0, mech, y0 = _setup()
    ctrl = diffrax.PIDController(rtol=CYCLE_RTOL, atol=CYCLE_ATOL, pcoeff=0.3, icoeff=0.4)
    n_save = 73
    fn = jax.jit(lambda m, y, t0: simulate(
        m, y, t0 + PERIOD, t0=t0, ts=t0 + PERIOD * jax.numpy.linspace(0.0, 1.0, n_save),
        stepsize_controller=ctrl))
    warm = fn(mech, y0, 0.0)
    traj, m = time_jitted(fn, (mech, warm.y_final, PERIOD), repeats)
    traj.raise_if_failed("benchmark rig profile", mech)
    steps = int(traj.num_steps)
    acc, rej = int(traj.num_accepted_steps), int(traj.num_rejected_steps)
    us_rhs = rhs_us(mech, traj.y_final)

    jac = jax.jit(jax.vmap(jax.jacfwd(lambda t, y: vector_field(t, y, (mech, Baumgarte())),
                                      argnums=1)))(traj.ts, traj.ys)
    lam_max = np.array([np.abs(np.linalg.eigvals(j)).max() for j in np.asarray(jac)])
    dt = PERIOD / (n_save - 1)
    floor_steps = float(np.sum(0.5 * (lam_max[1:] + lam_max[:-1])) * dt
                        / EXPLICIT_STABILITY_RADIUS)
    el = mech.element(common.JOINT)
    k_c = float(el.law.contact_stiffness(el.bushing_radius))
    m_rod = float(next(b.mass for b in mech.bodies if b.name == "rod"))
    q, qd, _ = mech.split(traj.y_final)
    y_ideal = mech0.join(q, qd)  # the same motion without the clearance joint
    us_rhs_ideal = rhs_us(mech0, y_ideal)
    us_loop = loop_us_per_step(traj.y_final.size, steps)
    return {
        "simulated_s": PERIOD, **m, "integrator_steps": steps, "accepted_steps": acc,
        "rejected_steps": rej, "us_per_step": m["run_s"] / steps * 1e6,
        "us_per_rhs": us_rhs, "rhs_share": 6 * steps * us_rhs * 1e-6 / m["run_s"],
        "us_per_rhs_ideal_mechanism": us_rhs_ideal,
        "us_per_rhs_contact_and_wear": us_rhs - us_rhs_ideal,
        "us_per_step_loop_only": us_loop,
        "xla_rhs": hlo_kernels(mech, traj.y_final),
        "xla_rhs_ideal_mechanism": hlo_kernels(mech0, y_ideal),
        "contact_stiffness_N_per_m": k_c,
        "contact_frequency_Hz": math.sqrt(k_c / m_rod) / (2 * math.pi),
        "dt_stable_contact_s": EXPLICIT_STABILITY_RADIUS / math.sqrt(k_c / m_rod),
        "steps_floor_contact_formula": PERIOD * math.sqrt(k_c / m_rod) / EXPLICIT_STABILITY_RADIUS,
        "lambda_max_over_cycle": [float(lam_max.min()), float(np.median(lam_max)),
                                  float(lam_max.max())],
        "steps_floor_eigenvalues": floor_steps,
        "accepted_over_floor": acc / floor_steps,
        "repeats": repeats,
    }


def _load_peer(name: str):
    """A peer module from benchmarks/peers/ (not a package: loaded by path)."""
    import importlib.util

    path = ROOT / "benchmarks" / "peers" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"diffwear_peer_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rhs_us(mech, y, t=0.3, n: int = 2000, reps: int = 5) -> float:
    """Microseconds per `vector_field` evaluation of ``mech`` at ``y``: ``n``
    calls chained inside one jitted fori_loop (no dispatch cost), median of
    ``reps`` timed calls."""
    import jax
    import jax.numpy as jnp

    from diffwear.dynamics.equations import Baumgarte, vector_field

    args = (mech, Baumgarte())

    @jax.jit
    def loop(y):  # each call depends on the last, so none is hoisted or skipped
        return jax.lax.fori_loop(0, n, lambda i, acc: acc + 1e-300 * vector_field(t, acc, args), y)

    _, m = time_jitted(loop, (jnp.asarray(y),), reps)
    return m["run_s"] / n * 1e6


def loop_us_per_step(size: int, steps: int, reps: int = 5) -> float:
    """Microseconds per step of diffrax's loop alone: Tsit5 with the wear
    cycles' PID controller (rtol = atol = 1e-6) on a trivial right-hand side
    (-y) of ``size`` states, run for ``steps`` steps (the rest of a real step
    is its six right-hand-side calls)."""
    import diffrax
    import jax
    import jax.numpy as jnp

    term = diffrax.ODETerm(lambda t, y, args: -y)
    ctrl = diffrax.PIDController(rtol=1e-6, atol=1e-6, pcoeff=0.3, icoeff=0.4,
                                 dtmin=1e-12, dtmax=1e-3)
    # -y is smooth: the controller's step grows to dtmax and stays there, so
    # the run takes ``steps`` steps of 1e-3 s
    fn = jax.jit(lambda y: diffrax.diffeqsolve(term, diffrax.Tsit5(), 0.0, steps * 1e-3, 1e-3,
                                               y, stepsize_controller=ctrl,
                                               max_steps=steps + 16))
    sol, m = time_jitted(fn, (jnp.ones(size),), reps)
    return m["run_s"] / int(sol.stats["num_steps"]) * 1e6


def hlo_kernels(mech, y, t: float = 0.3) -> dict:
    """The optimised XLA program of one `vector_field` call: its kernels (the
    entry computation's fusions, dots and library calls, each one dispatch
    of the CPU runtime) and all its instructions (fused ones included)."""
    import re

    import jax
    import jax.numpy as jnp

    from diffwear.dynamics.equations import Baumgarte, vector_field

    text = jax.jit(vector_field).lower(jnp.asarray(t), jnp.asarray(y),
                                       (mech, Baumgarte())).compile().as_text()
    entry = next(c for c in re.split(r"\n(?=\S)", text) if c.startswith("ENTRY"))
    ops = re.findall(r"= \S+ ([a-z][\w-]*)\(", entry)
    free = {"parameter", "constant", "get-tuple-element", "tuple", "bitcast"}
    return {"kernels": sum(op not in free for op in ops),
            "library_calls": ops.count("custom-call"),
            "instructions": sum(" = " in line for line in text.splitlines())}


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
    depth_dw = float(res.depth.max()) * 1e3
    vol_dw = float(worn_volume(res.depth, el.bushing_radius, el.law.depth)) * 1e9
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


def ch8_optimisation(repeats: int) -> dict:
    """Thesis Ch. 8 design optimisation, owned by `diffwear.design`: the case
    calls ``diffwear.cli.design.benchmark_case(quick)`` (quick when ``repeats`` is
    the quick count) and reports ``available: False`` until that module exists."""
    import importlib

    try:
        design = importlib.import_module("diffwear.cli.design")
    except ModuleNotFoundError as err:
        if err.name not in ("diffwear.design",):
            raise  # the module exists but one of its imports is broken: say so
        return {"available": False, "note": "not available (no diffwear.design yet)"}
    return {"available": True, **design.benchmark_case(quick=repeats <= QUICK_REPEATS)}


def rig_21400_quasi_static(repeats: int) -> dict:
    """``rig-21400`` on the quasi-static model (`QuasiStatic()` defaults: 180
    load samples, 40 steps of the wear ODE), compiled once; the dynamic
    route's figure is the ``rig-21400 (constant A)`` case."""
    import jax

    from diffwear.models import QuasiStatic
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies.rig_21400 import PERIOD, RIG_JOINT, _setup
    from diffwear.wear import worn_volume

    _, mech, y0 = _setup()
    model = QuasiStatic()
    fn = jax.jit(lambda m: model.evolve(m, ("crank_rod",), y0, period=PERIOD,
                                        cycles=float(RIG_CYCLES), wall_thickness=RIG_JOINT.wall))
    res, metrics = time_jitted(fn, (mech,), repeats)
    el = mech.element("crank_rod")
    depth = res.depth[0]
    return {**metrics, "max_wear_depth_mm": float(depth.max()) * 1e3,
            "wear_volume_mm3": float(worn_volume(depth, el.bushing_radius, el.law.depth)) * 1e9,
            "status": int(res.status), "pair": "rig-21400 (constant A)", "goal_s": 0.5}


def rig_lubricated_quasi_static(repeats: int) -> dict:
    """The ``rig-lubricated`` study's wear run: the Ch. 7 rig with its
    crank-rod joint in oil (`MixedLubrication`: short-bearing film and
    asperities) over 21,400 cycles on the quasi-static model, beside the dry
    rig's in the same run (``ratio_lubricated_to_dry``: what the film's
    equilibrium costs), each compiled once."""
    import jax

    from diffwear.models import QuasiStatic
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies.rig_21400 import PERIOD, RIG_JOINT, _setup
    from diffwear.studies.rig_lubricated import lubricated

    _, dry, y0 = _setup()
    model = QuasiStatic()
    out: dict = {}
    for tag, mech in (("dry", dry), ("lubricated", lubricated(dry))):
        fn = jax.jit(lambda m: model.evolve(m, ("crank_rod",), y0, period=PERIOD,
                                            cycles=float(RIG_CYCLES),
                                            wall_thickness=RIG_JOINT.wall))
        res, m = time_jitted(fn, (mech,), repeats)
        out.update({f"{tag}_compile_s": m["compile_s"], f"{tag}_run_s": m["run_s"],
                    f"{tag}_max_wear_depth_mm": float(res.depth[0].max()) * 1e3,
                    f"{tag}_status": int(res.status)})
    return {"compile_s": out["lubricated_compile_s"], "run_s": out["lubricated_run_s"],
            "ratio_lubricated_to_dry": out["lubricated_run_s"] / out["dry_run_s"], **out,
            "repeats": repeats}


def quasi_static_life_gradient(repeats: int) -> dict:
    """Ch. 8 lives (cyc1, cyc2) at the Table 8-4 design on the quasi-static
    model (`TwoJointLife().prepared()`, defaults) and their exact Jacobian
    w.r.t. (d1, d2, h1, h2) by `jax.jacfwd` (4 tangents): cost of the Jacobian
    over one forward run.  The dynamic route's pointwise life derivative is
    not usable (docs: which derivatives to trust); its Jacobian is 8 central-
    difference runs, i.e. a ratio of 8."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.design import TwoJointLife
    from diffwear.design.two_joint import TABLE_8_4

    model = TwoJointLife().prepared()
    x = jnp.asarray(TABLE_8_4)
    value, m_fwd = time_jitted(jax.jit(lambda x: model(x)), (x,), repeats)
    jac, m_jac = time_jitted(jax.jit(jax.jacfwd(model)), (x,), repeats)
    return {"cycles": np.asarray(value).tolist(), "jacobian_cycles_per_mm":
            (np.asarray(jac) * 1e-3).tolist(), "forward_s": m_fwd["run_s"],
            "forward_compile_s": m_fwd["compile_s"], "compile_s": m_jac["compile_s"],
            "run_s": m_jac["run_s"], "ratio_gradient_to_forward": m_jac["run_s"] / m_fwd["run_s"],
            "dynamic_ratio_central_differences": 8.0, "goal_ratio": 3.0}


SWEEP_DESIGNS, SWEEP_DESIGNS_QUICK, SWEEP_CHUNK = 1000, 64, 250


def quasi_static_life_sweep(repeats: int) -> dict:
    """Lives of 1,000 designs (quick: 64) spread over the Table 8-3 box
    (uniform, seeded) on the quasi-static model, `jax.vmap` in chunks of
    ``SWEEP_CHUNK`` (one compile), at the sweep settings
    `diffwear.design.SWEEP_MODEL` (their lives against the defaults' at the
    Table 8-4 design are reported); once, compiles excluded.  Beside it: the
    dynamic model's one life (steps 10) times the number of designs."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.design import SWEEP_MODEL, TwoJointLife
    from diffwear.design.two_joint import LOWER, TABLE_8_4, UPPER
    from diffwear.models import Dynamic

    quick = repeats <= QUICK_REPEATS
    n = SWEEP_DESIGNS_QUICK if quick else SWEEP_DESIGNS
    chunk = min(SWEEP_CHUNK, n)
    rng = np.random.default_rng(3)
    xs = LOWER + (UPPER - LOWER) * rng.uniform(size=(n, 4))
    model = SWEEP_MODEL.prepared()
    f = jax.jit(jax.vmap(model))
    _, first = timed(f, jnp.asarray(xs[:chunk]))
    t0 = time.perf_counter()
    lives = np.concatenate([np.asarray(f(jnp.asarray(xs[i:i + chunk])))
                            for i in range(0, n, chunk)])
    run = time.perf_counter() - t0
    sweep_84 = model.life(TABLE_8_4)
    default = TwoJointLife().prepared()
    default_84 = default.life(TABLE_8_4)
    out = {"designs": n, "chunk": chunk, "run_s": run, "compile_s": max(first - run * chunk / n, 0),
           "s_per_design": run / n, "finite": bool(np.all(np.isfinite(lives))),
           "life_range": [float(lives.min()), float(lives.max())],
           "table_8_4_sweep_settings": sweep_84.tolist(),
           "table_8_4_default_settings": default_84.tolist(),
           "sweep_settings_rel_error": float(np.max(np.abs(sweep_84 / default_84 - 1))),
           "goal_s": 20.0}
    if not quick:
        check = np.asarray(jax.jit(jax.vmap(lambda x: default(x)))(jnp.asarray(xs[:32])))
        out["sweep_settings_max_rel_error_32_designs"] = float(
            np.max(np.abs(lives[:32] / check - 1)))
        dyn = TwoJointLife(wear_model=Dynamic(steps=10))
        dyn.life(TABLE_8_4)  # compile
        t0 = time.perf_counter()
        dyn.life(TABLE_8_4)
        one = time.perf_counter() - t0
        out.update({"dynamic_one_life_s": one, "dynamic_estimate_s": one * n,
                    "speedup_vs_dynamic": one * n / run})
    out["note"] = (f"{n} designs, {run / n * 1e3:.1f} ms each; settings within "
                   f"{100 * out['sweep_settings_rel_error']:.2f} % of the defaults")
    return out


# Grids of the CPU sweep cases, clearances x wear coefficients: the quasi-static
# rig's points take ~0.15 s, the dynamic rig's at 50 dynamic cycles ~10 s.
CPU_SWEEP_GRID = {"quasi-static": (8, 8), "dynamic": (2, 4)}
CPU_SWEEP_GRID_QUICK = (2, 2)


def cpu_sweep(model_name: str) -> Callable[[int], dict]:
    """One sweep of the rig's wear over clearance x k on the CPU, run four
    ways beside the baseline a user would write, a plain loop of single
    jitted runs: `sweep` batched (jit(vmap), chunks of 16), looped, pooled over
    the cores, and the default (`Auto`).  ``quasi-static``: the 21,400-cycle
    rig at the default quasi-static settings, 64 points; ``dynamic``: the
    same at the study's 50 dynamic cycles, 8 points (quick: 4 points of 200
    cycles, 1 dynamic cycle, 60 nodes).  Times
    exclude the compilation (the loop's first call, each sweep's
    ``compile_s``), as a second run finds it compiled; a pool's start-up
    (and its compilation, where the program cannot be sent) is counted.
    ``ratio_*_to_loop``: seconds per point against the loop's (<= 1: at
    least as fast).  Once each (``repeats`` unused)."""
    import jax
    import numpy as np

    from diffwear.models import QuasiStatic
    from diffwear.sweep import Auto, Batched, Looped, Pooled, sweep
    from diffwear.sweep.execution import cpu_cores
    from diffwear.sweep.models import RigWear

    def case(repeats: int) -> dict:
        quick = repeats <= QUICK_REPEATS
        settings = {"cycles": 200.0, "n_theta": 60} if quick else {}
        if model_name == "quasi-static":
            model = RigWear(wear_model=QuasiStatic(), **settings)
        else:
            model = RigWear(dynamic_cycles=1 if quick else 50, **settings)
        n_c, n_k = CPU_SWEEP_GRID_QUICK if quick else CPU_SWEEP_GRID[model_name]
        base = model.defaults
        grid = {"clearance": np.geomspace(0.02e-3, 0.1e-3, n_c),
                "k": base["k"] * np.geomspace(0.5, 1.5, n_k)}
        points = n_c * n_k
        one = jax.jit(model)
        rows = [{**base, "clearance": c, "k": k} for c in grid["clearance"] for k in grid["k"]]
        _, first = timed(one, rows[0])
        t0 = time.perf_counter()
        loop = [jax.block_until_ready(one(r)) for r in rows]
        loop_s = time.perf_counter() - t0
        out = {"points": points, "cores": cpu_cores(), "loop_s": loop_s,
               "loop_compile_s": max(first - loop_s / points, 0.0),
               "points_per_s_loop": points / loop_s}
        # chunks of 16: a 64-point vmapped quasi-static rig deadlocks XLA's
        # multi-threaded CPU runtime here (every thread idle; 16 points run,
        # mostly, and 64 with XLA_FLAGS=--xla_cpu_multi_thread_eigen=false,
        # which the record's run sets: `xla_flags`)
        out["xla_flags"] = os.environ.get("XLA_FLAGS", "")
        for tag, execution in (("batched", Batched(chunk_size=16)), ("looped", Looped()),
                               ("pooled", Pooled()), ("auto", Auto())):
            res = sweep(model, base, grid, execution=execution)
            out[f"{tag}_s"] = res.info["run_s"]
            out[f"{tag}_compile_s"] = res.info["compile_s"]
            out[f"{tag}_processes"] = res.info["processes"]
            out[f"points_per_s_{tag}"] = points / res.info["run_s"]
            out[f"ratio_{tag}_to_loop"] = res.info["run_s"] / loop_s
            if tag == "auto":
                out["auto_ran"] = res.info["execution"]
            if tag in ("pooled", "auto") and "pool_program" in res.info:
                out[f"{tag}_program"] = res.info["pool_program"]
            depth = np.array([float(r["max_depth_mm"]) for r in loop])
            out[f"max_rel_diff_{tag}_vs_loop"] = float(np.max(np.abs(
                res["max_depth_mm"] / depth - 1.0)))
        out.update({"compile_s": out["loop_compile_s"], "run_s": out["auto_s"],
                    "note": f"{points} points; default sweep ran {out['auto_ran']} "
                            f"({out['auto_processes']} processes): "
                            f"{out['ratio_auto_to_loop']:.2f}x the loop's time"})
        return out

    return case


CALIBRATION_DATASETS = Path(__file__).resolve().parents[1] / "design_studies" / "calibration"
CALIBRATION_DATASET = CALIBRATION_DATASETS / "campaign_slow_run_in"


def calibration_loop(repeats: int, dataset: Path = CALIBRATION_DATASET,
                     goal_s: float = 300.0) -> dict:
    """The calibration loop on a 21,400-cycle campaign (by default the shipped
    ``campaign_slow_run_in``: four inspections of 360-point profiles,
    weighings, the force over the first cycle).  Full: the whole ``diffwear
    calibrate`` (load, base fit, forward selection with every candidate
    refitted, the discrepancy search where the residual is unexplained, the
    detection limits, the dynamic-model check, report and plots), once,
    against the 5-minute goal.  Quick (CI): a coarse profile grid (30 nodes)
    and one Marquardt iteration's value + forward-mode Jacobian pass, against
    one forward run, so the case cannot rot."""
    import tempfile

    import jax
    import numpy as np

    from diffwear.calibrate import load_dataset
    from diffwear.calibrate.effects import NAMES, EffectValues
    from diffwear.calibrate.fit import Fitter, ModelSettings, Problem
    from diffwear.cli.calibrate import run as calibrate
    from diffwear.io import OutputDir

    data = load_dataset(dataset)
    if repeats > QUICK_REPEATS:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            s = calibrate(data, OutputDir(Path(tmp) / "out"), log=lambda *a, **k: None)
            wall = time.perf_counter() - t0
        check = s["model_check"] or {}
        named = [e["name"] for e in s["effects_identified"]] or ["none"]
        d = s.get("discrepancy") or {}
        found = ", ".join(named) + (f"; discrepancy in {d['variable']}: {d['shape']}"
                                    if d.get("variable") else "")
        return {"dataset": data.name, "run_s": wall,
                "note": f"whole loop: {found}, held-out {s['heldout_rmse_before']:.3g} -> "
                        f"{s['heldout_rmse_after']:.3g} sigma; dynamic check "
                        f"{check.get('wall_time_s', 0.0):.0f} s",
                "effects_identified": named, "discrepancy": d.get("variable"),
                "effect_identified": s["effect_identified"],
                "effect_strength": s["effect_strength"], "effect_shape": s["effect_shape"],
                "heldout_rmse_before": s["heldout_rmse_before"],
                "heldout_rmse_after": s["heldout_rmse_after"],
                "dynamic_check_s": check.get("wall_time_s"),
                "model": s["model"], "goal_s": goal_s}
    problem = Problem.from_dataset(data, ModelSettings(n_theta=30))
    fitter = Fitter(problem)
    layout = fitter.layout(("run_in",))  # the base parameters, a strength and a shape
    z = np.zeros(layout.size)  # the stated values, no effect
    forward = jax.jit(lambda x: problem.residual(x, EffectValues.zero()))
    _, first = timed(forward, z[:problem.n_base])
    _, run_s = timed(forward, z[:problem.n_base])

    def evaluate(z):
        return fitter.linearise(layout.pack(z), layout.tangents)

    _, first_j = timed(evaluate, z)
    _, jac_s = timed(evaluate, z)
    # compile_s / run_s: the value + Jacobian pass (the table's columns)
    return {"dataset": data.name, "points": int(problem.y.size),
            "compile_forward_s": first - run_s, "forward_s": run_s,
            "compile_s": first_j - jac_s, "run_s": jac_s,
            "ratio_gradient_to_forward": jac_s / run_s,
            "parameters": problem.n_base, "effects": len(NAMES),
            "note": "quick: one value + Jacobian pass (30 nodes)"}


CASES: dict[str, Callable[[int], dict]] = {
    "ideal slider-crank, 2 s": ideal_slider_crank,
    **{f"clearance cycle, {law.upper()} c={c:g} mm": clearance_cycle(law, c)
       for law in ("ln", "kv", "efm") for c in (0.0005, 0.05, 0.5, 5.0)},
    "rig-21400 (constant A)": rig_21400,
    "rig-21400 FEM vs EFM route": rig_21400_fem_route,
    "vmap sweep 64 points vs 64 single runs": vmap_sweep,
    "rig cycle, Tsit5 and Rodas4": rig_cycle_integrators,
    "rig-21400 (Rodas4)": lambda r: rig_21400(r, "rodas4"),
    "rig-21400 gradient (4 parameters)": rig_gradient,
    "rig-21400 gradient (4 parameters, Rodas4)": lambda r: rig_gradient(r, "rodas4"),
    "rig-21400 gradient (4 parameters, Rodas4 at rtol 1e-6)":
        lambda r: rig_gradient(r, "rodas4", 1e-6),
    "rig cycle gradient (4 parameters, settled, Rodas4 at rtol 1e-6)": rig_cycle_gradient,
    "rig cycle profile": rig_profile,
    "ch8-optimisation": ch8_optimisation,
    "rig-21400 quasi-static": rig_21400_quasi_static,
    "rig-lubricated quasi-static (beside the dry rig)": rig_lubricated_quasi_static,
    "quasi-static life gradient (4 parameters)": quasi_static_life_gradient,
    "quasi-static life sweep, 1000 designs": quasi_static_life_sweep,
    "CPU sweep, quasi-static rig, 64 points (batched, looped, pooled, default vs loop)":
        cpu_sweep("quasi-static"),
    "CPU sweep, dynamic rig, 8 points (batched, looped, pooled, default vs loop)":
        cpu_sweep("dynamic"),
    "calibration loop": calibration_loop,
    "calibration loop, discrepancy search (three-lobed k)":
        lambda r: calibration_loop(r, CALIBRATION_DATASETS / "campaign_three_lobe_k"),
    "calibration loop, two effects (run-in and creep)":
        lambda r: calibration_loop(r, CALIBRATION_DATASETS / "campaign_run_in_and_creep"),
    "scipy-peer": scipy_peer,
    "exudyn-peer": exudyn_peer,
}


# ---------------------------------------------------------------- harness
def _git_commit() -> str | None:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                             capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def metadata(quick: bool) -> dict:
    import jax

    import diffwear

    return {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "quick": quick,
        "commit": _git_commit(),
        "diffwear": diffwear.__version__,
        "jax": jax.__version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "device": str(jax.devices()[0]),
        "cpu_count": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0] if hasattr(os, "getloadavg") else None,
    }


def run_cases(names: Sequence[str] | None = None, *, quick: bool = False, log=print) -> dict:
    """Run the named cases (default: all) -> {"meta": ..., "cases": {name: metrics}}."""
    import jax

    jax.config.update("jax_enable_x64", True)  # diffwear computes in float64
    names = list(CASES) if not names else list(names)
    unknown = [n for n in names if n not in CASES]
    if unknown:
        raise KeyError(f"unknown benchmark case(s) {unknown}; available: {list(CASES)}")
    repeats = QUICK_REPEATS if quick else REPEATS
    results = {"meta": metadata(quick), "cases": {}}
    for name in names:
        log(f"[bench] {name} ({repeats} repeats) ...", file=sys.stderr)
        results["cases"][name] = CASES[name](repeats)
    return results


COLUMNS = (  # metric key, header, format
    ("compile_s", "compile [s]", "{:.2f}"),
    ("run_s", "run, median [s]", "{:.3f}"),
    ("run_s_per_simulated_s", "run per simulated s", "{:.3f}"),
    ("integrator_steps", "integrator steps", "{:d}"),
    ("us_per_step", "µs per step", "{:.0f}"),
    ("dynamic_cycles", "dynamic cycles", "{:d}"),
    ("run_s_per_cycle", "run per dynamic cycle [s]", "{:.3f}"),
    ("points_per_s_unordered", "sweep points/s", "{:.1f}"),
    ("ratio_sweep_unordered_to_single", "sweep / single runs", "{:.2f}"),
    ("ratio_gradient_to_forward", "gradient / forward", "{:.1f}"),
    ("speedup_per_cycle", "peer / diffwear per cycle", "{:.1f}"),
    ("ratio_fem_to_efm", "FEM / EFM route", "{:.2f}"),
    ("ratio_lubricated_to_dry", "lubricated / dry", "{:.2f}"),
    ("note", "note", "{}"),
)


def markdown(results: dict) -> str:
    lines = ["| case | " + " | ".join(h for _, h, _ in COLUMNS) + " |",
             "|---|" + "---:|" * len(COLUMNS)]
    for name, m in results["cases"].items():
        cells = [fmt.format(m[key]) if key in m else "" for key, _, fmt in COLUMNS]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    meta = results["meta"]
    load = meta["load_average_1min"]
    load = "n/a" if load is None else f"{load:.1f}"
    lines.append(f"\n{meta['device']}, {meta['cpu_count']} CPUs, 1-min load {load}; "
                 f"jax {meta['jax']}, commit {meta['commit']}; "
                 f"{'quick' if meta['quick'] else 'full'} run")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"{QUICK_REPEATS} repeats instead of {REPEATS}")
    parser.add_argument("--json", type=Path, default=DEFAULT_JSON,
                        help="where to write the results (default: %(default)s)")
    parser.add_argument("--case", action="append", choices=list(CASES), metavar="NAME",
                        help="run only this case (repeatable); default: all of "
                             + ", ".join(repr(c) for c in CASES))
    args = parser.parse_args(argv)
    results = run_cases(args.case, quick=args.quick)
    print(markdown(results))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(results, indent=2) + "\n")
    print(f"\nwrote {args.json}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
