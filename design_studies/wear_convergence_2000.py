#!/usr/bin/env python3
"""Design study: does extrapolation change the answer?  (full check)

The Ch. 7 rig over 2,000 real cycles, simulated four ways:

- every cycle (A = 1: 2,000 dynamic cycles; the reference),
- constant A = 40 (50 dynamic cycles),
- adaptive A (thesis Eq. 4-20 with our "increment_change" criterion),
- error-controlled in the cycle count (Heun-Euler pair, rtol 1e-2, atol 1 um),

and compares maximum wear depth and worn volume with the reference (goal:
within 1 %).  Run by hand (the every-cycle run takes ~15 min on 2 cores):

    .venv/bin/python design_studies/wear_convergence_2000.py [--cycles 2000] [--out out/conv]

Writes ``convergence.json`` and prints a markdown table.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)  # diffwear computes in float64

from diffwear.studies import _wear_common as common
from diffwear.studies.rig_21400 import N_THETA, PERIOD, RIG_JOINT, _setup, with_wear_joint
from diffwear.wear import Adaptive, Constant, ErrorControlled, evolve, worn_volume


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=2000)
    parser.add_argument("--out", type=Path, default=Path("out/wear-convergence"))
    args = parser.parse_args()
    n = args.cycles
    mech0, mech, y0 = _setup()
    el = mech.element(common.JOINT)
    p = common.params_of(RIG_JOINT)

    def mech_of(p):
        return with_wear_joint(mech0, common.design_of(p, RIG_JOINT), n_theta=N_THETA)

    runs = {
        "every cycle (A = 1)": dict(method=Constant(1.0)),
        "constant A = n/50": dict(method=Constant(n / 50)),
        "adaptive": dict(method=Adaptive(a0=1.0), max_dynamic=n),
        "error-controlled": dict(method=ErrorControlled(rtol=1e-2, atol=1e-6, dn0=1.0),
                                 max_dynamic=n),
    }
    rows = {}
    for name, opts in runs.items():
        fn = jax.jit(lambda p, y, opts=opts: evolve(mech_of(p), common.JOINT, y, n,
                                                    period=PERIOD, **opts))
        t0 = time.perf_counter()
        res = jax.block_until_ready(fn(p, y0)).check(name)
        wall = time.perf_counter() - t0
        rows[name] = {
            "max_depth_mm": float(res.depth[0].max()) * 1e3,
            "volume_mm3": float(worn_volume(res.depth[0], el.bushing_radius, el.law.depth)) * 1e9,
            "dynamic_cycles": int(res.stats["dynamic_cycles"]),
            "wall_time_s_incl_compile": wall,
        }
        print(f"{name}: {rows[name]}", flush=True)
    ref = rows["every cycle (A = 1)"]
    for r in rows.values():
        r["depth_rel_err"] = r["max_depth_mm"] / ref["max_depth_mm"] - 1
        r["volume_rel_err"] = r["volume_mm3"] / ref["volume_mm3"] - 1
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "convergence.json").write_text(json.dumps({"cycles": n, "runs": rows}, indent=2))
    print("| method | max depth [mm] | volume [mm^3] | dynamic cycles | depth err | volume err |")
    print("|---|---|---|---|---|---|")
    for name, r in rows.items():
        print(f"| {name} | {r['max_depth_mm']:.5f} | {r['volume_mm3']:.4f} | "
              f"{r['dynamic_cycles']} | {r['depth_rel_err']:+.2%} | {r['volume_rel_err']:+.2%} |")


if __name__ == "__main__":
    main()
