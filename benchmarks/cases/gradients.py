"""Gradient cases of the dynamic route: the Jacobian of the rig-21400 wear
evolution and of one settled rig wear cycle, each checked against central
differences."""

from __future__ import annotations

import dataclasses
import statistics

from harness import QUICK_REPEATS, time_jitted, timed

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
            return jnp.stack([smooth_max(r.depth[0], 1e-7) * 1e3,
                              worn_volume(r.depth[0], el.bushing_radius, el.law.depth) * 1e9])
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
