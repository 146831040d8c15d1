"""The calibration loop on the shipped 21,400-cycle campaigns."""

from __future__ import annotations

import time
from pathlib import Path

from harness import QUICK_REPEATS, ROOT, timed

CALIBRATION_DATASETS = ROOT / "design_studies" / "calibration"
CALIBRATION_DATASET = CALIBRATION_DATASETS / "campaign_slow_run_in"


def calibration_loop(repeats: int, dataset: Path = CALIBRATION_DATASET,
                     goal_s: float = 300.0) -> dict:
    """The calibration loop on a 21,400-cycle campaign (by default the shipped
    ``campaign_slow_run_in``: four inspections of 360-point profiles,
    weighings, the force over the first cycle).  Full: the whole ``diffwear
    calibrate`` (load, base fit, forward selection with every candidate
    refitted, the discrepancy search where the residual is unexplained, the
    detection limits, the dynamic-model check, report and plots), once,
    against the 5-minute goal.  Quick (CI): a coarse profile grid (30 nodes)
    and one Marquardt iteration's value + forward-mode Jacobian pass, against
    one forward run, so the case cannot rot."""
    import tempfile

    import jax
    import numpy as np

    from diffwear.calibrate import load_dataset
    from diffwear.calibrate.effects import NAMES, EffectValues
    from diffwear.calibrate.fit import Fitter, ModelSettings, Problem
    from diffwear.cli.calibrate import run as calibrate
    from diffwear.io import OutputDir

    data = load_dataset(dataset)
    if repeats > QUICK_REPEATS:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            s = calibrate(data, OutputDir(Path(tmp) / "out"), log=lambda *a, **k: None)
            wall = time.perf_counter() - t0
        check = s["model_check"] or {}
        named = [e["name"] for e in s["effects_identified"]] or ["none"]
        d = s.get("discrepancy") or {}
        found = ", ".join(named) + (f"; discrepancy in {d['variable']}: {d['shape']}"
                                    if d.get("variable") else "")
        return {"dataset": data.name, "run_s": wall,
                "note": f"whole loop: {found}, held-out {s['heldout_rmse_before']:.3g} -> "
                        f"{s['heldout_rmse_after']:.3g} sigma; dynamic check "
                        f"{check.get('wall_time_s', 0.0):.0f} s",
                "effects_identified": named, "discrepancy": d.get("variable"),
                "effect_identified": s["effect_identified"],
                "effect_strength": s["effect_strength"], "effect_shape": s["effect_shape"],
                "heldout_rmse_before": s["heldout_rmse_before"],
                "heldout_rmse_after": s["heldout_rmse_after"],
                "dynamic_check_s": check.get("wall_time_s"),
                "model": s["model"], "goal_s": goal_s}
    problem = Problem.from_dataset(data, ModelSettings(n_theta=30))
    fitter = Fitter(problem)
    layout = fitter.layout(("run_in",))  # the base parameters, a strength and a shape
    z = np.zeros(layout.size)  # the stated values, no effect
    forward = jax.jit(lambda x: problem.residual(x, EffectValues.zero()))
    _, first = timed(forward, z[:problem.n_base])
    _, run_s = timed(forward, z[:problem.n_base])

    def evaluate(z):
        return fitter.linearise(layout.pack(z), layout.tangents)

    _, first_j = timed(evaluate, z)
    _, jac_s = timed(evaluate, z)
    # compile_s / run_s: the value + Jacobian pass (the table's columns)
    return {"dataset": data.name, "points": int(problem.y.size),
            "compile_forward_s": first - run_s, "forward_s": run_s,
            "compile_s": first_j - jac_s, "run_s": jac_s,
            "ratio_gradient_to_forward": jac_s / run_s,
            "parameters": problem.n_base, "effects": len(NAMES),
            "note": "quick: one value + Jacobian pass (30 nodes)"}
