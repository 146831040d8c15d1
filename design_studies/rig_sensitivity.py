#!/usr/bin/env python3
"""Design study: sensitivity of the rig's wear to its parameters, and the
spread of the wear coefficient.

At the thesis rig (`sweep.models.RigWear` defaults, reduced to ``--cycles``
real cycles in ``--dynamic`` dynamic cycles, ``--n-theta`` grid points):

1. elasticities d ln y / d ln p of max depth and worn volume w.r.t. every
   physical parameter (reverse-mode AD through the whole evolution), checked
   against central differences (step 1e-4 p), with the cycle tolerance
   tightened to ``--cycle-rtol`` (AD holds diffrax's adaptive steps fixed);
   a tornado plot;
2. the wear coefficient sampled log-normally, +-50 % (95 %) around Table 7-2's
   k (Podra & Andersson 1999's scatter between tests; see
   `sweep.sensitivity`), ``--samples`` points through `sweep`: distribution of
   max depth and of the wear life to 0.5 mm against the linear estimate.

Run by hand (minutes: the reverse-mode compile dominates):

    .venv/bin/python design_studies/rig_sensitivity.py --out out/rig-sensitivity

Writes elasticities.csv, tornado_max_depth_mm.png, hist_max_depth_mm.png,
hist_life_cycles.png and summary.json (results in design_studies/results/
are a copy of a run's summary.json).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)  # diffwear computes in float64

from diffwear.io import OutputDir
from diffwear.plots import sweep as plots_sweep
from diffwear.sweep import sensitivity as sens_mod
from diffwear.sweep.models import RigWear

LIFE_LIMIT_MM = 0.5  # a depth limit for the life estimate (about the rig's measured 0.485 mm)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=float, default=2140.0)
    ap.add_argument("--dynamic", type=int, default=5)
    ap.add_argument("--n-theta", type=int, default=90)
    ap.add_argument("--cycle-rtol", type=float, default=1e-8)
    ap.add_argument("--samples", type=int, default=32)
    ap.add_argument("--out", type=Path, default=Path("out/rig-sensitivity"))
    ap.add_argument("--overwrite", action="store_true")
    a = ap.parse_args()
    out = OutputDir(a.out, overwrite=a.overwrite)
    model = RigWear(cycles=a.cycles, dynamic_cycles=a.dynamic, n_theta=a.n_theta,
                    force_samples=37, cycle_rtol=a.cycle_rtol, cycle_atol=a.cycle_rtol)
    point = model.defaults
    outputs = ["max_depth_mm", "volume_mm3"]
    t0 = time.perf_counter()
    ad = sens_mod.sensitivity(model, point, outputs=outputs)
    t_ad = time.perf_counter() - t0
    t0 = time.perf_counter()
    fd = sens_mod.finite_differences(model, point, outputs=outputs, rel_step=1e-4)
    t_fd = time.perf_counter() - t0
    print(ad.markdown())
    rel = {o: {p: abs(ad.gradient[o][p] / fd.gradient[o][p] - 1) for p in ad.wrt}
           for o in outputs}
    print("AD vs FD relative difference:", rel)
    ad.to_csv(out.file("elasticities.csv"))
    plots_sweep.tornado(out.file("tornado_max_depth_mm.png"), ad, "max_depth_mm",
                     title=f"rig, {a.cycles:g} cycles: max wear depth")
    t0 = time.perf_counter()
    prop = sens_mod.propagate_scatter(model, point, "k", scatter=0.5, n=a.samples, seed=0,
                                      outputs=outputs,
                                      life=("max_depth_mm", LIFE_LIMIT_MM, a.cycles))
    t_uq = time.perf_counter() - t0
    plots_sweep.histogram(out.file("hist_max_depth_mm.png"), prop, "max_depth_mm",
                       xlabel="max wear depth [mm]")
    plots_sweep.histogram(out.file("hist_life_cycles.png"), prop, "life_cycles",
                       xlabel=f"cycles to {LIFE_LIMIT_MM} mm")
    print(prop.stats)
    out.json("summary.json", {
        # the computation's settings; where the files went is the caller's business
        "settings": {k: v for k, v in vars(a).items() if k not in ("out", "overwrite")},
        "point": point,
        "outputs": ad.outputs, "elasticity_ad": ad.elasticities(),
        "elasticity_fd": fd.elasticities(), "ad_vs_fd_rel_diff": rel,
        "scatter": prop.summary(), "wall_s": {"ad": t_ad, "fd": t_fd, "propagation": t_uq},
    })


if __name__ == "__main__":
    main()
