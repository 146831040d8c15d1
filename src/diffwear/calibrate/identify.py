"""Find the effect the base model lacks: score tests, refits, a decision;
and, when no wear effect explains the data, the mechanism parameter that does.

1. Fit the base model (the dataset's fitted parameters, every effect at zero).
2. Score (Lagrange-multiplier) test of each candidate at zero strength, from
   the base fit's residual r and Jacobian (fit points only): with
   g = J_e^T r and the efficient information I = J_e^T J_e - J_e^T J_b
   (J_b^T J_b)^-1 J_b^T J_e, the statistic S_e = g^2 / I is chi-square(1)
   under "no effect"; it is the chi-square drop a first Gauss-Newton step in
   s_e would give, i.e. how much of the residual the effect explains to first
   order.  An effect whose strength is bounded below by zero scores 0 when the
   residual asks for a negative strength.  An effect with a shape is scored at
   `SHAPE_GRID` points of its prior (the shape is not identified at zero
   strength): its statistic is the largest, its p-value Bonferroni-corrected
   for the grid, and its refit starts from that shape.
3. Refit the base parameters together with each of the ``top`` best
   candidates (strength, and shape where it has one).  A candidate qualifies
   when its fit-set chi-square falls by more than the chi-square critical
   value at p = 0.001 for its number of fitted numbers (`LR_CRITICAL`), its
   strength is `STRENGTH_SIGMAS` standard deviations (at the fitted shape)
   from zero on the allowed side, and (with held-out data) its held-out chi-square is lower than the
   base model's.  Among qualifying candidates the penalised criterion
   chi2_fit + chi2_holdout + ln(n_fit) per fitted number (BIC) decides.
4. Goodness of fit: the chosen model must leave fit-point residuals
   consistent with the stated noise, chi2 <= dof + `GOF_SIGMAS` sqrt(2 dof).
   Otherwise nothing in the library explains the data: ``effect_identified``
   is "none" and ``residual_unexplained`` is true (the best partial candidate
   is reported, not adopted).
5. Mechanism suspects: when no effect is identified, every rig parameter the
   dataset neither fits nor excludes (``suspect = false``) is scored the same
   way (its column: the derivative in ln of the parameter).  When the residual
   is unexplained and the best score passes p = 0.001 corrected for the number
   of suspects, that parameter is refitted to say how far it would have to
   move and whether that explains the data ("the force trace asks for a 2x
   longer crank").
"""

from __future__ import annotations

import math
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import SolverError
from .dataset import Dataset
from .effects import EFFECTS, NAMES, SHAPED, EffectValues
from .fit import LOG_STD, FitResult, Fitter, ModelSettings, Problem
from .parameters import RIG_PARAMETERS

# chi-square critical values at p = 0.001 for 1 and 2 fitted numbers
LR_CRITICAL = {1: 10.83, 2: 13.82}
STRENGTH_SIGMAS = 3.0  # |s| / std(s) of an adopted effect
GOF_SIGMAS = 4.0       # chi2 above dof + 4 sqrt(2 dof): residual not noise
DEFAULT_TOP = 3
# An effect is refitted only if the fit points leave degrees of freedom after
# it: with none, any candidate fits exactly and nothing can be told apart.
MIN_DOF_FOR_EFFECT = 2
# Shapes at which a shaped effect is scored: ln(shape / default) in units of
# its prior spread (+-1.5 sigma: a factor 32 either way for a decade prior)
SHAPE_GRID = (-1.5, -0.75, 0.0, 0.75, 1.5)


@dataclass
class Score:
    effect: str
    statistic: float     # S_e (chi-square(1) under "no effect")
    first_step: float    # the Gauss-Newton strength step -g / I
    p_value: float
    log_shape: float = 0.0   # ln(shape / default) where the statistic was largest
    by_kind: dict = field(default_factory=dict)  # share of g per series kind


@dataclass
class Suspect:
    """A rig parameter scored (the best one also refitted) when no wear effect
    explains the data; ``value0``: its stated value (SI)."""

    name: str
    value0: float
    score: Score
    refit: FitResult | None = None

    @property
    def factor(self) -> float:
        """Refitted (else first-step) value over the stated one."""
        if self.refit is not None:
            return self.refit.params[self.name] / self.value0
        return math.exp(float(np.clip(self.score.first_step, -20.0, 20.0)))

    def sentence(self) -> str:
        """"the force trace asks for a 2x longer crank length (...)"."""
        by_kind = self.score.by_kind
        kind = max(by_kind, key=lambda k: by_kind[k], default="data")
        what = {"force": "the force trace asks", "profile": "the wear profiles ask",
                "volume": "the worn volume asks", "max_depth": "the maximum depth asks"
                }.get(kind, f"the {kind} data ask")
        f = self.factor
        words = {"length": ("longer", "shorter"), "mass": ("heavier", "lighter"),
                 "stiffness": ("stiffer", "softer"), "inertia": ("larger", "smaller")}
        known = RIG_PARAMETERS.get(self.name)
        up, down = words.get((known.dimension if known else None) or "", ("larger", "smaller"))
        if abs(f - 1.0) < 0.2:
            how = f"a {100 * abs(f - 1.0):.2g} % {up if f >= 1 else down}"
        else:
            how = f"a {f:.2g}x {up}" if f >= 1 else f"a {1 / f:.2g}x {down}"
        label = known.description if known else self.name
        return (f"{what} for {how} {label} "
                f"({self.name}: {self.value0:.4g} -> {self.value0 * f:.4g} SI)")


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
    suspects: list[Suspect] = field(default_factory=list)
    check: dict | None = None   # the chosen model's fit on the reference (dynamic) model
    notes: dict = field(default_factory=dict)

    def summary(self) -> dict:
        c = self.chosen
        identified = self.effect_identified != "none"
        final = c if identified else self.base
        m = self.problem.model
        out = {
            "dataset": self.dataset.name,
            "model": m.name,
            "effect_identified": self.effect_identified,
            "effect_strength": c.strength if identified else 0.0,
            "effect_strength_std": c.strength_std if identified else 0.0,
            "effect_shape": c.shape if identified else None,
            "effect_shape_interval": list(c.shape_interval) if identified and c.shape_interval
            else None,
            "residual_unexplained": self.residual_unexplained,
            "heldout_rmse_before": self.base.rmse_holdout,
            "heldout_rmse_after": final.rmse_holdout,
            "heldout_rmse_units": "stated 1-sigma measurement noise",
            "fit_rmse_before": self.base.rmse_fit,
            "fit_rmse_after": final.rmse_fit,
            "chi2_fit": final.chi2_fit,
            "parameters": final.params,
            "parameters_std": final.params_std,
            "candidates": [_candidate(s, self.refits.get(s.effect), s.effect in self.qualifying,
                                      self.notes.get("failed_refits", {}).get(s.effect))
                           for s in self.scores],
            "goodness_of_fit": self.gof,
            "suspects": [_suspect(s) for s in self.suspects],
            "suspect": (self.suspects[0].sentence()
                        if self.suspects and self.suspects[0].refit is not None else None),
            "model_check": self.check,
            "model_settings": {"description": m.describe(), "n_theta": m.n_theta},
            "wall_time_s": self.wall_time_s,
        }
        return out


def _candidate(s: Score, refit: FitResult | None, qualifies: bool,
               failure: str | None = None) -> dict:
    out = {"name": s.effect, "score": s.statistic, "p_value": s.p_value,
           "first_step": s.first_step}
    if failure:
        out["refit_failed"] = failure
    shape = EFFECTS[NAMES.index(s.effect)].shape
    if shape is not None:
        out["scored_shape"] = shape.default * math.exp(s.log_shape)
    if refit is not None:
        out.update(refit_strength=refit.strength, refit_strength_std=refit.strength_std,
                   refit_shape=refit.shape, refit_chi2_fit=refit.chi2_fit,
                   refit_heldout_rmse=refit.rmse_holdout, qualifies=qualifies)
    return out


def _suspect(s: Suspect) -> dict:
    out = {"name": s.name, "score": s.score.statistic, "p_value": s.score.p_value,
           "value": s.value0, "factor": s.factor}
    if s.refit is not None:
        gof = _gof(s.refit)
        out.update(refit_value=s.refit.params[s.name], refit_std=s.refit.params_std[s.name],
                   refit_chi2_fit=s.refit.chi2_fit, refit_heldout_rmse=s.refit.rmse_holdout,
                   explains=gof["consistent_with_noise"], sentence=s.sentence())
    return out


def _chi2_sf(x: float) -> float:
    """P(chi-square(1) > x) = erfc(sqrt(x / 2))."""
    return math.erfc(math.sqrt(max(x, 0.0) / 2.0))


def _chi2_isf(p: float) -> float:
    """x with P(chi-square(1) > x) = p (bisection on `_chi2_sf`)."""
    lo, hi = 0.0, 200.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _chi2_sf(mid) > p else (lo, mid)
    return 0.5 * (lo + hi)


def _score(name, j, jb, r, lower, kinds) -> Score:
    """The efficient score test of column ``j`` against the fitted columns ``jb``."""
    g = float(j @ r)
    cross = jb.T @ j
    info = float(j @ j - cross @ np.linalg.solve(jb.T @ jb, cross)) if jb.size else float(j @ j)
    if not np.isfinite(info) or info <= 1e-12 * max(float(j @ j), 1e-300):
        return Score(name, 0.0, 0.0, 1.0)  # not identifiable from these data
    step = -g / info
    stat = g * g / info
    if step < 0 and lower >= 0:  # the residual asks for a forbidden sign
        stat = 0.0
    share = {}
    for kind in np.unique(kinds):
        m = kinds == kind
        share[str(kind)] = abs(float(j[m] @ r[m]))
    return Score(name, stat, step, _chi2_sf(stat), by_kind=share)


def score_tests(fitter: Fitter, base: FitResult, kinds) -> list[Score]:
    p = fitter.problem
    rows = ~p.holdout
    x = np.asarray(base.notes["x"])
    jb, _, _ = fitter.parameter_jacobian(x, names=())
    jb, r = jb[rows], base.residual[rows]
    best: dict[str, Score] = {}
    for g in SHAPE_GRID:
        je = fitter.effect_jacobian(x, LOG_STD * g)[rows]
        for k, eff in enumerate(EFFECTS):
            if not SHAPED[k] and g != 0.0:
                continue
            s = _score(eff.name, je[:, k], jb, r, eff.lower, kinds[rows])
            s.log_shape = float(LOG_STD[k] * g)
            if eff.name not in best or s.statistic > best[eff.name].statistic:
                best[eff.name] = s
    for k, eff in enumerate(EFFECTS):
        if SHAPED[k]:  # the largest of the grid's statistics: Bonferroni
            s = best[eff.name]
            s.p_value = min(1.0, len(SHAPE_GRID) * s.p_value)
    return sorted(best.values(), key=lambda s: -s.statistic)


def score_suspects(fitter: Fitter, base: FitResult, kinds) -> list[Score]:
    """Score tests of the problem's suspects (rig parameters on a log scale)."""
    p = fitter.problem
    rows = ~p.holdout
    jb, ju, _ = fitter.parameter_jacobian(np.asarray(base.notes["x"]), names=p.suspects)
    r = base.residual[rows]
    out = [_score(n, ju[rows, k], jb[rows], r, -math.inf, kinds[rows])
           for k, n in enumerate(p.suspects)]
    return sorted(out, key=lambda s: -s.statistic)


def _gof(fit: FitResult) -> dict:
    """Goodness of fit on the fit points.  (Held-out residuals also carry the
    parameter uncertainty propagated forward, so they are compared before and
    after, not against the noise.)"""
    chi2, dof = fit.chi2_fit, max(fit.dof, 1)
    limit = dof + GOF_SIGMAS * math.sqrt(2 * dof)
    return {"chi2": chi2, "dof": dof, "limit": limit, "consistent_with_noise": chi2 <= limit}


def _criterion(fit: FitResult) -> float:
    return fit.chi2_fit + fit.chi2_holdout + fit.n_effect * math.log(fit.n_fit)


def compile_check(data: Dataset, problem: Problem, settings: ModelSettings):
    """The dynamic model's residual function, compiled ahead (it runs beside
    the fits in a thread: its compilation is a third of the check's cost)."""
    reference = settings.with_model("dynamic").build(data.max_cycles)
    other = problem.with_model(reference)
    x = jax.ShapeDtypeStruct((problem.n_base,), jnp.float64)
    effects = jax.tree.map(lambda a: jax.ShapeDtypeStruct(a.shape, a.dtype),
                           EffectValues.zero())
    return reference, jax.jit(other.residual).lower(x, effects).compile()


def model_check(problem: Problem, fit: FitResult, prepared) -> dict:
    """The chosen fit evaluated (not refitted) on the dynamic model (``prepared``
    by `compile_check`): its chi-square on the fit and held-out points beside
    the fitted model's."""
    t0 = time.perf_counter()
    reference, residual = prepared
    r = np.asarray(residual(jnp.asarray(fit.notes["x"]), fit.effect_values()))
    rows = ~problem.holdout
    ok = bool(np.all(np.isfinite(r)))
    return {"model": reference.name, "description": reference.describe(), "ok": ok,
            "chi2_fit": float(np.sum(r[rows] ** 2)) if ok else None,
            "chi2_holdout": float(np.sum(r[~rows] ** 2)) if ok else None,
            "chi2_fit_model": fit.chi2_fit, "chi2_holdout_model": fit.chi2_holdout,
            "n_fit": int(rows.sum()), "n_holdout": int((~rows).sum()),
            "wall_time_s": time.perf_counter() - t0}


def calibrate(data: Dataset, settings: ModelSettings = ModelSettings(), *,
              top: int = DEFAULT_TOP, check: bool = True, log=print) -> Calibration:
    """The whole loop on one dataset (module notes); ``check``: evaluate the
    chosen fit on the dynamic model too (when the fit ran on another)."""
    t0 = time.perf_counter()
    problem = Problem.from_dataset(data, settings)
    fitter = Fitter(problem)
    check = check and problem.model.name != "dynamic" and data.mechanism is None
    pool = ThreadPoolExecutor(max_workers=1)  # its thread starts on the first submit
    prepared = pool.submit(compile_check, data, problem, settings) if check else None
    speculated: dict = {}
    kinds = np.array([data.series[k].kind for k in problem.series_of_point])
    log(f"{problem.model.describe()}; fitting {', '.join(problem.fit_names)}")
    base = fitter.fit(None)
    log(f"base fit: chi2 {base.chi2_fit:.1f} on {base.n_fit} points, held-out RMSE "
        f"{base.rmse_holdout:.3g} sigma ({base.iterations} steps, {base.wall_time_s:.1f} s)")
    scores = score_tests(fitter, base, kinds)
    log("scores: " + ", ".join(f"{s.effect} {s.statistic:.3g}" for s in scores))
    refits, qualifying, failed = {}, [], {}
    x0 = np.asarray(base.notes["x"])
    too_few = base.n_fit - problem.n_base - 2 < MIN_DOF_FOR_EFFECT
    if too_few:
        log(f"{base.n_fit} fit points for {problem.n_base} parameters: too few to fit an effect "
            "as well; candidates are scored, not refitted")
    for s in ([] if too_few else scores[:top]):
        if s.statistic <= 0.0:
            continue
        eff = EFFECTS[NAMES.index(s.effect)]
        try:
            f = fitter.fit(s.effect, x0=x0, s0=float(np.clip(s.first_step, eff.lower, None)),
                           log_shape0=s.log_shape)
        except SolverError as err:  # this candidate cannot be fitted: it does not qualify
            failed[s.effect] = str(err)
            log(f"refit + {s.effect}: {err}")
            continue
        refits[s.effect] = f
        lr = base.chi2_fit - f.chi2_fit
        spread = f.notes["strength_std_given_shape"]
        z = f.strength / spread if spread > 0 else math.inf
        ok = (lr > LR_CRITICAL[f.n_effect] and abs(z) >= STRENGTH_SIGMAS
              and f.strength >= eff.lower
              and (f.n_holdout == 0 or f.chi2_holdout < base.chi2_holdout))
        f.notes.update(likelihood_ratio=lr, z=z, criterion=_criterion(f))
        if ok:
            qualifying.append(s.effect)
            if prepared is not None and not speculated:
                # the first qualifying refit is usually the one chosen: its
                # dynamic check runs beside the remaining refits
                # (the compiled check is awaited in the pool's thread, not here)
                def check_refit(f: FitResult = f, compiled: Future = prepared) -> dict:
                    return model_check(problem, f, compiled.result())

                speculated[s.effect] = (f, pool.submit(check_refit))
        shape = "" if f.shape is None else f", shape {f.shape:.3g}"
        log(f"refit + {s.effect}: strength {f.strength:.4g} +- {f.strength_std:.2g}{shape}, "
            f"chi2 {f.chi2_fit:.1f}, held-out RMSE {f.rmse_holdout:.3g} sigma"
            f"{' (qualifies)' if ok else ''}")
    best = min((refits[e] for e in qualifying), key=_criterion, default=None)
    chosen = best if best is not None and _criterion(best) < _criterion(base) else base
    gof = _gof(chosen)
    if chosen.effect is not None and gof["consistent_with_noise"]:
        identified, unexplained = chosen.effect, False
    else:
        identified, unexplained = "none", not gof["consistent_with_noise"]
    log(f"identified: {identified}" + (" (the residual stays unexplained)" if unexplained else ""))
    suspects = []
    if identified == "none" and problem.suspects and not too_few:
        ranked = score_suspects(fitter, base, kinds)
        suspects = [Suspect(s.effect, float(problem.base0[s.effect]), s) for s in ranked]
        # named only when something is left to explain, at p = 0.001 over all suspects
        critical = _chi2_isf(0.001 / len(ranked))
        if unexplained and ranked and ranked[0].statistic > critical:
            lead = suspects[0]
            try:
                lead.refit = fitter.fit_suspect(lead.name, x0, lead.score.first_step)
            except SolverError as err:  # a suspect that cannot be fitted is still named
                log(f"refit with {lead.name} free failed: {err}")
            log(f"suspect: {lead.sentence()}")
    final = chosen if identified != "none" else base
    result = Calibration(data, problem, base, scores, refits, qualifying, chosen, identified,
                         unexplained, gof, 0.0, suspects, notes={"failed_refits": failed})
    if prepared is not None:
        ahead = speculated.get(final.effect)
        result.check = (ahead[1].result() if ahead is not None and ahead[0] is final
                        else model_check(problem, final, prepared.result()))
        c = result.check
        log(f"check on the {c['model']} model: chi2 {c['chi2_fit']} on the fit points "
            f"(fitted model {final.chi2_fit:.1f}), held out {c['chi2_holdout']}")
    pool.shutdown()
    result.wall_time_s = time.perf_counter() - t0
    return result
