"""Experiment: a Rosenbrock step with the exact Jacobian on one rig wear cycle,
against Tsit5 (the dynamic model's solver) at matched accuracy.

The stiffness of the rig's right-hand side sits in the pin's contact with the
elastic foundation, i.e. in the mechanism coordinates and velocities (18 of
the 199 states); the 181 wear and contact states of the clearance joint never
feed back within a cycle (their Jacobian columns are exactly zero, checked
below).  So the exact Jacobian is d f / d(q, qd), 18 forward-mode tangents,
and the step matrix (I / (h gamma) - J) factorises as one 18 x 18 LU plus a
back-substitution for the wear rows.

Method: ROS3P (Lang and Verwer 2001, BIT 41: third order, A-stable, embedded
second-order solution for step control), in the transformed form of Hairer
and Wanner (Solving ODEs II, eq. IV.7.25).  The coefficients are checked here
by the global error's order on a scalar test equation before any timing.

    python benchmarks/experiments/rosenbrock_rig_cycle.py [--json out.json]

Prints a table: for each solver and tolerance, steps per cycle, wall time per
cycle (median of 3 after compile) and the error of the cycle's end state
(the mechanism state, relative to its largest entry, and the wear increment,
relative to its peak) against Tsit5 at rtol 1e-10.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

# ROS3P, transformed coefficients (Hairer-Wanner IV.7.25)
GAMMA = 0.5 + math.sqrt(3.0) / 6.0
A21 = 1.0 / GAMMA
A31, A32 = 1.0 / GAMMA, 0.0
C21 = -1.607695154586736
C31 = -3.464101615137755
C32 = -1.732050807568877
ALPHA = (0.0, 1.0, 1.0)
GAMMAS = (GAMMA, -0.2113248654051871, -1.077350269189626)
M = (2.0, 0.5773502691896258, 0.4226497308103742)
ME = (2.113248654051871, 1.0, 0.4226497308103742)


def ros3p_step(f, t, y, h, w_solve, ft):
    """One ROS3P step from (t, y) of length h: (y1, error estimate).
    ``w_solve(rhs)`` applies (I / (h gamma) - J)^-1; ``ft`` = df/dt at (t, y)."""
    u1 = w_solve(f(t, y) + GAMMAS[0] * h * ft)
    u2 = w_solve(f(t + ALPHA[1] * h, y + A21 * u1) + (C21 / h) * u1 + GAMMAS[1] * h * ft)
    u3 = w_solve(f(t + ALPHA[2] * h, y + A31 * u1 + A32 * u2) + (C31 * u1 + C32 * u2) / h
                 + GAMMAS[2] * h * ft)
    y1 = y + M[0] * u1 + M[1] * u2 + M[2] * u3
    err = (M[0] - ME[0]) * u1 + (M[1] - ME[1]) * u2 + (M[2] - ME[2]) * u3
    return y1, err


def rosenbrock(f, t0, t1, y0, n_stiff, *, rtol, atol, h0=1e-4, max_steps=200_000):
    """Integrate y' = f(t, y) from t0 to t1 with ROS3P.  The Jacobian is exact
    in the first ``n_stiff`` states (columns); the remaining states must not
    feed back into f (their Jacobian columns are zero).  Returns (y1, steps,
    accepted, whether it reached t1)."""
    def jac(t, y):
        z = y[:n_stiff]
        j = jax.jacfwd(lambda z: f(t, jnp.concatenate([z, y[n_stiff:]])))(z)  # (n, n_stiff)
        ft = jax.jvp(lambda s: f(s, y), (t,), (jnp.ones_like(t),))[1]
        return j[:n_stiff], j[n_stiff:], ft

    def solve(lu, j21, hg, rhs):
        top = jax.scipy.linalg.lu_solve(lu, rhs[:n_stiff])
        return jnp.concatenate([top, hg * (rhs[n_stiff:] + j21 @ top)])

    def step(t, y, h):
        j11, j21, ft = jac(t, y)
        hg = h * GAMMA
        lu = jax.scipy.linalg.lu_factor(jnp.eye(n_stiff) / hg - j11)
        return ros3p_step(f, t, y, h, lambda rhs: solve(lu, j21, hg, rhs), ft)

    def cond(c):
        t, _, _, k, _, ok = c
        return (t < t1) & (k < max_steps) & ok

    def body(c):
        t, y, h, k, acc, ok = c
        h = jnp.minimum(h, t1 - t)
        y1, err = step(t, y, h)
        scale = atol + rtol * jnp.maximum(jnp.abs(y), jnp.abs(y1))
        e = jnp.sqrt(jnp.mean((err / scale) ** 2))
        finite = jnp.all(jnp.isfinite(y1)) & jnp.isfinite(e)
        accept = finite & (e <= 1.0)
        factor = jnp.where(finite, jnp.clip(0.9 * jnp.where(e > 0, e, 1e-10) ** (-1.0 / 3.0),
                                            0.2, 5.0), 0.2)
        return (jnp.where(accept, t + h, t), jnp.where(accept, y1, y), h * factor, k + 1,
                acc + accept, ok & (h > 1e-14))

    t, y, _, k, acc, ok = jax.lax.while_loop(
        cond, body, (jnp.asarray(t0, float), y0, jnp.asarray(h0, float), 0, 0,
                     jnp.array(True)))
    return y, k, acc, ok & (t >= t1)


def check_order() -> list[float]:
    """Global error at t = 1 of y' = -y^2 + cos t (y(0) = 1) on fixed steps
    h, h/2, h/4 (the controller off): the observed orders must be ~3."""
    def f(t, y):
        return -y ** 2 + jnp.cos(t) + 0.0 * t

    def fixed(nsteps):
        h = 1.0 / nsteps

        def body(i, y):
            t = i * h
            j = jax.jacfwd(lambda z: f(t, z))(y)
            ft = jax.jvp(lambda s: f(s, y), (t,), (jnp.ones_like(t),))[1]
            w = jnp.eye(1) / (h * GAMMA) - j
            return ros3p_step(f, t, y, h, lambda rhs: jnp.linalg.solve(w, rhs), ft)[0]

        return jax.lax.fori_loop(0, nsteps, body, jnp.ones(1))

    ref = fixed(4096)
    errs = [float(jnp.abs(fixed(n) - ref)[0]) for n in (16, 32, 64)]
    return [math.log2(errs[i] / errs[i + 1]) for i in range(2)]


def tsit5_cycle(rtol, period):
    """One cycle of ``period`` on Tsit5 (the wear cycle's PID settings):
    jitted (mech, y, t0) -> Trajectory."""
    import diffrax

    from diffwear.dynamics import simulate

    ctrl = diffrax.PIDController(rtol=rtol, atol=rtol, pcoeff=0.3, icoeff=0.4)
    return jax.jit(lambda m, y, t0: simulate(m, y, t0 + period, t0=t0, stepsize_controller=ctrl))


def ros3p_cycle(rtol, period, n_stiff):
    """One cycle on ROS3P: jitted (mech, y, t0) -> (y1, steps, accepted, ok)."""
    from diffwear.dynamics.equations import Baumgarte, vector_field

    return jax.jit(lambda m, y, t0: rosenbrock(
        lambda t, z: vector_field(t, z, (m, Baumgarte())), t0, t0 + period, y, n_stiff,
        rtol=rtol, atol=rtol))


def evolution_errors(mech, ys, n_stiff, cycles=21_400.0, a=428.0):
    """The rig's wear over ``cycles`` with constant A = ``a`` (each wear cycle
    on the profile worn so far), its cycles integrated by Tsit5 at rtol 1e-6
    (the wear cycle's setting) and 1e-4, and by ROS3P at 1e-4 / 1e-5: the final
    max depth and volume against Tsit5 at rtol 1e-8 (the reference).  A = 428
    is the rig study's own (50 wear cycles).  Each run once to compile, once
    timed."""
    from diffwear.studies._wear_common import JOINT
    from diffwear.studies.rig_21400 import PERIOD
    from diffwear.wear import worn_mechanism, worn_volume
    from diffwear.wear.cycle import reset_wear

    def tsit5(rtol):
        cycle = tsit5_cycle(rtol, PERIOD)
        return lambda m, y, t0: cycle(m, y, t0).y_final

    def ros3p(rtol):
        cycle = ros3p_cycle(rtol, PERIOD, n_stiff)
        return lambda m, y, t0: cycle(m, y, t0)[0]

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
            ("ROS3P", 1e-4, ros3p), ("ROS3P", 3e-5, ros3p), ("ROS3P", 1e-5, ros3p)]
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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    orders = check_order()
    print("ROS3P observed orders on the test equation:", [round(o, 2) for o in orders])
    assert all(2.7 < o < 3.4 for o in orders), orders

    from diffwear.dynamics.equations import Baumgarte, vector_field
    from diffwear.studies.rig_21400 import PERIOD, _setup

    mech0, mech, y0 = _setup()
    n_stiff = 2 * mech.n_coords
    jcols = np.asarray(jax.jacfwd(lambda y: vector_field(0.3, y, (mech, Baumgarte())))(y0))
    assert np.abs(jcols[:, n_stiff:]).max() == 0.0, \
        "the wear/contact states feed back: J is not block"

    ys = tsit5_cycle(1e-8, PERIOD)(mech, y0, 0.0).y_final
    ref = tsit5_cycle(1e-10, PERIOD)(mech, ys, PERIOD)
    y_ref = np.asarray(ref.y_final)
    dwear_ref = y_ref[n_stiff:] - np.asarray(ys)[n_stiff:]

    def errors(y1):
        y1 = np.asarray(y1)
        dq = np.max(np.abs(y1[:n_stiff] - y_ref[:n_stiff])) / np.max(np.abs(y_ref[:n_stiff]))
        dw = y1[n_stiff:] - np.asarray(ys)[n_stiff:]
        return float(dq), float(np.max(np.abs(dw - dwear_ref)) / np.max(np.abs(dwear_ref)))

    def timed(fn, *a):
        out = jax.block_until_ready(fn(*a))
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            out = jax.block_until_ready(fn(*a))
            times.append(time.perf_counter() - t0)
        return out, float(np.median(times))

    rows = []
    for rtol in (1e-4, 1e-5, 1e-6, 1e-8):
        out, s = timed(tsit5_cycle(rtol, PERIOD), mech, ys, PERIOD)
        rows.append(dict(solver="Tsit5", rtol=rtol, steps=int(out.num_steps),
                         accepted=int(out.num_accepted_steps), s_per_cycle=s,
                         **dict(zip(("err_state", "err_wear"), errors(out.y_final)))))
    for rtol in (1e-4, 3e-5, 1e-5, 1e-6):
        (y1, k, acc, ok), s = timed(ros3p_cycle(rtol, PERIOD, n_stiff), mech, ys,
                                    jnp.asarray(PERIOD))
        rows.append(dict(solver="ROS3P (exact 18x18 J)", rtol=rtol, steps=int(k),
                         accepted=int(acc), s_per_cycle=s, ok=bool(ok),
                         **dict(zip(("err_state", "err_wear"), errors(y1)))))
    print("| solver | rtol | steps (accepted) | s per cycle | max error, q qd / max |q qd| | "
          "max error, wear increment / peak |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['solver']} | {r['rtol']:g} | {r['steps']} ({r['accepted']}) | "
              f"{r['s_per_cycle']:.3f} | {r['err_state']:.2e} | {r['err_wear']:.2e} |")
    evolutions = evolution_errors(mech, ys, n_stiff)
    print()
    print("| 21,400 cycles, A = 428 (50 wear cycles) | max depth [mm] | volume [mm^3] | "
          "depth vs reference | volume vs reference | s |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in evolutions:
        print(f"| {r['solver']} rtol {r['rtol']:g} | {r['depth_mm']:.5f} | {r['volume_mm3']:.4f} | "
              f"{r['depth_rel']:+.2e} | {r['volume_rel']:+.2e} | {r['s']:.1f} |")
    if args.json:
        import os
        import platform
        import subprocess

        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                capture_output=True, text=True).stdout.strip()
        meta = {"date": time.strftime("%Y-%m-%d"), "commit": commit, "jax": jax.__version__,
                "python": platform.python_version(), "device": str(jax.devices()[0]),
                "cpu_count": os.cpu_count(), "load_average_1min": os.getloadavg()[0]}
        Path(args.json).write_text(json.dumps({"meta": meta, "orders": orders, "rows": rows,
                                               "evolutions": evolutions},
                                              indent=1))


if __name__ == "__main__":
    main()
