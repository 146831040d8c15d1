"""Experiment: how much the FEM route's rig-21400 result moves between runs
that differ at round-off, per setting.

The FEM route's worn profile keeps a node-to-node roughness of about one
wear step's depth (`diffwear.wear.fem_route`, "Stiffness of the wear step"),
and which nodes stand out depends on the last bits of the run, so a single
run's maximum depth is one draw.  Each setting is compiled once and run
``--runs`` times from the study's start with the crank centre's initial x
moved by k x 1e-12 m (k = 0, 1, ...: k = 0 is the study's own run; the
constraint stabilisation absorbs it within the warm-up cycle); per
run: max depth, max of the profile averaged over 5 nodes (+-4 deg,
`diffwear.wear.arc_peak_depth`),
worn volume, Archard volume k x sum(N ds), node-to-node roughness (rms of
the second difference) and the run time; then mean and standard deviation.

Settings (`--settings`, comma-separated): ``rodas4`` and ``tsit5`` (the
route's defaults on each integrator at its `CYCLE_INTEGRATORS` tolerance),
``rodas4-j8`` (J from every 8th sample), ``rodas4-m1`` and ``rodas4-m2``
(compliance rebuilt every cycle, every second).

    python benchmarks/experiments/fem_route_scatter.py [--runs 8] [--json out.json]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import jax  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402

SETTINGS = {  # name -> (integrator, FemWearModel options)
    "rodas4": ("rodas4", {}),
    "tsit5": ("tsit5", {}),
    "rodas4-j8": ("rodas4", {"jacobian_samples": 8}),
    "rodas4-m1": ("rodas4", {"refresh_interval": 1}),
    "rodas4-m2": ("rodas4", {"refresh_interval": 2}),
}
PERTURBATION = 1e-12  # m of the crank centre's x per run index


def scatter(setting: str, runs: int) -> dict:
    from diffwear.models import FemRoute
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import N_THETA, PERIOD, RIG_JOINT, TARGET_DYNAMIC, _setup
    from diffwear.wear import arc_peak_depth, worn_volume
    from diffwear.wear.fem_route import default_model

    integrator, options = SETTINGS[setting]
    mech0, _, y0 = _setup()
    mech_of_p = common.mech_builder(mech0, RIG_JOINT, N_THETA)
    efm = common.dynamic_model(RIG_CYCLES, TARGET_DYNAMIC, integrator)
    model = FemRoute(fem=default_model(RIG_JOINT, **options), extrapolation=efm.extrapolation,
                     cycle=efm.cycle, dynamic_cycles=efm.dynamic_cycles)
    p = common.params_of(RIG_JOINT)

    def run(p, y):  # as the study, in one call (it runs in chunks: the same result)
        return model.evolve(mech_of_p(p), (common.JOINT,), y, period=PERIOD, cycles=RIG_CYCLES,
                            wall_thickness=RIG_JOINT.wall)

    t0 = time.perf_counter()
    compiled = jax.jit(run).lower(p, y0).compile()
    out: dict = {"integrator": integrator, "options": options,
                 "compile_s": time.perf_counter() - t0, "runs": []}
    for k in range(runs):
        y = y0.at[0].add(PERTURBATION * k)
        t0 = time.perf_counter()
        res = jax.block_until_ready(compiled(p, y))
        wall = time.perf_counter() - t0
        res.check(f"{setting} run {k}")
        d = np.asarray(res.depth[0]) * 1e3
        out["runs"].append({
            "max_depth_mm": float(d.max()),
            "smoothed_max_depth_mm": float(arc_peak_depth(res.depth[0])) * 1e3,
            "volume_mm3": float(worn_volume(res.depth[0], RIG_JOINT.bushing_radius,
                                            RIG_JOINT.depth)) * 1e9,
            "archard_mm3": float(RIG_JOINT.k * res.state.load_sliding[0]) * 1e9,
            "roughness_mm": float(np.sqrt(np.mean((np.roll(d, 1) - 2 * d + np.roll(d, -1)) ** 2))),
            "run_s": wall})
    for key in ("max_depth_mm", "smoothed_max_depth_mm", "volume_mm3", "archard_mm3",
                "roughness_mm", "run_s"):
        v = np.array([r[key] for r in out["runs"]])
        out[key] = {"mean": float(v.mean()), "sd": float(v.std(ddof=1)) if v.size > 1 else 0.0,
                    "min": float(v.min()), "max": float(v.max())}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--settings", default="rodas4,tsit5,rodas4-j8,rodas4-m1")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    results = {}
    for name in args.settings.split(","):
        results[name] = r = scatter(name, args.runs)
        print(f"{name}: " + ", ".join(
            f"{key} {r[key]['mean']:.4f} +- {r[key]['sd']:.4f}"
            for key in ("max_depth_mm", "smoothed_max_depth_mm", "volume_mm3", "archard_mm3",
                        "roughness_mm", "run_s")), flush=True)
    if args.json:
        write_record(args.json, experiment="fem_route_scatter", perturbation_m=PERTURBATION,
                     results=results)


if __name__ == "__main__":
    main()
