"""Sweep cases: the vmapped 64-point clearance-cycle sweep against single
runs, and the CPU sweeps of the rig's wear (batched, looped, pooled, default)
against a plain loop."""

from __future__ import annotations

import os
import time
from collections.abc import Callable

from harness import QUICK_REPEATS, timed

SWEEP_CHUNK = 16


def vmap_sweep(repeats: int) -> dict:
    """64-point sweep (8 clearances 0.01..2 mm x 8 friction coefficients) of one
    KV clearance slider-crank cycle (`sweep.models.ClearanceForce`, 100 saves),
    vmapped in chunks of 16, against 64 single jitted runs; the sweep without
    and with ``order_by`` (estimates: smaller clearance = more steps, the
    brief's guess; larger friction = more steps) and with the measured step
    counts as an oracle order.  ``lockstep_efficiency``: useful
    integrator steps / steps run in lockstep (chunk size x slowest member),
    from the step counts, so independent of the machine load.  One pass each
    (``repeats`` unused: a pass is 64 runs)."""
    import math

    import jax
    import numpy as np

    from diffwear.sweep import sweep
    from diffwear.sweep.models import ClearanceForce

    model = ClearanceForce(law="kv", cycles=1, transient_cycles=0, samples_per_cycle=100)
    # mu first: grid-order chunks of 16 mix all clearances (2 mu values each)
    grid = {"mu": np.linspace(0.02, 0.3, 8), "clearance": np.geomspace(0.01e-3, 2e-3, 8)}
    out: dict = {"points": 64, "chunk_size": SWEEP_CHUNK}

    def efficiency(res):
        steps = res["integrator_steps"][res.info["order"]].reshape(-1, SWEEP_CHUNK)
        return float(steps.sum() / (SWEEP_CHUNK * steps.max(axis=1)).sum())

    runs = {}
    for tag, order_by in (("unordered", None),
                          ("order_by", lambda p: -math.log(p["clearance"])),
                          ("order_by_mu", lambda p: p["mu"]),
                          ("oracle", "steps")):
        if order_by == "steps":
            steps = dict(zip(zip(runs["unordered"]["clearance"], runs["unordered"]["mu"]),
                             runs["unordered"]["integrator_steps"]))
            order_by = lambda p, steps=steps: steps[(p["clearance"], p["mu"])]  # noqa: E731
        res = sweep(model, model.defaults, grid, chunk_size=SWEEP_CHUNK, order_by=order_by)
        runs[tag] = res
        out[f"sweep_{tag}_s"] = res.info["run_s"]
        out[f"sweep_{tag}_compile_s"] = res.info["compile_s"]
        out[f"points_per_s_{tag}"] = 64 / res.info["run_s"]
        out[f"lockstep_efficiency_{tag}"] = efficiency(res)

    one = jax.jit(model)
    rows = runs["unordered"].table()
    first, t_first = timed(one, {k: rows[0][k] for k in model.param_names})
    single, rel = [], []
    for row in rows:
        ref, wall = timed(one, {k: row[k] for k in model.param_names})
        single.append(wall)
        # equal up to the integration tolerance only (batched rounding, see `sweep`)
        rel.append(abs(float(ref["rms_force_N"]) / row["rms_force_N"] - 1.0))
    total = sum(single)
    out.update({
        "single_runs_s": total, "single_compile_s": max(t_first - single[0], 0.0),
        "points_per_s_single": 64 / total,
        **{f"ratio_sweep_{t}_to_single": out[f"sweep_{t}_s"] / total
           for t in ("unordered", "order_by", "order_by_mu", "oracle")},
        "max_rel_diff_rms_force_sweep_vs_single": max(rel),
        "median_rel_diff_rms_force_sweep_vs_single": float(np.median(rel)),
        "max_rel_diff_at_clearance_mm_mu": [rows[int(np.argmax(rel))]["clearance"] * 1e3,
                                            rows[int(np.argmax(rel))]["mu"]],
        "integrator_steps": int(runs["unordered"]["integrator_steps"].sum()),
        "steps_min_max": [int(runs["unordered"]["integrator_steps"].min()),
                          int(runs["unordered"]["integrator_steps"].max())],
        "compile_s": out["sweep_unordered_compile_s"], "run_s": out["sweep_unordered_s"],
        "repeats": 1,
    })
    return out


# Grids of the CPU sweep cases, clearances x wear coefficients: the quasi-static
# rig's points take ~0.15 s, the dynamic rig's at 50 dynamic cycles ~10 s.
CPU_SWEEP_GRID = {"quasi-static": (8, 8), "dynamic": (2, 4)}
CPU_SWEEP_GRID_QUICK = (2, 2)


def cpu_sweep(model_name: str) -> Callable[[int], dict]:
    """One sweep of the rig's wear over clearance x k on the CPU, run four
    ways beside the baseline a user would write, a plain loop of single
    jitted runs: `sweep` batched (jit(vmap), chunks of 16), looped, pooled over
    the cores, and the default (`Auto`).  ``quasi-static``: the 21,400-cycle
    rig at the default quasi-static settings, 64 points; ``dynamic``: the
    same at the study's 50 dynamic cycles, 8 points (quick: 4 points of 200
    cycles, 1 dynamic cycle, 60 nodes).  Times
    exclude the compilation (the loop's first call, each sweep's
    ``compile_s``), as a second run finds it compiled; a pool's start-up
    (and its compilation, where the program cannot be sent) is counted.
    ``ratio_*_to_loop``: seconds per point against the loop's (<= 1: at
    least as fast).  Once each (``repeats`` unused)."""
    import jax
    import numpy as np

    from diffwear.models import QuasiStatic
    from diffwear.sweep import Auto, Batched, Looped, Pooled, sweep
    from diffwear.sweep.execution import cpu_cores
    from diffwear.sweep.models import RigWear

    def case(repeats: int) -> dict:
        quick = repeats <= QUICK_REPEATS
        settings = {"cycles": 200.0, "n_theta": 60} if quick else {}
        if model_name == "quasi-static":
            model = RigWear(wear_model=QuasiStatic(), **settings)
        else:
            model = RigWear(dynamic_cycles=1 if quick else 50, **settings)
        n_c, n_k = CPU_SWEEP_GRID_QUICK if quick else CPU_SWEEP_GRID[model_name]
        base = model.defaults
        grid = {"clearance": np.geomspace(0.02e-3, 0.1e-3, n_c),
                "k": base["k"] * np.geomspace(0.5, 1.5, n_k)}
        points = n_c * n_k
        one = jax.jit(model)
        rows = [{**base, "clearance": c, "k": k} for c in grid["clearance"] for k in grid["k"]]
        _, first = timed(one, rows[0])
        t0 = time.perf_counter()
        loop = [jax.block_until_ready(one(r)) for r in rows]
        loop_s = time.perf_counter() - t0
        out = {"points": points, "cores": cpu_cores(), "loop_s": loop_s,
               "loop_compile_s": max(first - loop_s / points, 0.0),
               "points_per_s_loop": points / loop_s}
        # chunks of 16: a 64-point vmapped quasi-static rig deadlocks XLA's
        # multi-threaded CPU runtime here (every thread idle; 16 points run,
        # mostly, and 64 with XLA_FLAGS=--xla_cpu_multi_thread_eigen=false,
        # which the record's run sets: `xla_flags`)
        out["xla_flags"] = os.environ.get("XLA_FLAGS", "")
        for tag, execution in (("batched", Batched(chunk_size=16)), ("looped", Looped()),
                               ("pooled", Pooled()), ("auto", Auto())):
            res = sweep(model, base, grid, execution=execution)
            out[f"{tag}_s"] = res.info["run_s"]
            out[f"{tag}_compile_s"] = res.info["compile_s"]
            out[f"{tag}_processes"] = res.info["processes"]
            out[f"points_per_s_{tag}"] = points / res.info["run_s"]
            out[f"ratio_{tag}_to_loop"] = res.info["run_s"] / loop_s
            if tag == "auto":
                out["auto_ran"] = res.info["execution"]
            if tag in ("pooled", "auto") and "pool_program" in res.info:
                out[f"{tag}_program"] = res.info["pool_program"]
            depth = np.array([float(r["max_depth_mm"]) for r in loop])
            out[f"max_rel_diff_{tag}_vs_loop"] = float(np.max(np.abs(
                res["max_depth_mm"] / depth - 1.0)))
        out.update({"compile_s": out["loop_compile_s"], "run_s": out["auto_s"],
                    "note": f"{points} points; default sweep ran {out['auto_ran']} "
                            f"({out['auto_processes']} processes): "
                            f"{out['ratio_auto_to_loop']:.2f}x the loop's time"})
        return out

    return case
