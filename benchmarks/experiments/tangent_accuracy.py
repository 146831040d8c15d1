"""Experiment: how accurate are the tangents of a rig cycle at the wear
cycle's tolerances?

diffrax's step controller sees only the solution's error; the tangents
(forward mode, `diffrax.ForwardMode`) ride on the same steps without control
of their own.  This script measures, along the bushing clearance (relative
change), the tangent of

* the end state's coordinates and velocities after the unsettled warm-up
  cycle (from the assembled state, with the first impacts), and
* the wear increment (sum over the profile's nodes) of one settled wear cycle,

on each integrator at its wear-cycle tolerance and tighter (and Rodas4's
three derivative routes at 1e-6), against central differences (relative
steps 1e-2 and 1e-3) of the same run and against Rodas4 at rtol 1e-7 (the
reference tangent).  Then the same three routes on the LN clearance
slider-crank, where the pin impacts (`slider_crank_rows`).

    python benchmarks/experiments/tangent_accuracy.py [--json out.json]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402

CLEARANCE = 1  # index of the clearance in the rig's design parameters
FD_STEPS = (1e-2, 1e-3)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    import diffrax

    from diffwear.dynamics import ROS3P, Rodas4, simulate
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import N_THETA, PERIOD, RIG_JOINT, _setup

    mech0, mech, y0 = _setup()
    p0 = common.params_of(RIG_JOINT)
    mech_of_p = common.mech_builder(mech0, RIG_JOINT, N_THETA)
    n = 2 * mech.n_coords
    nodes = mech.element(common.JOINT).profile.n
    tight = diffrax.PIDController(rtol=1e-8, atol=1e-8)
    y_settled = simulate(mech, y0, PERIOD, stepsize_controller=tight).y_final
    direction = jnp.eye(p0.size)[CLEARANCE]

    def quantity(which, solver, tol, x, adjoint=None):
        m = mech_of_p(p0 * (1.0 + x))
        ctrl = diffrax.PIDController(rtol=tol, atol=tol, pcoeff=0.3, icoeff=0.4)
        kw = {} if adjoint is None else {"adjoint": adjoint}
        if which == "warm-up end state":
            y = simulate(m, y0, PERIOD, solver=solver, stepsize_controller=ctrl, **kw).y_final
            return y[:n]
        y = simulate(m, y_settled, 2 * PERIOD, t0=PERIOD, solver=solver, stepsize_controller=ctrl,
                     **kw).y_final
        return jnp.sum(y[n:n + nodes])[None]

    def tangent(which, solver, tol):
        return np.asarray(jax.jit(lambda x: jax.jvp(
            lambda z: quantity(which, solver, tol, z, diffrax.ForwardMode()), (x,),
            (direction,))[1])(jnp.zeros(p0.size)))

    held, ros2 = Rodas4(differentiate_jacobian=False), Rodas4(sensitivity="ros2")
    runs = [("Tsit5", diffrax.Tsit5(), 1e-6), ("ROS3P", ROS3P(), 1e-4), ("Rodas4", Rodas4(), 1e-4),
            ("Rodas4", Rodas4(), 1e-6), ("Rodas4, Jacobian held", held, 1e-6),
            ("Rodas4, ROS2 tangents", ros2, 1e-6)]
    rows = []
    for which in ("warm-up end state", "wear increment"):
        ref = tangent(which, Rodas4(), 1e-7)
        scale = float(np.abs(ref).max())
        for name, solver, tol in runs:
            f = jax.jit(lambda x, s=solver, t=tol: quantity(which, s, t, x))
            jv = tangent(which, solver, tol)
            row = dict(quantity=which, solver=name, rtol=tol,
                       tangent_vs_reference=float(np.abs(jv - ref).max() / scale))
            for h in FD_STEPS:
                fd = np.asarray(f(h * direction) - f(-h * direction)) / (2 * h)
                row[f"fd_{h:g}_vs_reference"] = float(np.abs(fd - ref).max() / scale)
            rows.append(row)
            print(row, flush=True)
    print("| quantity | solver | rtol | tangent vs reference | central differences (1e-2, 1e-3) "
          "vs reference |")
    print("|---|---|---:|---:|---:|")
    for r in rows:
        print(f"| {r['quantity']} | {r['solver']} | {r['rtol']:g} | {r['tangent_vs_reference']:.2e}"
              f" | {r['fd_0.01_vs_reference']:.2e}, {r['fd_0.001_vs_reference']:.2e} |")
    impacts = slider_crank_rows()
    if args.json:
        write_record(args.json, rows=rows, slider_crank_ln=impacts)


def slider_crank_rows():
    """The three Rodas4 derivative routes off the rig: the Table 2-1
    slider-crank with a 0.5 mm LN clearance joint (impacts and short
    contacts), the end state 20 ms after 0.3 s along the contact stiffness
    (relative change), against central differences (relative step 1e-4) of
    Rodas4's forward run at the same tolerance; largest difference over the
    state, relative to the largest entry."""
    import diffrax
    import equinox as eqx

    from diffwear.dynamics import Rodas4, simulate
    from diffwear.presets import clearance_slider_crank

    mech, y0 = clearance_slider_crank("ln", 0.5e-3)
    y = jax.jit(lambda y: simulate(mech, y, 0.3).y_final)(y0)
    i = [f.name for f in mech.forces].index("crank_rod")

    def end(s, solver, tol, adjoint=None):
        m = eqx.tree_at(lambda m: m.forces[i].law.stiffness, mech,
                        mech.forces[i].law.stiffness * (1.0 + s))
        kw = {} if adjoint is None else {"adjoint": adjoint}
        return simulate(m, y, 0.32, t0=0.3, solver=solver,
                        stepsize_controller=diffrax.PIDController(rtol=tol, atol=tol), **kw).y_final

    routes = [("exact", Rodas4()), ("Jacobian held", Rodas4(differentiate_jacobian=False)),
              ("ROS2 tangents", Rodas4(sensitivity="ros2"))]
    rows = []
    for tol in (1e-6, 1e-8, 1e-10):
        f = jax.jit(lambda s, t=tol: end(s, Rodas4(), t))
        fd = np.asarray(f(1e-4) - f(-1e-4)) / 2e-4
        row = {"rtol": tol}
        for name, solver in routes:
            tangent = np.asarray(jax.jit(lambda s=solver, t=tol: jax.jvp(
                lambda x: end(x, s, t, diffrax.ForwardMode()), (0.0,), (1.0,))[1])())
            row[name] = float(np.abs(tangent - fd).max() / np.abs(fd).max())
        rows.append(row)
        print(row, flush=True)
    print("| LN slider-crank, rtol | exact | Jacobian held | ROS2 tangents |")
    print("|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['rtol']:g} | {r['exact']:.1e} | {r['Jacobian held']:.1e} | "
              f"{r['ROS2 tangents']:.1e} |")
    return rows


if __name__ == "__main__":
    main()
