"""Experiment: Rodas4 against Tsit5 where the pin flies and impacts.

On the rig the pin stays pressed into the elastic foundation, the contact is
the stiffness and Rodas4 (`--integrator rodas4`) is 5-9x faster per cycle than
Tsit5 at matched state accuracy (`rosenbrock_rig_cycle.py`).  This experiment
asks whether that carries over to mechanisms whose clearance joints lose
contact: the Table 2-1 slider-crank with a clearance crank-rod joint (thesis
Ch. 3 data) at 0.5 and 5 mm, the regime of free flight and impacts, for each
contact law (LN, KV, EFM).  One cycle after the start-up cycle, each solver's
end state (q, qd; relative to the largest entry) against Tsit5 at
rtol = atol = 1e-10 from the same state.

    python benchmarks/experiments/rosenbrock_impacts.py [--laws ln,kv,efm]
        [--clearances-mm 0.5,5] [--json out.json]

Prints a table: steps (accepted), wall time per cycle (median of 3 after
compile) and the state error, for Tsit5 at rtol 1e-6 (the clearance studies'
setting) and Rodas4 at 1e-4 (its wear-cycle preset), 1e-5 and 1e-6.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import jax  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402  (puts the harness on sys.path)
from harness import time_jitted  # noqa: E402

SOLVERS = (("Tsit5", 1e-6), ("Rodas4", 1e-4), ("Rodas4", 1e-5), ("Rodas4", 1e-6))


def one_cycle(solver, tol, period):
    """Jitted (mech, y, t0) -> Trajectory of one cycle, the clearance studies'
    PID settings."""
    import diffrax

    from diffwear.dynamics import simulate

    ctrl = diffrax.PIDController(rtol=tol, atol=tol, pcoeff=0.3, icoeff=0.4)
    return jax.jit(lambda m, y, t0: simulate(m, y, t0 + period, t0=t0, solver=solver,
                                             stepsize_controller=ctrl, max_steps=2_000_000))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--laws", default="ln,kv,efm")
    ap.add_argument("--clearances-mm", default="0.5,5")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    from diffwear.dynamics import Rodas4
    from diffwear.presets import clearance_slider_crank
    from diffwear.studies.clearance_sweep import PERIOD

    compiled: dict = {}

    def fn(name, tol, law):  # one compilation per (solver, tolerance, law)
        key = (name, tol, law)
        if key not in compiled:
            compiled[key] = one_cycle(Rodas4() if name == "Rodas4" else None, tol, PERIOD)
        return compiled[key]

    rows = []
    for law in args.laws.split(","):
        for c_mm in (float(c) for c in args.clearances_mm.split(",")):
            mech, y0 = clearance_slider_crank(law, c_mm * 1e-3)
            n = 2 * mech.n_coords
            start = fn("Tsit5", 1e-10, law)(mech, y0, 0.0)
            start.raise_if_failed("start-up cycle", mech)
            ys = start.y_final
            ref = np.asarray(fn("Tsit5", 1e-10, law)(mech, ys, PERIOD).y_final)
            for name, tol in SOLVERS:
                out, times = time_jitted(fn(name, tol, law), (mech, ys, PERIOD), repeats=3)
                out.raise_if_failed(f"{name} {law} {c_mm} mm", mech)
                y1 = np.asarray(out.y_final)
                rows.append(dict(
                    law=law, clearance_mm=c_mm, solver=name, rtol=tol,
                    steps=int(out.num_steps), accepted=int(out.num_accepted_steps),
                    s_per_cycle=times["run_s"],
                    err_state=float(np.abs(y1[:n] - ref[:n]).max() / np.abs(ref[:n]).max())))
                print(rows[-1], flush=True)
    print()
    print("| law | clearance [mm] | solver | rtol | steps (accepted) | s per cycle | "
          "error of q, qd (/ max) |")
    print("|---|---:|---|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['law'].upper()} | {r['clearance_mm']:g} | {r['solver']} | {r['rtol']:g} | "
              f"{r['steps']} ({r['accepted']}) | {r['s_per_cycle']:.3f} | {r['err_state']:.1e} |")
    if args.json:
        write_record(args.json, rows=rows)


if __name__ == "__main__":
    main()
