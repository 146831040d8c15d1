#!/usr/bin/env python3
"""Sweeps at accelerator scale: one prepared run of the batched workloads.

    python benchmarks/gpu.py [--json PATH] [--quick]

Run it on a GPU machine through ``benchmarks/gpu.sh``, which runs it once on
the GPU and once on the same host's CPU (``JAX_PLATFORMS=cpu``, smaller
batches) so that both records come from one machine.  Cases (first calls,
i.e. compilations, timed apart):

* ``two_joint_lives``: quasi-static lives of the Ch. 8 design at the default
  settings (`diffwear.design.TwoJointLife().prepared()`), ``jax.vmap`` over
  uniform designs in the Table 8-3 box, in chunks: designs/s;
* ``qs_rig_sweep``: the 21,400-cycle rig on the quasi-static model over
  clearance x k (`sweep`, batched): points/s;
* ``dynamic_rig_sweep``: the same on the dynamic model at the study's 50
  dynamic cycles: points/s;
* ``dynamic_rig_one``: one dynamic rig run (3 dynamic cycles), the seconds
  a single run takes on this device.

``--quick``: tiny batches and reduced settings (a smoke run; what the test
suite runs on a CPU).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "src") not in sys.path:
    sys.path.insert(0, str(ROOT / "src"))

# Batches: (designs or points, chunk) on a GPU, and on the host's CPU.
FULL = {"gpu": {"lives": (65_536, 16_384), "qs_rig": (4_096, 4_096), "dyn_rig": (1_024, 1_024)},
        "cpu": {"lives": (1_024, 256), "qs_rig": (36, 36), "dyn_rig": (8, 8)}}
QUICK = {"lives": (64, 32), "qs_rig": (4, 4), "dyn_rig": (2, 2)}


def _timed(fn, *args):
    import jax

    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - t0


def two_joint_lives(n: int, chunk: int) -> dict:
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.design import LOWER, UPPER, TwoJointLife

    xs = LOWER + (UPPER - LOWER) * np.random.default_rng(3).uniform(size=(n, 4))
    f = jax.jit(jax.vmap(TwoJointLife().prepared()))
    _, first = _timed(f, jnp.asarray(xs[:chunk]))
    t0 = time.perf_counter()
    lives = np.concatenate([np.asarray(f(jnp.asarray(xs[i:i + chunk])))
                            for i in range(0, n, chunk)])
    run = time.perf_counter() - t0
    return {"designs": n, "chunk": chunk, "first_call_s": first, "run_s": run,
            "designs_per_s": n / run, "finite": bool(np.all(np.isfinite(lives)))}


def rig_sweep(model, n: int, chunk: int) -> dict:
    import math

    import numpy as np

    from diffwear.sweep import Batched, sweep
    from diffwear.wear.status import from_code, not_computed

    side = int(math.isqrt(n))
    base = model.defaults
    grid = {"clearance": np.geomspace(0.02e-3, 0.1e-3, side),
            "k": base["k"] * np.geomspace(0.5, 1.5, n // side)}
    res = sweep(model, base, grid, execution=Batched(chunk_size=chunk))
    return {"points": len(res), "chunk": res.info["chunk_size"], "chunks": res.info["chunks"],
            "compile_s": res.info["compile_s"], "run_s": res.info["run_s"],
            "points_per_s": len(res) / res.info["run_s"],
            "failed": int(np.sum(not_computed(from_code(res["status"]))))}


def dynamic_rig_one(dynamic_cycles: int, cycles: float, n_theta: int) -> dict:
    import jax

    from diffwear.sweep.models import RigWear

    model = RigWear(dynamic_cycles=dynamic_cycles, cycles=cycles, n_theta=n_theta)
    f = jax.jit(model)
    _, first = _timed(f, model.defaults)
    runs = [_timed(f, model.defaults)[1] for _ in range(3)]
    return {"dynamic_cycles": dynamic_cycles, "first_call_s": first,
            "run_s": sorted(runs)[1], "runs_s": runs}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    import jax

    jax.config.update("jax_enable_x64", True)
    from diffwear.models import QuasiStatic
    from diffwear.sweep.models import RigWear

    backend = jax.default_backend()
    sizes = QUICK if args.quick else FULL["cpu" if backend == "cpu" else "gpu"]
    reduced = {"cycles": 200.0, "n_theta": 60} if args.quick else {}
    out: dict = {}
    log = lambda name, r: print(f"{name}: {json.dumps(r)}", flush=True)  # noqa: E731
    out["two_joint_lives"] = two_joint_lives(*sizes["lives"])
    log("two_joint_lives", out["two_joint_lives"])
    out["qs_rig_sweep"] = rig_sweep(RigWear(wear_model=QuasiStatic(), **reduced),
                                    *sizes["qs_rig"])
    log("qs_rig_sweep", out["qs_rig_sweep"])
    out["dynamic_rig_sweep"] = rig_sweep(
        RigWear(dynamic_cycles=1 if args.quick else 50, **reduced), *sizes["dyn_rig"])
    log("dynamic_rig_sweep", out["dynamic_rig_sweep"])
    out["dynamic_rig_one"] = dynamic_rig_one(1 if args.quick else 3,
                                             reduced.get("cycles", 21_400.0),
                                             reduced.get("n_theta", 180))
    log("dynamic_rig_one", out["dynamic_rig_one"])
    record = {"date": datetime.date.today().isoformat(), "backend": backend,
              "device": str(jax.devices()[0].device_kind), "jax": jax.__version__,
              "host": platform.node(), "cpus": os.cpu_count(), "quick": args.quick,
              "cases": out}
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(record, indent=2) + "\n")
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
