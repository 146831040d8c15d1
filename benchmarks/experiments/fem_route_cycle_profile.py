"""Experiment: where one wear cycle of the FEM route's rig-21400 run spends
its time, and how accurate its sampled joint force is on each integrator.

One rig cycle (180-node grid, the route's defaults: 65 samples, 180 x 4 Q9
ring) after a warm-up cycle, on the unworn bushing and on a worn one (the
stored FEM-route profile after 21,400 cycles,
``design_studies/results/studies/rig-21400-fem/wear_profile.csv``), timed part
by part, each jitted on its own (median of 5 calls after compile):

1. **dynamics**: the cycle saved at the 65 sample times on Tsit5 (rtol 1e-6,
   interpolated and stepped onto the samples) and on Rodas4 (rtol 1e-4,
   interpolated, and stepped onto the samples without dense output: the
   route's cycle), with the steps taken and the error of the sampled joint
   force against Tsit5 at rtol 1e-10 (largest over the samples, relative to
   the peak force) and of the cycle's FE depth increment;
2. **ring_compliance**: mesh and condensation of the worn ring;
3. **fem_increment**: the 65 given-force FE solves and the quadrature;
4. **implicit_step**: the implicit wear step's J from every 8th sample and
   from all of them (`FemWearModel.jacobian_samples`).

The EFM route's cycle (Rodas4, nothing saved) is timed beside it.

    python benchmarks/experiments/fem_route_cycle_profile.py [--json out.json]
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402  (puts the harness on sys.path)
from harness import time_jitted  # noqa: E402

PROFILE = ROOT / "design_studies" / "results" / "studies" / "rig-21400-fem" / "wear_profile.csv"


def stored_profile(n: int) -> np.ndarray:
    """The stored FEM-route rig profile [m] on the n-node grid (its rows are theta
    from 0 to 2 pi, the last repeating the first)."""
    with open(PROFILE, newline="") as f:
        rows = list(csv.DictReader(f))
    depth = np.array([float(r["depth_mm"]) for r in rows]) * 1e-3
    assert depth.size in (n, n + 1), depth.size
    return depth[:n]


def profile_cycle(mech, depth) -> dict:
    from diffwear.presets import RIG_JOINT
    from diffwear.studies._wear_common import JOINT
    from diffwear.studies.rig_21400 import PERIOD, _setup
    from diffwear.wear import fem_route as fr
    from diffwear.wear.cycle import cycle_integrator, wear_cycle
    from diffwear.wear.evolution import _with_profile

    model = fr.default_model(RIG_JOINT)
    el = mech.element(JOINT)
    index = fr.clearance_element(mech, JOINT)[0]
    m = _with_profile(mech, index, el.profile.clearance + depth)
    y0 = _setup()[2]
    warm = jax.jit(lambda y: wear_cycle(m, JOINT, y, 0.0, PERIOD))(y0)
    n_save = model.n_samples + 1

    def cycle(solver, tol, step, save=True):
        return jax.jit(lambda m, y: wear_cycle(m, JOINT, y, PERIOD, PERIOD,
                                               n_save=n_save if save else None, rtol=tol,
                                               atol=tol, solver=solver, step_to_saves=step))

    rodas4, rodas_tol = cycle_integrator("rodas4")
    variants = {"tsit5 interpolated": (None, 1e-6, False),
                "tsit5 stepped": (None, 1e-6, True),
                "rodas4 interpolated": (rodas4, rodas_tol, False),
                "rodas4 stepped (route)": (fr.sampling_solver(rodas4), rodas_tol, True)}
    ref = cycle(None, 1e-10, True)(m, warm.y_end)
    contact = fr.ring_contact(fr.ring_compliance(model, el.bushing_radius, depth),
                              fr.unworn_tributary(model, el.bushing_radius, el.profile.n),
                              el.bushing_radius, el.pin_radius, depth, el.law.depth)
    k = el.wear.coefficient
    increment = jax.jit(lambda c, ys, ts: fr.fem_increment(c, fr.joint_samples(m, JOINT, ys),
                                                           ts, k))
    f_ref = np.asarray(fr.joint_samples(m, JOINT, ref.ys).force)
    peak_force = float(np.max(np.linalg.norm(f_ref, axis=1)))
    dh_ref = np.asarray(increment(contact, ref.ys, ref.ts).depth_increment)
    out: dict = {"max_depth_mm": float(np.max(depth)) * 1e3, "dynamics": {}}
    for name, (solver, tol, step) in variants.items():
        traj, t = time_jitted(cycle(solver, tol, step), (m, warm.y_end), 5)
        f = np.asarray(fr.joint_samples(m, JOINT, traj.ys).force)
        dh = np.asarray(increment(contact, traj.ys, traj.ts).depth_increment)
        out["dynamics"][name] = {
            "run_s": t["run_s"], "steps": int(traj.num_steps),
            "force_error": float(np.max(np.linalg.norm(f - f_ref, axis=1))) / peak_force,
            "increment_peak_error": float(np.max(np.abs(dh - dh_ref)) / dh_ref.max()),
            "increment_total_error": float(abs(dh.sum() / dh_ref.sum() - 1))}
    _, t = time_jitted(cycle(rodas4, rodas_tol, False, save=False), (m, warm.y_end), 5)
    out["efm_route_cycle_rodas4_s"] = t["run_s"]
    _, t = time_jitted(jax.jit(lambda h: fr.ring_compliance(model, el.bushing_radius, h)),
                       (depth,), 5)
    out["ring_compliance_s"] = t["run_s"]
    inc, t = time_jitted(increment, (contact, ref.ys, ref.ts), 5)
    out["fem_increment_s"] = t["run_s"]
    samples = fr.joint_samples(m, JOINT, ref.ys)
    for js in (8, model.n_samples):
        step = jax.jit(lambda c, s, ts, inc, js=js: fr.implicit_step(c, s, ts, inc, k, 428.0, js))
        _, t = time_jitted(step, (contact, samples, ref.ts, inc), 5)
        out[f"implicit_step_j{js}_s"] = t["run_s"]
    route = out["dynamics"]["rodas4 stepped (route)"]["run_s"]
    out["route_cycle_s"] = (route + out["ring_compliance_s"] + out["fem_increment_s"]
                            + out[f"implicit_step_j{model.n_samples}_s"])
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    from diffwear.studies.rig_21400 import _setup

    mech = _setup()[1]
    n = mech.element("crank_rod").profile.n
    results = {}
    for tag, depth in (("unworn", jnp.zeros(n)), ("worn", jnp.asarray(stored_profile(n)))):
        results[tag] = r = profile_cycle(mech, depth)
        print(f"{tag} (max depth {r['max_depth_mm']:.3f} mm):")
        for name, d in r["dynamics"].items():
            print(f"  {name:24s} {d['run_s'] * 1e3:7.1f} ms {d['steps']:5d} steps, force error "
                  f"{d['force_error']:.1e}, increment peak {d['increment_peak_error']:.1e} "
                  f"total {d['increment_total_error']:.1e}")
        print(f"  EFM route cycle (Rodas4) {r['efm_route_cycle_rodas4_s'] * 1e3:.1f} ms; "
              f"ring_compliance {r['ring_compliance_s'] * 1e3:.1f} ms; fem_increment "
              f"{r['fem_increment_s'] * 1e3:.1f} ms; implicit_step J8 "
              f"{r['implicit_step_j8_s'] * 1e3:.1f} ms, J64 {r['implicit_step_j64_s'] * 1e3:.1f} "
              f"ms; the route's cycle {r['route_cycle_s'] * 1e3:.1f} ms")
    if args.json:
        write_record(args.json, experiment="fem_route_cycle_profile", results=results)


if __name__ == "__main__":
    main()
