"""Do the calibration's 90 % predictive bands cover 90 % of what they claim?

Synthetic campaigns from the project's own generator (`synthetic`, on the
quasi-static model: the model the loop fits, so the bands are tested, not
the model), each with its own truth (k and the spring's free length off
their stated values, a run-in or a pressure exponent of random strength, or
none) and its own noise; each is fitted in the form of its truth, its
posterior drawn (`posterior.laplace`, the Laplace draws checked on the exact
model) and the share of its held-out points inside their 90 % band counted.
Pooled over the campaigns, that share should lie in `GOAL`.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from .effects import EffectValues
from .fit import Fitter, ModelSettings, Problem
from .model import rig_defaults
from .posterior import BAND, laplace
from .quasi_static import QuasiStaticRigHistory
from .synthetic import Plan, synthesize

# A 2,000-cycle campaign (the shipped synthetic plan) on a 48-node profile
# grid: profiles at 500/1000/1500/2000 cycles, weighings every 250, the force
# over the first cycle; from 1,500 cycles held out
PLAN = Plan(profile_angles=48, force_cycles=(0.0,))
SETTINGS = ModelSettings(model=QuasiStaticRigHistory, n_theta=48, steps=20)
# the pooled held-out share a 90 % band should reach: 0.90 within the
# scatter of 20 campaigns of ~100 correlated held-out points each
GOAL = (0.85, 0.95)
FIRST_SEED = 1000


def truth(rng: np.random.Generator) -> tuple[dict, tuple, EffectValues]:
    """A campaign's truth: rig parameters, the effects to fit, their values."""
    d = rig_defaults()
    params = {"k": d["k"] * float(rng.uniform(0.8, 1.4)),
              "free_length": d["free_length"] + float(rng.uniform(-0.01, 0.02))}
    kind = rng.integers(3)
    if kind == 0:
        return params, (), EffectValues.zero()
    if kind == 1:
        s = float(rng.uniform(0.5, 2.5))
        return params, ("run_in",), EffectValues.of(run_in=s,
                                                    run_in_cycles=float(rng.uniform(150, 600)))
    return params, ("pressure_exponent",), EffectValues.of(
        pressure_exponent=float(rng.uniform(0.3, 1.2)))


def one(seed: int, folder: Path) -> dict:
    """One synthetic campaign (written under ``folder``) fitted in the form of
    its truth, and its held-out points counted inside their band."""
    rng = np.random.default_rng(seed)
    params, effects, values = truth(rng)
    # the dataset as written and loaded back (`write_dataset`)
    data = synthesize(folder / f"c{seed}", name=f"coverage-{seed}", effects=values, seed=seed,
                      plan=PLAN, settings=SETTINGS, truth=params)
    problem = Problem.from_dataset(data, SETTINGS)
    fitter = Fitter(problem)
    base = fitter.fit(None)
    fit = fitter.fit(effects, start=base, s0={e: 1.0 for e in effects}) if effects else base
    post = laplace(fitter, fit)
    held = problem.holdout
    lo, hi = post.predictive_band(problem.sigma, problem.y)
    inside = (problem.y >= lo) & (problem.y <= hi)
    return {"seed": seed, "effects": list(effects), "held_out_points": int(held.sum()),
            "inside": int(inside[held].sum()), "coverage": float(np.mean(inside[held])),
            "fit_coverage": float(np.mean(inside[~held])),
            "pareto_k": post.diagnostics["pareto_k"], "chi2_fit": fit.chi2_fit,
            "n_fit": fit.n_fit}


def run(campaigns: int = 20, first_seed: int = FIRST_SEED, log=print) -> dict:
    """The coverage over ``campaigns`` synthetic campaigns (module notes):
    pooled, per campaign and each campaign's row."""
    t0 = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(campaigns):
            row = one(first_seed + k, Path(tmp))
            rows.append(row)
            log(f"campaign {k + 1}/{campaigns}: {row['effects'] or 'no effect'}, "
                f"held-out coverage {row['coverage']:.3f} (Pareto k {row['pareto_k']:.2f})")
    inside = sum(r["inside"] for r in rows)
    points = sum(r["held_out_points"] for r in rows)
    per = np.array([r["coverage"] for r in rows])
    return {"campaigns": campaigns, "band": BAND, "pooled_heldout_coverage": inside / points,
            "median_campaign_coverage": float(np.median(per)),
            "campaign_coverage_5_95": [float(np.quantile(per, 0.05)),
                                       float(np.quantile(per, 0.95))],
            "goal": list(GOAL), "wall_s": time.perf_counter() - t0, "rows": rows}


__all__ = ["run", "one", "truth", "GOAL", "PLAN", "SETTINGS"]
