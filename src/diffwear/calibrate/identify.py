"""Find the effects the base model lacks: score tests, forward selection with
identifiability, ambiguity and detection limits; a learned discrepancy when
the library has nothing; and the mechanism parameter that explains the data
when no wear effect does.

1. Fit the base model (the dataset's fitted parameters, every effect at zero).
2. Forward selection (`select`): at each stage every effect not yet in the
   model is scored at the current model (`scores`) and **every** candidate
   with a positive score is refitted on top of it (a failed refit is
   retried from other starts and, if it still fails, named with its reason).
   Each refit is judged in its identified form (`selection`): a shape the
   data do not determine is not counted, and what is reported (the
   strength, or the extra worn volume of the identified form) must stand
   `STRENGTH_SIGMAS` from zero at its reported uncertainty.  The best
   qualifying candidate by the penalised criterion joins the model, unless
   the next is within `AMBIGUITY` of it (then the answer is "A or B", with
   the measurement that would separate them); the effects already in the
   model are then re-judged in the joint fit and dropped if they no longer
   qualify.  The loop stops when nothing qualifies.
3. Goodness of fit: the chosen model must leave fit-point residuals
   consistent with the stated noise, chi2 <= dof + `GOF_SIGMAS` sqrt(2 dof);
   otherwise ``residual_unexplained`` is true.
4. Mechanism suspects: when no effect is identified, every rig parameter the
   dataset neither fits nor excludes (``suspect = false``) is scored; when the
   residual is unexplained and the best score passes p = 0.001 corrected for
   the number of suspects, it is refitted ("the force trace asks for a 2x
   longer crank").
5. Discrepancy (`learned`): when the residual is still unexplained (no
   suspect explains it), k (1 + delta(x)) is fitted over each variable; the
   one that cuts the held-out error is named with delta's shape in words.
6. Detection limits: at the final model, the smallest strength of each
   effect not named that these data would have detected (`scores`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, SolverError
from . import learned
from .dataset import Dataset
from .discrepancy import VARIABLES
from .effects import EFFECTS, NAMES, log_shape
from .fit import SCALES, FitResult, Fitter, ModelSettings, Problem
from .parameters import RIG_PARAMETERS
from .plausibility import check_depths, unit_slips
from .reference import DynamicCheck
from .scores import (
    SHAPE_GRID,
    Score,
    chi2_isf,
    detection_limits,
    score_suspects,
    score_tests,
)
from .selection import (
    AMBIGUITY,
    LR_CRITICAL,
    STRENGTH_SIGMAS,
    Assessment,
    assess,
    criterion,
    determined_numbers,
    separating_measurement,
)

GOF_SIGMAS = 4.0       # chi2 above dof + 4 sqrt(2 dof): residual not noise
# An effect is refitted only if the fit points leave degrees of freedom after
# it: with none, any candidate fits exactly and nothing can be told apart.
MIN_DOF_FOR_EFFECT = 2
MAX_EFFECTS = 3        # effects adopted at most (forward-selection stages)
# Forward-selection paths: one from each of the best few qualifying single
# effects (a greedy path from the single best can be trapped by an effect
# that mimics a pair of others), each explaining at least PATH_SHARE of the
# criterion drop the best single effect gives
PATHS = 3
PATH_SHARE = 0.9
# A refit's first start: the score test's Gauss-Newton step, at most this
# many of the effect's scales (the step is linear; the model is not)
FIRST_STEP_SCALES = 5.0
DEFAULT_TOP = 3        # accepted for compatibility; every candidate is refitted

__all__ = ["AMBIGUITY", "GOF_SIGMAS", "LR_CRITICAL", "SHAPE_GRID", "STRENGTH_SIGMAS",
           "Calibration", "Score", "Suspect", "calibrate", "score_tests"]


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
            f = self.refit.params[self.name] / self.value0
            # a refit that ran off to a vanishing or unbounded value is stated
            # at the bounds of the words (1e-6..1e6), not divided by zero
            return float(np.clip(f, 1e-6, 1e6)) if math.isfinite(f) else 1e6
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



def _suspect(s: Suspect) -> dict:
    out = {"name": s.name, "score": s.score.statistic, "p_value": s.score.p_value,
           "value": s.value0, "factor": s.factor}
    if s.refit is not None:
        gof = _gof(s.refit)
        out.update(refit_value=s.refit.params[s.name], refit_std=s.refit.params_std[s.name],
                   refit_chi2_fit=s.refit.chi2_fit, refit_heldout_rmse=s.refit.rmse_holdout,
                   explains=gof["consistent_with_noise"], sentence=s.sentence())
    return out



def _gof(fit: FitResult) -> dict:
    """Goodness of fit on the fit points.  (Held-out residuals also carry the
    parameter uncertainty propagated forward, so they are compared before and
    after, not against the noise.)"""
    chi2, dof = fit.chi2_fit, max(fit.dof, 1)
    limit = dof + GOF_SIGMAS * math.sqrt(2 * dof)
    return {"chi2": chi2, "dof": dof, "limit": limit, "consistent_with_noise": chi2 <= limit}



class _DynamicChi2:
    """fit -> the dynamic model's fit-point chi-square at the fit's numbers;
    `submit` queues an evaluation that may be needed later."""

    def __init__(self, problem: Problem, check: DynamicCheck):
        self.rows, self.check = ~problem.holdout, check

    def __call__(self, fit: FitResult) -> float:
        r = self.check.residual(fit)
        return float(np.sum(r[self.rows] ** 2)) if np.all(np.isfinite(r)) else math.inf

    def submit(self, fit: FitResult) -> None:
        self.check.submit(fit)


def model_check(problem: Problem, fit: FitResult, check: DynamicCheck) -> dict:
    """The chosen fit evaluated (not refitted) on the dynamic model: its
    chi-square on the fit and held-out points beside the fitted model's."""
    t0 = time.perf_counter()
    r = check.residual(fit)
    rows = ~problem.holdout
    ok = bool(np.all(np.isfinite(r)))
    chi2 = float(np.sum(r[rows] ** 2)) if ok else math.inf
    # the fit carries over when the reference model leaves noise-sized
    # residuals too (the goodness-of-fit limit of the fitted model's points)
    dof = max(fit.dof, 1)
    carries = chi2 <= dof + GOF_SIGMAS * math.sqrt(2 * dof) or chi2 <= 1.5 * fit.chi2_fit
    return {"model": check.name, "description": check.describe(), "ok": ok,
            "carries_over": bool(ok and carries),
            "chi2_fit": chi2 if ok else None,
            "chi2_holdout": float(np.sum(r[~rows] ** 2)) if ok else None,
            "chi2_fit_model": fit.chi2_fit, "chi2_holdout_model": fit.chi2_holdout,
            "n_fit": int(rows.sum()), "n_holdout": int((~rows).sum()),
            "wall_time_s": time.perf_counter() - t0,
            "waited_s": check.busy_s}


@dataclass
class Stage:
    """One forward-selection stage: the scores at the model so far, every
    candidate refitted on top of it, and what was decided."""

    scores: list
    assessed: dict                     # effect -> Assessment
    failed: dict                       # effect -> why its refit failed
    added: str | None = None
    dropped: list = field(default_factory=list)
    ambiguous: tuple | None = None     # (Path, Path): two equally good models


@dataclass
class Selection:
    model: FitResult                   # the chosen model (base + the adopted effects)
    adopted: list                      # Assessment of each adopted effect, in the joint fit
    stages: list
    ambiguous: tuple | None = None     # (Path, Path)
    separation: dict | None = None


def _starts(score: Score, effect: str):
    """Starting (strength, ln shape) pairs of a refit: the score's first step
    (at most `FIRST_STEP_SCALES` of the effect's scale), a tenth of the scale
    in its direction, then the scale at the default shape and at the shape
    grid's ends."""
    k = NAMES.index(effect)
    eff, scale = EFFECTS[k], float(SCALES[k])
    sign = 1.0 if score.first_step >= 0 or eff.lower >= 0 else -1.0
    first = float(np.clip(score.first_step, max(eff.lower, -FIRST_STEP_SCALES * scale),
                          FIRST_STEP_SCALES * scale))
    out = [(first, score.log_shape), (0.1 * sign * scale, score.log_shape), (scale, 0.0)]
    if eff.shape is not None:
        out += [(scale, eff.shape.log_std * g) for g in (SHAPE_GRID[0], SHAPE_GRID[-1])]
    return out


def refit(fitter: Fitter, current: FitResult, effect: str, score: Score, log):
    """``current`` + ``effect`` from the starts of `_starts`, in turn until a
    fit ends no worse than ``current`` (a start far down a non-linear
    direction can end in a poorer minimum); (the best fit, None) or (None,
    the reasons every start failed)."""
    key = (frozenset((*current.effects, effect)), current.discrepancy)
    cache = fitter.fits
    if key in cache:  # the same model reached on another path
        return cache[key], None
    errors, best = [], None
    t0 = time.perf_counter()
    for tried, (s0, g0) in enumerate(_starts(score, effect), 1):
        strengths = {**current.strengths, effect: s0}
        shapes = {e: log_shape(e, v) for e, v in current.shapes.items()}
        shapes[effect] = g0
        try:
            f = fitter.fit((*current.effects, effect), x0=current.notes["x"],
                           s0=strengths, log_shape0=shapes,
                           discrepancy=current.discrepancy)
        except SolverError as err:
            errors.append(str(err))
            continue
        if best is None or f.chi2_fit < best.chi2_fit:
            best = f
        if f.chi2_fit <= current.chi2_fit + 1e-6 * current.chi2_fit:
            break
    if best is not None:
        best.notes.update(starts=tried, refit_s=time.perf_counter() - t0)
        cache[key] = best
        return best, None
    reason = "; ".join(dict.fromkeys(errors))
    log(f"refit + {effect} failed from {len(errors)} starts: {reason}")
    return None, reason


def _judge_members(fitter, model: FitResult, inspections, log, always: bool = False):
    """Each effect of ``model`` judged in the joint fit against the model
    without it (its discrepancy kept); returns (assessments, the weakest
    that fails or None).  A single effect is judged only when ``always``."""
    out: dict = {}
    weakest = None
    if len(model.effects) == 1 and not always:
        return out, None
    for e in model.effects:
        rest = tuple(x for x in model.effects if x != e)
        key = (frozenset(rest), model.discrepancy)
        cache = fitter.fits
        without = cache.get(key)
        if without is None:
            try:
                without = cache[key] = fitter.fit(rest, start=model,
                                                  discrepancy=model.discrepancy)
            except SolverError as err:
                log(f"refit without {e} failed: {err}")
                continue
        a = assess(fitter, e, model, without, inspections)
        out[e] = a
        # the weakest failing member: the one whose removal leaves the best model
        if not a.qualifies and (weakest is None
                                or criterion(without) < criterion(weakest[1])):
            weakest = (e, without)
    return out, weakest


def prune(fitter: Fitter, model: FitResult, inspections, log, always: bool = False):
    """Drop the effects of ``model`` that no longer qualify beside the others
    (and its discrepancy), weakest first; (model, {effect: Assessment}, dropped)."""
    judged, weakest = _judge_members(fitter, model, inspections, log, always)
    dropped = []
    while weakest is not None:
        e, model = weakest
        dropped.append(e)
        judged.pop(e, None)
        log(f"dropped: {e} (no longer qualifies beside the rest of the model)")
        judged, weakest = _judge_members(fitter, model, inspections, log, always)
    return model, judged, dropped


def _stage(fitter: Fitter, current: FitResult, kinds, inspections, log,
           exclude=()) -> Stage:
    """Score every effect not in ``current`` (nor ``exclude``) and refit each
    with a positive score on top of it (the scores kept in ``current``'s notes:
    a path grown again reaches the same fits)."""
    key = ("scores", tuple(sorted(exclude)))
    if key not in current.notes:
        current.notes[key] = score_tests(fitter, current, kinds, exclude)
    scores = current.notes[key]
    log(("scores" if not current.effects else f"scores beside {' + '.join(current.effects)}")
        + ": " + ", ".join(f"{s.effect} {s.statistic:.3g}" for s in scores))
    stage = Stage(scores, {}, {})
    todo = [s for s in scores if s.statistic > 0.0]
    done = [(s, refit(fitter, current, s.effect, s, log)) for s in todo]
    for s, (f, failure) in done:
        if f is None:
            stage.failed[s.effect] = failure
            continue
        a = assess(fitter, s.effect, f, current, inspections)
        stage.assessed[s.effect] = a
        log(f"refit + {s.effect}: {_words(a)}")
    return stage


@dataclass
class Path:
    """One forward-selection path: the model it ends on and its effects'
    assessments in that model."""

    model: FitResult
    adopted: dict
    stages: list

    @property
    def criterion(self) -> float:
        return criterion(self.model)

    @property
    def numbers(self) -> float:
        return determined_numbers(self.model)

    @property
    def name(self) -> str:
        return " + ".join(self.model.effects) or "none"


def _improving(stage: Stage, current: FitResult) -> list:
    """The stage's qualifying candidates that improve on ``current`` by the
    criterion, best first."""
    return sorted((a for a in stage.assessed.values()
                   if a.qualifies and a.criterion < criterion(current)),
                  key=lambda a: a.criterion)


def _grow(fitter: Fitter, first: Assessment, kinds, inspections, log,
          reference=None, foresee=None) -> Path:
    """Greedy forward selection from the one-effect model ``first``: the best
    qualifying addition by the criterion at each stage, then the effects
    already in the model re-judged beside it; an effect dropped is not
    offered again on this path.  ``reference(fit) -> chi2`` (the dynamic
    model's fit-point chi-square, evaluated, not refitted): an addition must
    lower it too, else it stands for the fitted model's own error.
    ``foresee(fit)``: told the fits that check would evaluate (unchecked)."""
    current = first.fit
    adopted = {first.effect: first}
    stages: list = []
    excluded: set = set()
    while len(current.effects) < MAX_EFFECTS:
        stage = _stage(fitter, current, kinds, inspections, log, tuple(excluded))
        stages.append(stage)
        ranked = _improving(stage, current)
        if ranked and foresee is not None:
            foresee(current)
            foresee(ranked[0].fit)
        if ranked and reference is not None:
            before = reference(current)
            for a in ranked:
                after = reference(a.fit)
                if not after < before:
                    a.qualifies = False
                    a.reasons.append(f"the dynamic model's chi2 rises ({before:.1f} -> "
                                     f"{after:.1f}): the fitted model's own error")
                    log(f"+ {a.effect} beside {' + '.join(current.effects)}: the dynamic "
                        f"model's chi2 rises {before:.1f} -> {after:.1f}; not adopted")
                else:
                    log(f"+ {a.effect} beside {' + '.join(current.effects)}: the dynamic "
                        f"model's chi2 falls {before:.1f} -> {after:.1f}")
                    break
            ranked = [a for a in ranked if a.qualifies]
        if not ranked:
            break
        best = ranked[0]
        stage.added = best.effect
        log(f"adopted beside {' + '.join(current.effects)}: {best.effect}")
        current, judged, stage.dropped = prune(fitter, best.fit, inspections, log)
        adopted[best.effect] = best
        for e in stage.dropped:
            adopted.pop(e, None)
            excluded.add(e)
        adopted.update(judged)
        if best.effect in stage.dropped:
            break
    return Path(current, {e: adopted[e] for e in current.effects if e in adopted}, stages)


@dataclass
class _Grown:
    path: Path
    seen: set          # its log lines
    checked: bool      # grown with the dynamic model's check


def select(fitter: Fitter, base: FitResult, kinds, inspections, data, log,
           reference=None) -> Selection:
    """Forward selection along `PATHS` paths (module notes): each starts from
    one of the best qualifying single effects and grows greedily; the paths'
    final models are compared by the criterion, within Occam's window."""
    stage1 = _stage(fitter, base, kinds, inspections, log)
    ranked = _improving(stage1, base)
    if not ranked:
        return Selection(base, [], [stage1])
    # a path starts from a single effect that explains most of what the best
    # one explains (a far poorer start cannot be rescued by one more effect)
    gain = criterion(base) - ranked[0].criterion
    starts = [a for a in ranked[:PATHS]
              if a.criterion - ranked[0].criterion <= (1.0 - PATH_SHARE) * gain]
    # Each path grown first without the dynamic model's check (one dynamic
    # evaluation costs as much as several refits; those a check would need
    # are queued to run beside the fits); then the best path not yet checked
    # is grown again with it (its refits reused, its log lines not repeated),
    # until no unchecked path can enter the best checked one's window: the
    # check only holds additions back.
    foresee = getattr(reference, "submit", None)
    grown = []
    for a in starts:
        seen: set = set()

        def first_pass(line, seen=seen):
            seen.add(line)
            log(line)

        grown.append(_Grown(_grow(fitter, a, kinds, inspections, first_pass,
                                  foresee=foresee), seen, reference is None))
    while True:
        unchecked = [g for g in grown if not g.checked]
        checked = [g.path.criterion for g in grown if g.checked]
        if not unchecked or (checked and min(g.path.criterion for g in unchecked)
                             >= min(checked) + AMBIGUITY):
            break
        g = min(unchecked, key=lambda g: g.path.criterion)
        log(f"path {g.path.name}: checked on the dynamic model")
        g.path = _grow(fitter, starts[grown.index(g)], kinds, inspections,
                       lambda line, seen=g.seen: None if line in seen else log(line), reference)
        g.checked = True
    paths: dict[tuple, Path] = {}
    trailing = []
    for g in grown:
        if g.checked:
            paths.setdefault(tuple(sorted(g.path.model.effects)), g.path)
        else:
            trailing.append(g.path)
            log(f"path {g.path.name}: not checked on the dynamic model (criterion "
                f"{g.path.criterion:.1f}, {AMBIGUITY:g} or more above the best checked path)")
    order = sorted(paths.values(), key=lambda p: p.criterion)
    window = [p for p in order if p.criterion - order[0].criterion < AMBIGUITY]
    simplest = min(p.numbers for p in window)
    window = [p for p in window if p.numbers == simplest]  # Occam's window
    best = window[0]
    stage1.added = best.model.effects[0] if best.model.effects else None
    stages = [stage1, *best.stages]
    if len(window) > 1:
        other = window[1]
        sep = separating_measurement(fitter, best.model, other.model, data)
        log(f"{best.name} or {other.name}: these data cannot tell them apart (criteria "
            f"{best.criterion:.1f} and {other.criterion:.1f}); {sep['sentence']}")
        stage1.ambiguous = (best, other)
        return Selection(base, [], stages, (best, other), sep)
    others = sorted((p for p in (*order, *trailing) if p is not best), key=lambda p: p.criterion)
    log(f"selected: {best.name} (criterion {best.criterion:.1f}; other paths: "
        + (", ".join(f"{p.name} {p.criterion:.1f}" for p in others) or "none") + ")")
    return Selection(best.model, list(best.adopted.values()), stages)


def _words(a: Assessment) -> str:
    f = a.fit
    shape = "" if f.shapes.get(a.effect) is None else f", shape {f.shapes[a.effect]:.3g}" + (
        "" if a.shape_determined else " (not determined)")
    form = f"; {a.form.sentence(a.effect)}" if a.form is not None else ""
    return (f"strength {f.strengths[a.effect]:.4g} +- {f.strengths_std[a.effect]:.2g}{shape}, "
            f"chi2 {f.chi2_fit:.1f}, held-out RMSE {f.rmse_holdout:.3g} sigma{form}"
            + (" (qualifies)" if a.qualifies else f" ({'; '.join(a.reasons)})")
            + f" [{f.notes.get('starts', 1)} start(s), {f.iterations} steps, "
              f"{f.notes.get('refit_s', f.wall_time_s):.1f} s]")


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
    selection: Selection | None = None
    discrepancy: learned.Search | None = None
    limits: dict = field(default_factory=dict)
    final: FitResult | None = None   # the adopted effects (+ the named discrepancy)
    adopted: list = field(default_factory=list)   # Assessment of each named effect
    partial: list = field(default_factory=list)   # adopted, but leaving the residual

    def summary(self) -> dict:
        final = self.final or self.chosen
        m = self.problem.model
        sel = self.selection
        effects = [a.entry() for a in self.adopted]
        if sel is not None and sel.ambiguous is not None:
            a, b = sel.ambiguous
            sentence = f"{a.name} or {b.name}: these data cannot tell them apart"
            if sel.separation:
                sentence += "; " + sel.separation["sentence"]
            effects.append({
                "name": f"{a.name} or {b.name}", "ambiguous": True,
                "alternatives": [{"name": p.name, "criterion": p.criterion,
                                  "effects": [x.entry() for x in p.adopted.values()]}
                                 for p in (a, b)],
                "separating_measurement": sel.separation, "sentence": sentence})
        first = effects[0] if effects else None
        out = {
            "dataset": self.dataset.name,
            "model": m.name,
            "effect_identified": self.effect_identified,
            "effects_identified": effects,
            "effects_partial": [a.entry() for a in self.partial],
            "effect_strength": first["strength"] if first and not first.get("ambiguous")
            else 0.0,
            "effect_strength_std": first["strength_std"] if first and not first.get("ambiguous")
            else 0.0,
            "effect_shape": first.get("shape") if first else None,
            "effect_shape_interval": first.get("shape_interval") if first else None,
            "residual_unexplained": self.residual_unexplained,
            "unit_warnings": self.notes.get("unit_warnings", []),
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
            "stages": [_stage_summary(st) for st in (sel.stages if sel else [])],
            "detection_limits": self.limits,
            "discrepancy": _discrepancy(self),
            "goodness_of_fit": self.gof,
            "suspects": [_suspect(s) for s in self.suspects],
            "suspect": (self.suspects[0].sentence()
                        if self.suspects and self.suspects[0].refit is not None else None),
            "model_check": self.check,
            "model_settings": {"description": m.describe(), "n_theta": m.n_theta},
            "wall_time_s": self.wall_time_s,
        }
        return out


def _stage_summary(st: Stage) -> dict:
    return {"added": st.added, "dropped": st.dropped,
            "ambiguous": [p.name for p in st.ambiguous] if st.ambiguous else None,
            "candidates": {e: {"criterion": a.criterion, "qualifies": a.qualifies,
                               "reasons": a.reasons, "z": a.z,
                               "likelihood_ratio": a.likelihood_ratio}
                           for e, a in st.assessed.items()},
            "failed": st.failed}


def _discrepancy(c: Calibration) -> dict | None:
    d = c.discrepancy
    if d is None:
        return None
    trials = {t.variable: ({"failed": t.failure} if t.fit is None else
                           {"heldout_rmse": t.fit.rmse_holdout, "chi2_fit": t.fit.chi2_fit,
                            "criterion": t.criterion, "cuts_heldout_error": t.cuts})
              for t in d.trials}
    before = d.reference.rmse_holdout
    if d.chosen is None:
        tried = [t.variable for t in d.trials]
        return {"variable": None, "heldout_rmse_before": before, "heldout_rmse_after": before,
                "tried": trials, "skipped": d.skipped,
                "shape": "unexplained; no discrepancy in " + _or_list(tried)
                         + " cuts the held-out error"}
    f = d.chosen.model
    out = learned.describe(d.chosen.variable, f.discrepancy_coefficients, f.discrepancy_cov,
                           c.dataset)
    out.update(heldout_rmse_before=before, heldout_rmse_after=f.rmse_holdout,
               effective_coefficients=f.notes.get("discrepancy_edf"), tried=trials,
               skipped=d.skipped)
    return out


def _or_list(items) -> str:
    words = [i.replace("_", " ") for i in items]
    if len(words) <= 1:
        return "".join(words) or "any variable"
    return ", ".join(words[:-1]) + " or " + words[-1]


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
        e = s.effect
        out.update(refit_strength=refit.strengths.get(e, refit.strength),
                   refit_strength_std=refit.strengths_std.get(e, refit.strength_std),
                   refit_shape=refit.shapes.get(e), refit_chi2_fit=refit.chi2_fit,
                   refit_heldout_rmse=refit.rmse_holdout, qualifies=qualifies)
    return out


def _inspections(data: Dataset, problem: Problem) -> list:
    """Cycle counts of the fitted wear measurements (profiles, volumes, depths)."""
    out: set = set()
    for s in data.series:
        if s.kind == "force":
            continue
        counts = np.broadcast_to(np.asarray(s.cycle_counts, float), s.holdout.shape)
        out.update(float(c) for c in np.unique(counts[~s.holdout]))
    return sorted(c for c in out if c > 0)


def require_fit_points(data: Dataset, n_fitted: int | None = None) -> None:
    """Refuse (InputError) a dataset with no more fit points than fitted
    parameters: nothing can be fitted from it."""
    n = sum(int(np.sum(~np.asarray(s.holdout, bool))) for s in data.series)
    k = len(data.fit_names) if n_fitted is None else n_fitted
    if n <= k:
        raise InputError(
            f"{data.path}: {n} fit point(s) for {k} fitted parameter(s) "
            f"({', '.join(data.fit_names)}): too few to fit anything; add measurements "
            "(or measurements before holdout_from_cycles) or fit fewer parameters")


def discrepancy_variables(data: Dataset, spec: str) -> tuple:
    """The ``--discrepancy`` option: 'all' (every variable the data can show),
    'none', or comma-separated names, each checked against the data."""
    text = str(spec).strip().lower()
    if text == "all":
        return VARIABLES
    if text == "none":
        return ()
    names = tuple(v.strip() for v in text.split(",") if v.strip())
    if not names:
        raise InputError(f"--discrepancy {spec!r}: allowed 'all', 'none' or names from "
                         f"{', '.join(VARIABLES)}")
    for v in names:
        if v not in VARIABLES:
            raise InputError(f"--discrepancy {v!r}: unknown variable; allowed "
                             f"{', '.join(VARIABLES)}, 'all' or 'none'")
    learned.check_variables(data, names)
    return names


def calibrate(data: Dataset, settings: ModelSettings = ModelSettings(), *,
              top: int = DEFAULT_TOP, check: bool = True, discrepancy=VARIABLES,
              log=print) -> Calibration:
    """The whole loop on one dataset (module notes).  ``check``: evaluate the
    chosen fit on the dynamic model too (when the fit ran on another);
    ``discrepancy``: the variables a learned discrepancy is searched over
    (empty: none).  ``top`` is kept for compatibility: every candidate is
    refitted."""
    del top
    t0 = time.perf_counter()
    discrepancy = tuple(discrepancy)
    problem = Problem.from_dataset(data, settings)
    if discrepancy != VARIABLES:  # asked for by name: refuse what the data cannot show
        learned.check_variables(data, discrepancy)
    require_fit_points(data, problem.n_base)
    wall = problem.base0.get("wall")
    check_depths(data, None if wall is None else float(wall))
    fitter = Fitter(problem)
    check = check and problem.model.checked_on_dynamic
    # the dynamic model, compiled and evaluated beside the fits (`reference`)
    dynamic = DynamicCheck(data, settings) if check else None
    try:
        result = _loop(data, problem, fitter, discrepancy, dynamic, log)
    finally:
        if dynamic is not None:
            dynamic.close()
    result.wall_time_s = time.perf_counter() - t0
    return result


def _loop(data: Dataset, problem: Problem, fitter: Fitter, discrepancy: tuple,
          dynamic: DynamicCheck | None, log) -> Calibration:
    """`calibrate`'s steps 1-6 (module notes)."""
    kinds = np.array([data.series[k].kind for k in problem.series_of_point])
    inspections = _inspections(data, problem)
    log(f"{problem.model.describe()}; fitting {', '.join(problem.fit_names)}")
    base = fitter.fit(None)
    log(f"base fit: chi2 {base.chi2_fit:.1f} on {base.n_fit} points, held-out RMSE "
        f"{base.rmse_holdout:.3g} sigma ({base.iterations} steps, {base.wall_time_s:.1f} s)")
    stated_k = problem.base0.get("k")
    slips = unit_slips(data, problem, base, None if stated_k is None else float(stated_k))
    for w in slips:
        log(f"warning: {w['message']}")
    too_few = base.n_fit - problem.n_base - 2 < MIN_DOF_FOR_EFFECT
    if too_few:
        log(f"{base.n_fit} fit points for {problem.n_base} parameters: too few to fit an effect "
            "as well; candidates are scored, not refitted")
        sel = Selection(base, [], [])
        scores = score_tests(fitter, base, kinds)
    else:
        sel = select(fitter, base, kinds, inspections, data, log,
                     None if dynamic is None else _DynamicChi2(problem, dynamic))
        scores = sel.stages[0].scores
    first = sel.stages[0] if sel.stages else None
    refits = {e: a.fit for e, a in first.assessed.items()} if first else {}
    qualifying = [e for e, a in first.assessed.items() if a.qualifies] if first else []
    failed = dict(first.failed) if first else {}
    chosen = sel.model
    gof = _gof(chosen)
    unexplained = not gof["consistent_with_noise"]
    if sel.ambiguous is not None:  # either alternative stands for the model's fit
        unexplained = not _gof(sel.ambiguous[0].model)["consistent_with_noise"]
    log(f"selected: {', '.join(chosen.effects) or 'no effect'}"
        + (" (the residual stays unexplained)" if unexplained else ""))
    suspects = []
    suspect_explains = False
    if (not chosen.effects or unexplained) and sel.ambiguous is None and problem.suspects \
            and not too_few:
        ranked = score_suspects(fitter, base, kinds)
        suspects = [Suspect(s.effect, float(problem.base0[s.effect]), s) for s in ranked]
        # named only when something is left to explain, at p = 0.001 over all suspects
        critical = chi2_isf(0.001 / len(ranked))
        if unexplained and ranked and ranked[0].statistic > critical:
            lead = suspects[0]
            try:
                lead.refit = fitter.fit_suspect(lead.name, np.asarray(base.notes["x"]),
                                                lead.score.first_step)
                suspect_explains = _gof(lead.refit)["consistent_with_noise"]
            except SolverError as err:  # a suspect that cannot be fitted is still named
                log(f"refit with {lead.name} free failed: {err}")
            log(f"suspect: {lead.sentence()}")
    search = None
    if unexplained and not suspect_explains and discrepancy and not too_few:
        # against the base model: effects adopted while the residual stays
        # unexplained may stand in for what the library lacks
        search = learned.search(fitter, base, data, discrepancy, log)
        if search.chosen is not None:
            log(f"discrepancy named: {search.chosen.variable}")
        else:
            log("no discrepancy cuts the held-out error")
    final, adopted = chosen, list(sel.adopted)
    if sel.ambiguous is not None and not chosen.effects:
        final = sel.ambiguous[0].model  # either alternative stands for the fitted model
    if search is not None and search.chosen is not None:
        # the library's effects must still qualify beside the learned discrepancy
        final, judged, dropped = prune(fitter, search.chosen.model, inspections, log,
                                       always=True)
        search.chosen.fit = final
        adopted = [judged[e] for e in final.effects if e in judged]
    explained = _gof(final)["consistent_with_noise"]
    partial = [] if explained else adopted
    adopted = adopted if explained else []
    if sel.ambiguous is not None and not adopted:
        identified = "ambiguous"
    else:
        identified = adopted[0].effect if adopted else "none"
    limits = detection_limits(score_tests(fitter, final, kinds)) if not too_few else {}
    result = Calibration(data, problem, base, scores, refits, qualifying, chosen, identified,
                         unexplained, gof, 0.0, suspects,
                         notes={"failed_refits": failed, "unit_warnings": slips},
                         selection=sel, discrepancy=search, limits=limits, final=final,
                         adopted=adopted, partial=partial)
    if dynamic is not None:
        result.check = model_check(problem, final, dynamic)
        c = result.check
        log(f"check on the {c['model']} model: chi2 {c['chi2_fit']} on the fit points "
            f"(fitted model {final.chi2_fit:.1f}), held out {c['chi2_holdout']}")
        if not c["carries_over"]:
            log("warning: the fit does not carry over to the dynamic model; the quasi-static "
                "model's own error may have chosen the effects (refit with --model dynamic)")
    return result
