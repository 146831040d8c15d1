"""Experiment: the Rosenbrock solvers on one rig wear cycle, against Tsit5 (the
dynamic model's default solver) at matched accuracy.

The stiffness of the rig's right-hand side sits in the pin's contact with the
elastic foundation, i.e. in the mechanism coordinates and velocities (18 of
the 199 states); the 181 wear and contact states of the clearance joint never
feed back within a cycle (their Jacobian columns are exactly zero, checked
by tests/test_rosenbrock.py).  So the exact Jacobian is d f / d(q, qd), 18
forward-mode tangents, and the step matrix (I / (h gamma) - J) factorises as
one 18 x 18 LU plus a back-substitution for the wear rows.

Methods: `diffwear.dynamics.ROS3P` (Lang and Verwer 2001), `Rodas4`
(Hairer and Wanner's RODAS, fourth order, L-stable) and the W-method
`ROS34PW2` (Rang and Angermann 2005), with the Jacobian fresh at every step or
reused over 5 and 20 steps (their coefficients are checked by the tests).

    python benchmarks/experiments/rosenbrock_rig_cycle.py [--json out.json]

Prints a table: for each solver and tolerance, steps per cycle, wall time per
cycle (median of 3 after compile) and the error of the cycle's end state
(the mechanism state, relative to its largest entry, and the wear increment,
relative to its peak) against Tsit5 at rtol 1e-10.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402  (puts the harness on sys.path)
from harness import time_jitted  # noqa: E402


def cycle_on(rtol, period, solver=None):
    """One cycle of ``period`` on Tsit5 (or ``solver``) with the wear cycle's
    PID settings: jitted (mech, y, t0) -> Trajectory."""
    import diffrax

    from diffwear.dynamics import simulate

    ctrl = diffrax.PIDController(rtol=rtol, atol=rtol, pcoeff=0.3, icoeff=0.4)
    return jax.jit(lambda m, y, t0: simulate(m, y, t0 + period, t0=t0, solver=solver,
                                             stepsize_controller=ctrl))


def evolution_errors(mech, ys, cycles=21_400.0, a=428.0):
    """The rig's wear over ``cycles`` with constant A = ``a`` (each wear cycle
    on the profile worn so far), its cycles integrated by Tsit5 at rtol 1e-6
    (the wear cycle's setting) and 1e-4, by ROS3P at 1e-4 / 3e-5 / 1e-5 and
    by Rodas4 at 1e-4 / 5e-5: the final
    max depth and volume against Tsit5 at rtol 1e-8 (the reference).  A = 428
    is the rig study's own (50 wear cycles).  Each run once to compile, once
    timed."""
    from diffwear.dynamics import ROS3P, Rodas4
    from diffwear.studies._wear_common import JOINT
    from diffwear.studies.rig_21400 import PERIOD
    from diffwear.wear import worn_mechanism, worn_volume
    from diffwear.wear.cycle import reset_wear

    def end_state_on(solver):
        def make(rtol):
            cycle = cycle_on(rtol, PERIOD, solver)
            return lambda m, y, t0: cycle(m, y, t0).y_final
        return make

    tsit5, ros3p, rodas4 = end_state_on(None), end_state_on(ROS3P()), end_state_on(Rodas4())

    def evolve(cycle):
        el0 = mech.element(JOINT)
        h = jnp.zeros(el0.profile.n)
        y, t = ys, PERIOD
        t_start = time.perf_counter()
        for _ in range(int(round(cycles / a))):
            worn = worn_mechanism(mech, JOINT, h)
            y0 = reset_wear(worn, JOINT, y)
            y = cycle(worn, y0, jnp.asarray(t))
            aux = worn.split(y)[2][worn.aux_slice(JOINT)]
            h = h + a * worn.element(JOINT).wear_depth(aux)
            t += PERIOD
        wall = time.perf_counter() - t_start
        return (float(jnp.max(h)) * 1e3,
                float(worn_volume(h, el0.bushing_radius, el0.law.depth)) * 1e9, wall)

    runs = [("Tsit5", 1e-8, tsit5), ("Tsit5", 1e-6, tsit5), ("Tsit5", 1e-4, tsit5),
            ("ROS3P", 1e-4, ros3p), ("ROS3P", 3e-5, ros3p), ("ROS3P", 1e-5, ros3p),
            ("Rodas4", 1e-4, rodas4), ("Rodas4", 5e-5, rodas4)]
    out = []
    for name, rtol, make in runs:
        cycle = make(rtol)
        evolve(cycle)  # compile (and warm) once
        depth, volume, wall = evolve(cycle)
        out.append(dict(solver=name, rtol=rtol, depth_mm=depth, volume_mm3=volume, s=wall))
    ref = out[0]
    for r in out:
        r["depth_rel"] = r["depth_mm"] / ref["depth_mm"] - 1.0
        r["volume_rel"] = r["volume_mm3"] / ref["volume_mm3"] - 1.0
    return out


class RigCycleReference:
    """The rig after a warm-up cycle (Tsit5 at rtol 1e-8) and its next cycle
    on Tsit5 at rtol 1e-10, against which `row` measures a solver's cycle."""

    def __init__(self):
        from diffwear.studies.rig_21400 import PERIOD, _setup

        _, self.mech, y0 = _setup()
        self.period, self.n_stiff = PERIOD, 2 * self.mech.n_coords
        self.ys = cycle_on(1e-8, PERIOD)(self.mech, y0, 0.0).y_final
        self.y_ref = np.asarray(cycle_on(1e-10, PERIOD)(self.mech, self.ys, PERIOD).y_final)

    def errors(self, y1) -> tuple[float, float]:
        """(max error of q, qd / their largest entry, max error of the cycle's
        wear increment / its peak)."""
        n, y1, ys = self.n_stiff, np.asarray(y1), np.asarray(self.ys)
        dq = np.max(np.abs(y1[:n] - self.y_ref[:n])) / np.max(np.abs(self.y_ref[:n]))
        dwear_ref = self.y_ref[n:] - ys[n:]
        dw = y1[n:] - ys[n:]
        return float(dq), float(np.max(np.abs(dw - dwear_ref)) / np.max(np.abs(dwear_ref)))

    def row(self, name: str, rtol: float, solver=None) -> dict:
        """One cycle on ``solver`` (None: Tsit5) at rtol = atol = ``rtol``:
        steps, median time, errors."""
        out, times = time_jitted(cycle_on(rtol, self.period, solver),
                                 (self.mech, self.ys, self.period), repeats=3)
        err_state, err_wear = self.errors(out.y_final)
        return dict(solver=name, rtol=rtol, steps=int(out.num_steps),
                    accepted=int(out.num_accepted_steps), s_per_cycle=times["run_s"],
                    err_state=err_state, err_wear=err_wear)


def print_rows(rows) -> None:
    """The rows of `RigCycleReference.row` as a markdown table."""
    print("| solver | rtol | steps (accepted) | s per cycle | max error, q qd / max |q qd| | "
          "max error, wear increment / peak |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['solver']} | {r['rtol']:g} | {r['steps']} ({r['accepted']}) | "
              f"{r['s_per_cycle']:.3f} | {r['err_state']:.2e} | {r['err_wear']:.2e} |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    from diffwear.dynamics import ROS3P, ROS34PW2, Rodas4

    ref = RigCycleReference()
    runs = [("Tsit5", rtol, None) for rtol in (1e-4, 1e-5, 1e-6, 1e-8)]
    runs += [("ROS3P", rtol, ROS3P()) for rtol in (1e-4, 3e-5, 1e-5, 1e-6)]
    runs += [("Rodas4", rtol, Rodas4()) for rtol in (2e-4, 1e-4, 5e-5, 1e-5)]
    runs += [("ROS34PW2, fresh Jacobian", 1e-4, ROS34PW2()),
             ("ROS34PW2, Jacobian every 5 steps", 1e-4, ROS34PW2(jacobian_every=5)),
             ("ROS34PW2, Jacobian every 20 steps", 1e-4, ROS34PW2(jacobian_every=20))]
    rows = [ref.row(name, rtol, solver) for name, rtol, solver in runs]
    print_rows(rows)
    evolutions = evolution_errors(ref.mech, ref.ys)
    print()
    print("| 21,400 cycles, A = 428 (50 wear cycles) | max depth [mm] | volume [mm^3] | "
          "depth vs reference | volume vs reference | s |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in evolutions:
        print(f"| {r['solver']} rtol {r['rtol']:g} | {r['depth_mm']:.5f} | {r['volume_mm3']:.4f} | "
              f"{r['depth_rel']:+.2e} | {r['volume_rel']:+.2e} | {r['s']:.1f} |")
    if args.json:
        write_record(args.json, rows=rows, evolutions=evolutions)


if __name__ == "__main__":
    main()
