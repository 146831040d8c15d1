"""Experiment: how accurate are the tangents of a rig cycle at the wear
cycle's tolerances?

diffrax's step controller sees only the solution's error; the tangents
(forward mode, `diffrax.ForwardMode`) ride on the same steps without control
of their own.  This script measures, along the bushing clearance (relative
change), the tangent of

* the end state's coordinates and velocities after the unsettled warm-up
  cycle (from the assembled state, with the first impacts), and
* the wear increment (sum over the profile's nodes) of one settled wear cycle,

on each integrator at its wear-cycle tolerance and tighter, against central
differences (relative steps 1e-2 and 1e-3) of the same run and against
Rodas4 at rtol 1e-7 (the reference tangent).

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

    runs = [("Tsit5", diffrax.Tsit5(), 1e-6), ("ROS3P", ROS3P(), 1e-4), ("Rodas4", Rodas4(), 1e-4),
            ("Rodas4", Rodas4(), 1e-6)]
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
    if args.json:
        write_record(args.json, rows=rows)


if __name__ == "__main__":
    main()
