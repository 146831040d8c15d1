"""Find the effect the base model lacks: score tests, refits, a decision.

1. Fit the base model (the dataset's fitted parameters, every effect at zero).
2. Score (Lagrange-multiplier) test of each candidate at zero strength, from
   the base fit's residual r and Jacobian (fit points only): with
   g = J_e^T r and the efficient information I = J_e^T J_e - J_e^T J_b
   (J_b^T J_b)^-1 J_b^T J_e, the statistic S_e = g^2 / I is chi-square(1)
   under "no effect"; it is the chi-square drop a first Gauss-Newton step in
   s_e would give, i.e. how much of the residual the effect explains to first
   order.  An effect whose strength is bounded below by zero scores 0 when the
   residual asks for a negative strength.  Candidates are ranked by S_e.
3. Refit the base parameters together with each of the ``top`` best
   candidates.  A candidate qualifies when its fit-set chi-square falls by
   more than `LR_CRITICAL` (likelihood ratio, p = 0.001), its strength is
   `STRENGTH_SIGMAS` standard deviations from zero on the allowed side, and
   (with held-out data) its held-out chi-square is lower than the base model's.
   Among qualifying candidates the penalised criterion chi2_fit + chi2_holdout
   + ln(n_fit) per added strength (BIC) decides.
4. Goodness of fit: the chosen model must leave fit-point residuals
   consistent with the stated noise, chi2 <= dof + `GOF_SIGMAS` sqrt(2 dof).
   Otherwise nothing in the library explains the data: ``effect_identified``
   is "none" and ``residual_unexplained`` is true (the best partial candidate
   is reported, not adopted).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .dataset import Dataset
from .effects import EFFECTS, NAMES
from .fit import FitResult, Fitter, ModelSettings, Problem

LR_CRITICAL = 10.83    # chi-square(1) at p = 0.001
STRENGTH_SIGMAS = 3.0  # |s| / std(s) of an adopted effect
GOF_SIGMAS = 4.0       # chi2 above dof + 4 sqrt(2 dof): residual not noise
DEFAULT_TOP = 3
# An effect is refitted only if the fit points leave degrees of freedom after
# it: with none, any candidate fits exactly and nothing can be told apart.
MIN_DOF_FOR_EFFECT = 2


@dataclass
class Score:
    effect: str
    statistic: float     # S_e (chi-square(1) under "no effect")
    first_step: float    # the Gauss-Newton strength step -g / I
    p_value: float


@dataclass
class Calibration:
    dataset: Dataset
    problem: Problem
    base: FitResult
    scores: list[Score]
    refits: dict[str, FitResult]
    qualifying: list[str]
    chosen: FitResult
    effect_identified: str
    residual_unexplained: bool
    gof: dict
    wall_time_s: float
    notes: dict = field(default_factory=dict)

    def summary(self) -> dict:
        c = self.chosen
        identified = self.effect_identified != "none"
        return {
            "dataset": self.dataset.name,
            "effect_identified": self.effect_identified,
            "effect_strength": c.strength if identified else 0.0,
            "effect_strength_std": c.strength_std if identified else 0.0,
            "residual_unexplained": self.residual_unexplained,
            "heldout_rmse_before": self.base.rmse_holdout,
            "heldout_rmse_after": c.rmse_holdout if identified else self.base.rmse_holdout,
            "heldout_rmse_units": "stated 1-sigma measurement noise",
            "fit_rmse_before": self.base.rmse_fit,
            "fit_rmse_after": c.rmse_fit if identified else self.base.rmse_fit,
            "parameters": (c if identified else self.base).params,
            "parameters_std": (c if identified else self.base).params_std,
            "candidates": [
                {"name": s.effect, "score": s.statistic, "p_value": s.p_value,
                 "first_step": s.first_step,
                 **({"refit_strength": self.refits[s.effect].strength,
                     "refit_strength_std": self.refits[s.effect].strength_std,
                     "refit_chi2_fit": self.refits[s.effect].chi2_fit,
                     "refit_heldout_rmse": self.refits[s.effect].rmse_holdout,
                     "qualifies": s.effect in self.qualifying}
                    if s.effect in self.refits else {})}
                for s in self.scores],
            "goodness_of_fit": self.gof,
            "model": {"dynamic_cycles": self.problem.model.dynamic_cycles,
                      "extrapolation": self.problem.model.extrapolation,
                      "n_theta": self.problem.model.n_theta},
            "wall_time_s": self.wall_time_s,
        }


def _chi2_sf(x: float) -> float:
    """P(chi-square(1) > x) = erfc(sqrt(x / 2))."""
    return math.erfc(math.sqrt(max(x, 0.0) / 2.0))


def score_tests(fitter: Fitter, base: FitResult) -> list[Score]:
    p = fitter.problem
    rows = ~p.holdout
    jb = base.notes["jacobian_base"][rows]
    je = base.notes["jacobian_effects"][rows]
    r = base.residual[rows]
    info_b = jb.T @ jb
    out = []
    for k, eff in enumerate(EFFECTS):
        j = je[:, k]
        g = float(j @ r)
        cross = jb.T @ j
        info = float(j @ j - cross @ np.linalg.solve(info_b, cross)) if jb.size else float(j @ j)
        if info <= 1e-12 * max(float(j @ j), 1e-300):
            out.append(Score(eff.name, 0.0, 0.0, 1.0))  # not identifiable from these data
            continue
        step = -g / info
        stat = g * g / info
        if step < 0 and eff.lower >= 0:  # the residual asks for a forbidden sign
            stat = 0.0
        out.append(Score(eff.name, stat, step, _chi2_sf(stat)))
    return sorted(out, key=lambda s: -s.statistic)


def _gof(fit: FitResult) -> dict:
    """Goodness of fit on the fit points.  (Held-out residuals also carry the
    parameter uncertainty propagated forward, so they are compared before and
    after, not against the noise.)"""
    chi2, dof = fit.chi2_fit, max(fit.dof, 1)
    limit = dof + GOF_SIGMAS * math.sqrt(2 * dof)
    return {"chi2": chi2, "dof": dof, "limit": limit, "consistent_with_noise": chi2 <= limit}


def _criterion(fit: FitResult) -> float:
    return fit.chi2_fit + fit.chi2_holdout + (math.log(fit.n_fit) if fit.effect else 0.0)


def calibrate(data: Dataset, settings: ModelSettings = ModelSettings(), *,
              top: int = DEFAULT_TOP, log=print) -> Calibration:
    """The whole loop on one dataset (module notes)."""
    t0 = time.perf_counter()
    problem = Problem.from_dataset(data, settings)
    fitter = Fitter(problem)
    m = problem.model
    log(f"model: {m.dynamic_cycles} dynamic cycles of A = {m.extrapolation:g}, "
        f"{m.n_theta} profile nodes; fitting {', '.join(problem.fit_names)}")
    base = fitter.fit(None)
    log(f"base fit: chi2 {base.chi2_fit:.1f} on {base.n_fit} points, held-out RMSE "
        f"{base.rmse_holdout:.3g} sigma ({base.iterations} steps, {base.wall_time_s:.0f} s)")
    scores = score_tests(fitter, base)
    log("scores: " + ", ".join(f"{s.effect} {s.statistic:.3g}" for s in scores))
    refits, qualifying = {}, []
    x0 = np.asarray(base.notes["x"])
    too_few = base.n_fit - problem.n_base - 1 < MIN_DOF_FOR_EFFECT
    if too_few:
        log(f"{base.n_fit} fit points for {problem.n_base} parameters: too few to fit an effect "
            "strength as well; candidates are scored, not refitted")
    for s in ([] if too_few else scores[:top]):
        if s.statistic <= 0.0:
            continue
        eff = EFFECTS[NAMES.index(s.effect)]
        f = fitter.fit(s.effect, x0=x0, s0=float(np.clip(s.first_step, eff.lower, None)))
        refits[s.effect] = f
        lr = base.chi2_fit - f.chi2_fit
        z = f.strength / f.strength_std if f.strength_std > 0 else math.inf
        ok = (lr > LR_CRITICAL and abs(z) >= STRENGTH_SIGMAS and f.strength >= eff.lower
              and (f.n_holdout == 0 or f.chi2_holdout < base.chi2_holdout))
        f.notes.update(likelihood_ratio=lr, z=z, criterion=_criterion(f))
        if ok:
            qualifying.append(s.effect)
        log(f"refit + {s.effect}: strength {f.strength:.4g} +- {f.strength_std:.2g}, chi2 "
            f"{f.chi2_fit:.1f}, held-out RMSE {f.rmse_holdout:.3g} sigma"
            f"{' (qualifies)' if ok else ''}")
    best = min((refits[e] for e in qualifying), key=_criterion, default=None)
    chosen = best if best is not None and _criterion(best) < _criterion(base) else base
    gof = _gof(chosen)
    if chosen.effect is not None and gof["consistent_with_noise"]:
        identified, unexplained = chosen.effect, False
    else:
        identified, unexplained = "none", not gof["consistent_with_noise"]
    log(f"identified: {identified}" + (" (the residual stays unexplained)" if unexplained else ""))
    return Calibration(data, problem, base, scores, refits, qualifying, chosen, identified,
                       unexplained, gof, time.perf_counter() - t0)
