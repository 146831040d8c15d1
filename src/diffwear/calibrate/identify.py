"""Find what the base model lacks, on the fit data alone: library effects and
learned discrepancies in one forward selection, a check that the chosen
model predicts, mechanism suspects, detection limits, then the posterior,
the life and the next measurement.

1. Fit the base model (the dataset's fitted parameters, every effect at zero).
2. Forward selection (`select`): at each stage every candidate not yet in
   the model, the library's effects and a discrepancy k (1 + delta(x)) over
   each supported variable (`learned`) alike, is scored at the current model
   (`scores`) and refitted on top of it (a failed refit is retried from
   other starts and, if it still fails, named with its reason; beside other
   members only candidates scoring above `LATER_SCORE` are refitted).  Each
   refit is judged in its identified form (`selection`): adopted on its
   chi-square drop at p = 0.001 for the numbers the data determine (a
   discrepancy's effective number of coefficients included), ranked by BIC
   (`selection.criterion`: no held-out term).  Members already in the model
   are re-judged in the joint fit and dropped if they no longer qualify.
   Paths grow from the best few single candidates (`PATHS`), the best
   discrepancy among them; an addition within `AMBIGUITY` of a stage's best
   grows a branch of its own (`BRANCHES`), and every branch's end competes.
3. Prediction inside the fit window (`validation.forward_check`): each
   path's model, refitted on the points before the window's last
   inspection, must predict that inspection; only predicting models
   compete, the fewest members first (Occam's window, `OCCAM_TOLERANCE`),
   and a runner-up within `AMBIGUITY` makes the answer "A or B" (what both
   hold adopted, the answer open on the rest).  So does a model that differs
   from the chosen one only in its discrepancy's variable and fits the fit
   points as well (chi-square and prior within `AMBIGUITY`, `_rival`): two
   bases over different variables are not nested, and the criterion's gap
   between two that fit alike is only the penalty of their coefficients.
   The held-out points are read once, after the choice, for the before/after
   report.
4. Goodness of fit: the chosen model must leave fit-point residuals
   consistent with the stated noise, chi2 <= dof + `GOF_SIGMAS` sqrt(2 dof);
   otherwise ``residual_unexplained`` is true.
5. Mechanism suspects: when no member is adopted or the residual is
   unexplained, every rig parameter the dataset neither fits nor excludes is
   scored and the best refitted; a suspect outside its plausible range
   (`parameters.plausible_range`) is not a finding.
6. Detection limits at the final model (`scores`); beside a discrepancy, k
   identified orthogonal to it (`FitResult.identified_k`).
7. The posterior (`posterior`), the life and the next measurement
   (`forecast`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, SolverError
from . import learned
from .dataset import Dataset
from .effects import LIBRARY, Effect, Library, log_shape
from .fit import FitResult, Fitter, ModelSettings, Problem
from .forecast import DEFAULT_OUTLOOK, Forecast, Outlook, forecast
from .parameters import RIG_PARAMETERS, plausible_range
from .plausibility import check_depths, unit_slips
from .posterior import Posterior, coverage, predictive_band, refined
from .posterior import posterior as posterior_of
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
    assess_discrepancy,
    criterion,
    determined_numbers,
)
from .validation import PredictiveCheck, forward_check

GOF_SIGMAS = 4.0       # chi2 above dof + 4 sqrt(2 dof): residual not noise
SELECTION_RULE = (
    "chosen on the fit points alone: the library's effects and the learned discrepancies "
    "compete in one forward selection (each adopted on its chi-square drop at p = 0.001 and "
    "ranked by BIC, chi2 + prior + ln n per determined number); a model counts as an "
    "explanation only if, refitted on the points before the fit window's last inspection, "
    "it predicts that inspection; two discrepancies over different variables that fit the fit "
    "points alike (chi2 + prior within 6) are both an answer; the held-out points are read "
    "once, after the choice")
# An effect is refitted only if the fit points leave degrees of freedom after
# it: with none, any candidate fits exactly and nothing can be told apart.
MIN_DOF_FOR_EFFECT = 2
MAX_EFFECTS = 3        # members adopted at most: effects and a discrepancy
# Beside other members, an effect is refitted only when its score test (the
# chi-square drop of one Gauss-Newton step) exceeds this: p = 0.16, where an
# adoption needs a drop of 10.83 (p = 0.001)
LATER_SCORE = 2.0
# Occam's window keeps the models within this many determined numbers of the
# simplest (a discrepancy's effective number of coefficients is not whole)
OCCAM_TOLERANCE = 0.5
# Forward-selection paths: one from each of the best few qualifying single
# effects (a greedy path from the single best can be trapped by an effect
# that mimics a pair of others), each explaining at least PATH_SHARE of the
# criterion drop the best single effect gives
PATHS = 3
PATH_SHARE = 0.9
# Additions within AMBIGUITY of a stage's best grown as branches of their own,
# the best included: a tie is carried to the ends, where the models compete
BRANCHES = 2
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
    def plausible(self) -> bool:
        """Whether the refitted (or first-step) value lies in the parameter's
        plausible range (`parameters.plausible_range`)."""
        bounds = plausible_range(self.name)
        return bounds is None or bounds[0] <= self.factor <= bounds[1]

    def implausible(self) -> str:
        lo, hi = plausible_range(self.name) or (0.0, math.inf)
        return (f"the data ask for {self.name} = {self.value0 * self.factor:.3g} SI "
                f"({self.factor:.3g}x the stated {self.value0:.4g}), outside its plausible "
                f"range ({lo:.3g}x to {hi:.3g}x): not a finding; the residual stands for a "
                "model error of another kind")

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
           "value": s.value0, "factor": s.factor,
           "plausible_range": plausible_range(s.name)}
    if s.refit is not None:
        gof = _gof(s.refit)
        out.update(refit_value=s.refit.params[s.name], refit_std=s.refit.params_std[s.name],
                   refit_chi2_fit=s.refit.chi2_fit, refit_heldout_rmse=s.refit.rmse_holdout,
                   explains=gof["consistent_with_noise"] and s.plausible,
                   sentence=s.sentence())
        if not s.plausible:
            out["implausible"] = s.implausible()
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
    branches: list = field(default_factory=list)   # as close as `added`: grown apart


@dataclass
class Selection:
    model: FitResult                   # the chosen model (base + the adopted members)
    adopted: list                      # Assessment of each adopted member, in the joint fit
    stages: list
    ambiguous: tuple | None = None     # (Path, Path)
    paths: list = field(default_factory=list)   # every path's end, best criterion first


def _starts(score: Score, eff: Effect):
    """Starting (strength, ln shape) pairs of a refit of effect ``eff``: the
    score's first step (at most `FIRST_STEP_SCALES` of the effect's scale),
    a tenth of the scale in its direction, then the scale at the default
    shape and at the shape grid's ends."""
    scale = float(eff.scale)
    sign = 1.0 if score.first_step >= 0 or eff.lower >= 0 else -1.0
    first = float(np.clip(score.first_step, max(eff.lower, -FIRST_STEP_SCALES * scale),
                          FIRST_STEP_SCALES * scale))
    out = [(first, score.log_shape), (0.1 * sign * scale, score.log_shape), (scale, 0.0)]
    if eff.shape is not None:
        out += [(scale, eff.shape.log_std * g) for g in (SHAPE_GRID[0], SHAPE_GRID[-1])]
    return out


def refit(fitter: Fitter, current: FitResult, effect: str, score: Score, log):
    """``current`` + ``effect`` (a library effect from the starts of
    `_starts`, in turn until a fit ends no worse than ``current``: a start far
    down a non-linear direction can end in a poorer minimum; or a learned
    discrepancy, `learned.candidate`); (the best fit, None) or (None, the
    reasons every start failed)."""
    variable = learned.variable_of(effect)
    if variable is not None:
        return _refit_discrepancy(fitter, current, variable, log)
    key = (frozenset((*current.effects, effect)), current.discrepancy)
    cache = fitter.fits
    if key in cache:  # the same model reached on another path
        return cache[key], None
    errors, best = [], None
    t0 = time.perf_counter()
    for tried, (s0, g0) in enumerate(_starts(score, fitter.library.effect(effect)), 1):
        strengths = {**current.strengths, effect: s0}
        shapes = {e: log_shape(e, v, fitter.library) for e, v in current.shapes.items()}
        shapes[effect] = g0
        try:
            f = fitter.fit((*current.effects, effect), s0=strengths, log_shape0=shapes,
                           discrepancy=current.discrepancy, start=current)
        except SolverError as err:
            errors.append(str(err))
            continue
        if best is None or f.chi2_fit < best.chi2_fit:
            best = f
        if f.chi2_fit <= current.chi2_fit + 1e-6 * current.chi2_fit:
            break
    if best is not None:
        best.notes.update(starts=tried, refit_s=time.perf_counter() - t0)
        _note_edf(best)
        cache[key] = best
        return best, None
    reason = "; ".join(dict.fromkeys(errors))
    log(f"refit + {effect} failed from {len(errors)} starts: {reason}")
    return None, reason


def _note_edf(fit: FitResult) -> None:
    if fit.discrepancy is not None and "discrepancy_edf" not in fit.notes:
        fit.notes["discrepancy_edf"] = learned.effective_coefficients(fit)


def _fit_cached(fitter: Fitter, effects: tuple, discrepancy: str | None, start: FitResult):
    """The model of ``effects`` and ``discrepancy``, fitted from ``start``
    once; fitted again from a later ``start`` that holds it and fits better
    by more than `LR_CRITICAL` of one number (a model less a member can be
    no better than the model, so a cached fit that far above it sits in a
    poorer minimum, which the larger model's numbers lead out of); the
    better of the two is kept."""
    key = (frozenset(effects), discrepancy)
    cached = fitter.fits.get(key)
    if cached is not None and not (start.chi2_fit < cached.chi2_fit - LR_CRITICAL[1]
                                   and _holds(start, effects, discrepancy)):
        return cached
    f = fitter.fit(effects, start=start, discrepancy=discrepancy)
    _note_edf(f)
    if cached is None or f.chi2_fit < cached.chi2_fit:
        fitter.fits[key] = f
    return fitter.fits[key]


def _holds(model: FitResult, effects: tuple, discrepancy: str | None) -> bool:
    """Whether ``model`` holds every member of (``effects``, ``discrepancy``)."""
    return set(effects) <= set(model.effects) and discrepancy in (None, model.discrepancy)


def _refit_discrepancy(fitter: Fitter, current: FitResult, variable: str, log):
    t0 = time.perf_counter()
    try:
        f = _fit_cached(fitter, current.effects, variable, current)
    except SolverError as err:
        log(f"refit + {learned.label(learned.candidate(variable))} failed: {err}")
        return None, str(err)
    f.notes.setdefault("refit_s", time.perf_counter() - t0)
    return f, None


def _members(model: FitResult) -> tuple:
    """The candidates a model holds: its effects and its discrepancy."""
    return (*model.effects,
            *((learned.candidate(model.discrepancy),) if model.discrepancy else ()))


def _name(model: FitResult, leave=()) -> str:
    """The members of ``model`` (less ``leave``) in words, joined by " + "."""
    return " + ".join(learned.label(m) for m in _members(model) if m not in leave)


def _without(model: FitResult, member: str) -> tuple:
    """(effects, discrepancy) of ``model`` less ``member``."""
    if learned.variable_of(member) is not None:
        return model.effects, None
    return tuple(x for x in model.effects if x != member), model.discrepancy


def _judge(fitter, member: str, model: FitResult, without: FitResult, inspections):
    if learned.variable_of(member) is not None:
        return assess_discrepancy(member, model, without)
    return assess(fitter, member, model, without, inspections)


def _judge_members(fitter, model: FitResult, inspections, log, always: bool = False):
    """Each member of ``model`` (effect or discrepancy) judged in the joint fit
    against the model without it; returns (assessments, the weakest that
    fails or None).  A single member is judged only when ``always``."""
    out: dict = {}
    weakest = None
    members = _members(model)
    if len(members) == 1 and not always:
        return out, None
    for e in members:
        effects, variable = _without(model, e)
        try:
            without = _fit_cached(fitter, effects, variable, model)
        except SolverError as err:
            log(f"refit without {learned.label(e)} failed: {err}")
            continue
        a = _judge(fitter, e, model, without, inspections)
        out[e] = a
        # the weakest failing member: the one whose removal leaves the best model
        if not a.qualifies and (weakest is None
                                or criterion(without) < criterion(weakest[1])):
            weakest = (e, without)
    return out, weakest


def prune(fitter: Fitter, model: FitResult, inspections, log, always: bool = False):
    """Drop the members of ``model`` (effects, discrepancy) that no longer
    qualify beside the others, weakest first; (model, {member: Assessment},
    dropped)."""
    judged, weakest = _judge_members(fitter, model, inspections, log, always)
    dropped = []
    while weakest is not None:
        e, model = weakest
        dropped.append(e)
        judged.pop(e, None)
        log(f"dropped: {learned.label(e)} (no longer qualifies beside the rest of the model)")
        judged, weakest = _judge_members(fitter, model, inspections, log, always)
    return model, judged, dropped


def _stage(fitter: Fitter, current: FitResult, kinds, inspections, log,
           exclude=(), variables=()) -> Stage:
    """Score every candidate not in ``current`` (nor ``exclude``): the library's
    effects and, when ``current`` has none, the discrepancy over each of
    ``variables``; refit each effect with a positive score and each
    discrepancy whose score passes `learned.SCREEN_P` on top of it (the
    scores kept in ``current``'s notes: a path grown again reaches the same
    fits)."""
    key = ("scores", tuple(sorted(exclude)), tuple(variables))
    if key not in current.notes:
        current.notes[key] = (score_tests(fitter, current, kinds, exclude)
                              + _discrepancy_scores(fitter, current, variables, exclude))
    scores = current.notes[key]
    log(("scores" if not _members(current) else
         f"scores beside {_name(current)}")
        + ": " + ", ".join(f"{learned.label(s.effect)} {s.statistic:.3g}" for s in scores))
    stage = Stage(scores, {}, {})
    # at the first stage every effect with a positive score is refitted (a
    # strong non-linear effect can score low at zero strength); beside
    # others, one whose score could not grow into an adoption is not
    floor = 0.0 if not _members(current) else LATER_SCORE
    todo = [s for s in scores if s.statistic > floor and (
        learned.variable_of(s.effect) is None or s.p_value < learned.SCREEN_P)]
    done = [(s, refit(fitter, current, s.effect, s, log)) for s in todo]
    for s, (f, failure) in done:
        if f is None:
            stage.failed[s.effect] = failure
            continue
        a = _judge(fitter, s.effect, f, current, inspections)
        stage.assessed[s.effect] = a
        log(f"refit + {learned.label(s.effect)}: {_words(a)}")
    return stage


def _discrepancy_scores(fitter: Fitter, current: FitResult, variables, exclude) -> list:
    """Score tests (`learned.score`) of the discrepancy over each variable,
    when ``current`` has none; as `Score` (statistic, p-value corrected for
    the number of variables)."""
    todo = [v for v in variables if learned.candidate(v) not in exclude]
    if current.discrepancy is not None or not todo:
        return []
    rows = ~fitter.problem.holdout
    if current.effects or current.discrepancy is not None:
        jb, v = current.notes["jacobian"], current.notes["v"]
    else:
        jb = fitter.parameter_jacobian(np.asarray(current.notes["x"]), names=())[0][rows]
        v = current.notes.get("v", fitter._pack(np.asarray(current.notes["x"])))
    out = []
    for variable in todo:
        t = learned.score(fitter, current, variable, jb, v)
        out.append(Score(learned.candidate(variable), t["statistic"], 0.0,
                         min(1.0, len(todo) * t["p_value"]), by_kind={"dof": t["dof"]}))
    return sorted(out, key=lambda s: -s.statistic)


@dataclass
class Path:
    """One forward-selection path: the model it ends on and its effects'
    assessments in that model."""

    model: FitResult
    adopted: dict
    stages: list
    start: str | None = None                 # its first member (None: held back)
    check: "PredictiveCheck | None" = None   # its prediction of the last fit inspection

    @property
    def criterion(self) -> float:
        return criterion(self.model)

    @property
    def numbers(self) -> float:
        return determined_numbers(self.model)

    @property
    def name(self) -> str:
        return _name(self.model) or "none"


def _improving(stage: Stage, current: FitResult) -> list:
    """The stage's qualifying candidates that improve on ``current`` by the
    criterion, best first."""
    return sorted((a for a in stage.assessed.values()
                   if a.qualifies and a.criterion < criterion(current)),
                  key=lambda a: a.criterion)


def _grow(fitter: Fitter, first: Assessment, kinds, inspections, log,
          reference=None, foresee=None, variables=(), base: FitResult | None = None) -> list:
    """Forward selection from the one-candidate model ``first``: the best
    qualifying addition (effect or discrepancy over one of ``variables``)
    by the criterion at each stage, then the members already in the model
    re-judged beside it; a member dropped is not offered again on this
    path.  An addition within `AMBIGUITY` of the best opens a branch of its
    own (at most `BRANCHES` at a stage): where two additions tie, the data
    may still tell their models apart one stage on, and only comparing the
    ends can say.  Returns every branch's `Path`, best criterion first.

    ``reference(fit) -> chi2`` (the dynamic model's fit-point chi-square,
    evaluated, not refitted): an addition must lower it too, else it stands
    for the fitted model's own error.  So must ``first`` from ``base`` (the
    model without it) where ``first`` is a learned discrepancy and the
    base's is finite: a path whose first member is a discrepancy that raises
    it ends on ``base``.  (A first library effect is not held back: its
    form is physics both models share, and where their pressure
    distributions differ its dynamic chi-square can rise although it is the
    cause; a discrepancy can take any shape, the fitted model's error's
    too.)  ``foresee(fit)``: told the fits that check would evaluate
    (unchecked)."""
    if base is not None and learned.variable_of(first.effect) is not None:
        if foresee is not None:
            foresee(base)
            foresee(first.fit)
        if reference is not None:
            before, after = reference(base), reference(first.fit)
            if math.isfinite(before) and _held_back(first, before, after, log):
                return [Path(base, {}, [])]
    def end(model, adopted, stages) -> Path:
        return Path(model, {e: adopted[e] for e in _members(model) if e in adopted}, stages,
                    first.effect)

    # branches still to grow: (model, its members' assessments, stages, excluded)
    todo: list[tuple] = [(first.fit, {first.effect: first}, [], frozenset())]
    grown = {frozenset(_members(first.fit))}
    ends = []
    while todo:
        current, adopted, stages, excluded = todo.pop(0)
        if len(_members(current)) >= MAX_EFFECTS:
            ends.append(end(current, adopted, stages))
            continue
        stage, ties = _additions(fitter, current, kinds, inspections, log, excluded, variables,
                                 reference, foresee)
        if not ties:
            ends.append(end(current, adopted, [*stages, stage]))
            continue
        beside = _name(current)
        if len(ties) > 1:
            log(f"beside {beside}: " + " or ".join(learned.label(a.effect) for a in ties)
                + f" (within {AMBIGUITY:g} in the criterion): each grown on a branch of its own")
        for a in ties:
            members = frozenset((*_members(current), a.effect))
            if members in grown:
                continue
            grown.add(members)
            branch = dataclasses.replace(stage, added=a.effect, dropped=[], branches=[
                t.effect for t in ties if t is not a])
            log(f"adopted beside {beside}: {learned.label(a.effect)}"
                + (" (on a branch of its own)" if a is not ties[0] else ""))
            model, judged, branch.dropped = prune(fitter, a.fit, inspections, log)
            kept = {**adopted, a.effect: a}
            for e in branch.dropped:
                kept.pop(e, None)
            kept.update(judged)
            if a.effect in branch.dropped:   # the addition itself fell: the path ends
                ends.append(end(model, kept, [*stages, branch]))
                continue
            todo.append((model, kept, [*stages, branch], excluded | set(branch.dropped)))
    return sorted(ends, key=lambda p: p.criterion)


def _additions(fitter: Fitter, current: FitResult, kinds, inspections, log, excluded,
               variables, reference, foresee) -> tuple:
    """One stage on top of ``current``: the stage, and the qualifying
    additions that improve on it by the criterion, the best and those within
    `AMBIGUITY` of it (at most `BRANCHES`), each passed by ``reference``
    (`_grow`) where given."""
    stage = _stage(fitter, current, kinds, inspections, log, tuple(excluded), variables)
    ranked = _improving(stage, current)
    if ranked and foresee is not None:
        foresee(current)
        for a in ranked[:BRANCHES]:
            foresee(a.fit)
    if ranked and reference is not None:
        before = reference(current)
        beside = _name(current)
        passed: list = []
        for a in ranked:
            if passed and a.criterion - passed[0].criterion >= AMBIGUITY:
                break
            after = reference(a.fit)
            if not _held_back(a, before, after, log, beside):
                log(f"+ {learned.label(a.effect)} beside {beside}: the dynamic "
                    f"model's chi2 falls {before:.5g} -> {after:.5g}")
                passed.append(a)
            if len(passed) == BRANCHES:
                break
        ranked = [a for a in ranked if a.qualifies]
    ties = [a for a in ranked if a.criterion - ranked[0].criterion < AMBIGUITY][:BRANCHES]
    return stage, ties


def _held_back(a: Assessment, before: float, after: float, log, beside: str = "") -> bool:
    """Whether the dynamic model's fit-point chi-square fails to fall from
    ``before`` to ``after`` with ``a``'s candidate added (``beside`` the
    members already in the model); if so, ``a`` no longer qualifies, with
    the reason, and the log says so."""
    if after < before:
        return False
    a.qualifies = False
    a.reasons.append(f"the dynamic model's chi2 rises ({before:.5g} -> {after:.5g}): the "
                     "fitted model's own error")
    log(f"+ {learned.label(a.effect)}{f' beside {beside}' if beside else ''}: the dynamic "
        f"model's chi2 rises {before:.5g} -> {after:.5g}; not adopted")
    return True


@dataclass
class _Grown:
    paths: list        # the ends of one start's branches, best first
    seen: set          # their log lines
    checked: bool      # grown with the dynamic model's check

    @property
    def criterion(self) -> float:
        return self.paths[0].criterion


def select(fitter: Fitter, base: FitResult, kinds, inspections, data, log,
           reference=None, variables=()) -> Selection:
    """Forward selection along `PATHS` paths (module notes): each starts from
    one of the best qualifying single candidates (and one from the best
    qualifying discrepancy) and grows greedily; the paths' final models are
    checked on the last fit inspection (`validation`), and those that predict
    it are compared by the criterion, within Occam's window."""
    stage1 = _stage(fitter, base, kinds, inspections, log, (), variables)
    ranked = _improving(stage1, base)
    if not ranked:
        return Selection(base, [], [stage1])
    # a path starts from a single candidate that explains most of what the
    # best one explains (a far poorer start cannot be rescued by one more),
    # and one from the best discrepancy: a library effect that fits the fit
    # points as well may not predict, and only the check below can tell
    gain = criterion(base) - ranked[0].criterion
    starts = [a for a in ranked[:PATHS]
              if a.criterion - ranked[0].criterion <= (1.0 - PATH_SHARE) * gain]
    learned_first = [a for a in ranked if learned.variable_of(a.effect) is not None]
    if learned_first and learned_first[0] not in starts:
        starts = [*starts[:PATHS - 1], learned_first[0]]
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
                                  foresee=foresee, variables=variables, base=base),
                            seen, reference is None))
    while True:
        unchecked = [g for g in grown if not g.checked]
        lead = min((g.paths[0] for g in grown if g.checked), key=lambda p: p.criterion,
                   default=None)
        if lead is not None:   # only a path that could enter the best checked one's window
            unchecked = [g for g in unchecked if g.criterion < lead.criterion + AMBIGUITY
                         or any(_rival(lead, p) for p in g.paths)]
        if not unchecked:
            break
        g = min(unchecked, key=lambda g: g.criterion)
        log(f"path {g.paths[0].name}: checked on the dynamic model")
        g.paths = _grow(fitter, starts[grown.index(g)], kinds, inspections,
                        lambda line, seen=g.seen: None if line in seen else log(line), reference,
                        variables=variables, base=base)
        g.checked = True
    paths: dict[tuple, Path] = {}
    trailing = []
    for g in grown:
        for path in g.paths:
            if g.checked:
                paths.setdefault(tuple(sorted(_members(path.model))), path)
            else:
                trailing.append(path)
                log(f"path {path.name}: not checked on the dynamic model (criterion "
                    f"{path.criterion:.1f}, {AMBIGUITY:g} or more above the best checked path)")
    order = sorted(paths.values(), key=lambda p: p.criterion)
    # a model is an explanation only when it also predicts the last fit
    # inspection from the earlier ones (`validation`)
    for p in order:
        p.check = forward_check(fitter, p.model, data)
        if p.check is not None:
            log(f"path {p.name}: {p.check.sentence()}")
    predicting = [p for p in order if p.check is None or p.check.predicts]
    if predicting and predicting[0] is not order[0]:
        log(f"{order[0].name} fits best but does not predict the last fit inspection; "
            f"{predicting[0].name} does")
    pool = predicting or order
    window = [p for p in pool if p.criterion - pool[0].criterion < AMBIGUITY]
    # Occam's window: among comparable models the simplest, first by causes
    # (one effect is a simpler explanation than a pair that fits as well),
    # then by the numbers the data determine
    fewest = min(len(_members(p.model)) for p in window)
    window = [p for p in window if len(_members(p.model)) == fewest]
    simplest = min(p.numbers for p in window)
    window = [p for p in window if p.numbers <= simplest + OCCAM_TOLERANCE]
    best = window[0]
    stage1.added = best.start
    stages = [stage1, *best.stages]
    rival = min((p for p in pool if _rival(best, p)), key=_misfit, default=None)
    if len(window) == 1 and rival is not None:
        log(f"{rival.name} fits the fit points as well as {best.name} (chi2 + prior "
            f"{_misfit(rival):.1f} and {_misfit(best):.1f}): the criterion's gap "
            f"({rival.criterion - best.criterion:.1f}) is only the penalty of their "
            "coefficients")
        window.append(rival)
    if len(window) > 1:
        other = window[1]
        log(f"{best.name} or {other.name}: these data cannot tell them apart (criteria "
            f"{best.criterion:.1f} and {other.criterion:.1f})")
        stage1.ambiguous = (best, other)
        # what both alternatives hold is adopted; the answer is open on the rest
        shared = [best.adopted[e] for e in _members(best.model)
                  if e in _members(other.model) and e in best.adopted]
        return Selection(base, shared, stages, (best, other), order)
    others = sorted((p for p in (*order, *trailing) if p is not best), key=lambda p: p.criterion)
    log(f"selected: {best.name} (criterion {best.criterion:.1f}; other paths: "
        + (", ".join(f"{p.name} {p.criterion:.1f}" for p in others) or "none") + ")")
    return Selection(best.model, list(best.adopted.values()), stages, None, order)


def _misfit(p: Path) -> float:
    """The fit points' chi-square of a path's model with its prior rows: the
    criterion without the penalty of its determined numbers."""
    return p.model.chi2_fit + p.model.prior_chi2


def _rival(best: Path, p: Path) -> bool:
    """Whether ``p``'s model differs from ``best``'s only in the variable of
    its learned discrepancy and fits the fit points as well, its `_misfit`
    less than `AMBIGUITY` above (module notes).  Two bases over different
    variables are not nested: when their fits tie, the criterion's gap is
    only the penalty of their coefficients, which follows the bases' sizes
    and priors (five depth layers against three cycle-count terms), not
    the data."""
    a, b = best.model, p.model
    return (p is not best and a.discrepancy is not None
            and b.discrepancy not in (None, a.discrepancy)
            and sorted(a.effects) == sorted(b.effects)
            and _misfit(p) - _misfit(best) < AMBIGUITY)


def second_weight(first: Path, second: Path) -> tuple[float, str]:
    """The second explanation's weight in an open answer, and the rule:
    exp(-criterion / 2), normalised (Bayesian model averaging with BIC
    weights); for two discrepancies over different variables that fit alike
    (`_rival`), exp(-(chi2 + prior) / 2), as the criterion's gap between them
    is only their coefficients' penalty."""
    if _rival(first, second):
        a, b, rule = _misfit(first), _misfit(second), "exp(-(chi2 + prior) / 2)"
    else:
        a, b, rule = first.criterion, second.criterion, "exp(-criterion / 2)"
    return 1.0 / (1.0 + math.exp(0.5 * (b - a))), rule


def _words(a: Assessment) -> str:
    f = a.fit
    verdict = ((" (qualifies)" if a.qualifies else f" ({'; '.join(a.reasons)})")
               + f" [{f.notes.get('starts', 1)} start(s), {f.iterations} steps, "
                 f"{f.notes.get('refit_s', f.wall_time_s):.1f} s]")
    if a.edf is not None:
        return (f"chi2 {f.chi2_fit:.1f}, {a.edf:.2g} effective coefficients, chi2 drop "
                f"{a.likelihood_ratio:.1f}" + verdict)
    shape = "" if f.shapes.get(a.effect) is None else f", shape {f.shapes[a.effect]:.3g}" + (
        "" if a.shape_determined else " (not determined)")
    form = f"; {a.form.sentence(a.effect)}" if a.form is not None else ""
    return (f"strength {f.strengths[a.effect]:.4g} +- {f.strengths_std[a.effect]:.2g}{shape}, "
            f"chi2 {f.chi2_fit:.1f}{form}" + verdict)


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
    discrepancy: Assessment | None = None   # the adopted discrepancy
    limits: dict = field(default_factory=dict)
    final: FitResult | None = None   # the adopted effects (+ the named discrepancy)
    adopted: list = field(default_factory=list)   # Assessment of each named effect
    partial: list = field(default_factory=list)   # adopted, but leaving the residual
    prediction: PredictiveCheck | None = None     # the final model's forward check
    without_discrepancy: FitResult | None = None  # the final model less its discrepancy
    posterior: Posterior | None = None
    # an "A or B" answer: the second model's posterior and its weight
    open_posterior: tuple[Posterior, float] | None = None
    coverage: dict = field(default_factory=dict)  # share of points inside the 90 % band
    forecast: Forecast | None = None

    @property
    def pool(self) -> tuple[tuple[Posterior, float], ...]:
        """(posterior, weight) of each model the answer holds: the chosen
        model's alone, or both of an "A or B" answer by their weights."""
        if self.posterior is None:
            return ()
        if self.open_posterior is None:
            return ((self.posterior, 1.0),)
        return ((self.posterior, 1.0 - self.open_posterior[1]), self.open_posterior)

    def _own_discrepancy(self, model: FitResult, shared: set) -> dict:
        """{"discrepancy_shape": words} of an open answer's explanation whose
        discrepancy the other does not hold; else {}."""
        v = model.discrepancy
        if v is None or learned.candidate(v) in shared:
            return {}
        d = learned.describe(v, model.discrepancy_coefficients, model.discrepancy_cov,
                             self.dataset, model.notes.get("log_k_per_coefficient"),
                             self.problem.library)
        return {"discrepancy_shape": d["shape"]}

    def pool_models(self) -> list[dict] | None:
        """{name, weight, weighted_by} of each model `pool` holds when it holds
        two (`second_weight`: the rule)."""
        if len(self.pool) < 2 or self.selection is None or self.selection.ambiguous is None:
            return None
        rule = second_weight(*self.selection.ambiguous)[1]
        return [{"name": m.name, "weight": w, "weighted_by": rule}
                for m, (_, w) in zip(self.selection.ambiguous, self.pool)]

    def predictive_band(self):
        """(lower, upper) 90 % predictive band of every point over `pool`."""
        p = self.problem
        return predictive_band(self.pool, p.sigma, p.y)

    def summary(self) -> dict:
        final = self.final or self.chosen
        m = self.problem.model
        sel = self.selection
        effects = [a.entry() for a in self.adopted]
        if sel is not None and sel.ambiguous is not None:
            a, b = sel.ambiguous
            shared = set(_members(a.model)) & set(_members(b.model))
            beside = [learned.label(m) for m in _members(a.model) if m in shared]
            sentence = (f"{_apart(a, shared)} or {_apart(b, shared)}"
                        + (f" beside {' + '.join(beside)}" if beside else "")
                        + ": these data cannot tell them apart")
            separation = None if self.forecast is None else self.forecast.next_measurement
            if separation and "expected_separation_sigma" in separation:
                sentence += "; " + separation["sentence"]
            effects.append({
                "name": f"{_apart(a, shared)} or {_apart(b, shared)}", "ambiguous": True,
                "beside": beside,
                "alternatives": [{"name": p.name, "criterion": p.criterion,
                                  "effects": [x.entry() for e, x in p.adopted.items()
                                              if learned.variable_of(e) is None
                                              and e not in shared],
                                  "discrepancy": p.model.discrepancy,
                                  **self._own_discrepancy(p.model, shared)}
                                 for p in (a, b)],
                "separating_measurement": separation, "sentence": sentence})
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
            "effects_refused": [{"name": n, "reason": why} for n, why in self.problem.refused],
            "heldout_rmse_before": self.base.rmse_holdout,
            "heldout_rmse_after": final.rmse_holdout,
            "heldout_rmse_units": "stated 1-sigma measurement noise",
            "fit_rmse_before": self.base.rmse_fit,
            "fit_rmse_after": final.rmse_fit,
            "chi2_fit": final.chi2_fit,
            "parameters": final.params,
            "parameters_std": final.params_std,
            "candidates": [_candidate(s, self.refits.get(s.effect), s.effect in self.qualifying,
                                      self.notes.get("failed_refits", {}).get(s.effect),
                                      self.problem.library)
                           for s in self.scores],
            "stages": [_stage_summary(st) for st in (sel.stages if sel else [])],
            "detection_limits": self.limits,
            "discrepancy": _discrepancy(self),
            "goodness_of_fit": self.gof,
            "suspects": [_suspect(s) for s in self.suspects],
            "suspect": (self.suspects[0].sentence()
                        if self.suspects and self.suspects[0].refit is not None
                        and self.suspects[0].plausible else None),
            "model_check": self.check,
            "model_settings": {"description": m.describe(), "n_theta": m.n_theta},
            "selection": {
                "rule": SELECTION_RULE,
                "prediction_check": None if self.prediction is None
                else self.prediction.entry(),
                "paths": [{"name": p.name, "criterion": p.criterion,
                           "prediction_check": None if p.check is None else p.check.entry()}
                          for p in (sel.paths if sel else [])]},
            "posterior": None if self.posterior is None else self.posterior.entry(),
            "heldout_coverage": self.coverage.get("heldout"),
            "fit_coverage": self.coverage.get("fit"),
            "coverage_models": self.pool_models(),
            "life": None if self.forecast is None else {
                "limit_mm": self.forecast.limit * 1e3, **self.forecast.life,
                "depth_at_horizon": self.forecast.depth,
                "horizon_cycles": self.forecast.horizon},
            "next_measurement": None if self.forecast is None
            else self.forecast.next_measurement,
            "wall_time_s": self.wall_time_s,
        }
        return out

    def summary_discrepancy(self) -> dict:
        """The discrepancy as `summary.json` lists it (`_discrepancy`)."""
        return _discrepancy(self) or {}


def _apart(p: Path, shared) -> str:
    """``p``'s name less the members it shares with its alternative."""
    return _name(p.model, shared) or "none"


def _stage_summary(st: Stage) -> dict:
    return {"added": st.added, "dropped": st.dropped, "branches": st.branches,
            "ambiguous": [p.name for p in st.ambiguous] if st.ambiguous else None,
            "candidates": {e: {"criterion": a.criterion, "qualifies": a.qualifies,
                               "reasons": a.reasons, "z": a.z,
                               "likelihood_ratio": a.likelihood_ratio}
                           for e, a in st.assessed.items()},
            "failed": st.failed}


def _discrepancy(c: Calibration) -> dict | None:
    """The discrepancy in `summary.json`: the adopted one described, with k
    with and without it; else the variables tried and why none qualified."""
    sel = c.selection
    stage1 = sel.stages[0] if sel is not None and sel.stages else None
    tried = {}
    for s in (stage1.scores if stage1 else []):
        v = learned.variable_of(s.effect)
        if v is None:
            continue
        assert stage1 is not None  # the scores are the first stage's
        a = stage1.assessed.get(s.effect)
        tried[v] = {"score": s.statistic, "p_value": s.p_value,
                    **({} if a is None else {"chi2_fit": a.fit.chi2_fit, "criterion": a.criterion,
                                             "qualifies": a.qualifies, "reasons": a.reasons,
                                             "effective_coefficients": a.edf})}
        if s.effect in stage1.failed:
            tried[v]["failed"] = stage1.failed[s.effect]
    d = c.discrepancy
    open_ = [] if sel is None or sel.ambiguous is None else list(sel.ambiguous)
    if d is None and any(p.model.discrepancy for p in open_):
        # one explanation of an open answer holds a discrepancy: not adopted, not refused
        return {"variable": None, "alternatives": [p.model.discrepancy for p in open_],
                "tried": tried, "shape": "open: " + " or ".join(p.name for p in open_)
                + " (the fit data cannot tell them apart)"}
    if d is None:
        if not tried:
            return None
        return {"variable": None, "tried": tried,
                "shape": "no discrepancy in " + _or_list(list(tried)) + " qualifies beside "
                         "the library's effects on the fit data"}
    f = c.final or d.fit
    lay = f.notes["layout"]
    variable = f.discrepancy
    assert variable is not None  # an adopted discrepancy is in the final model
    b = f.notes.get("log_k_per_coefficient")
    out = learned.describe(variable, f.discrepancy_coefficients, f.discrepancy_cov,
                           c.dataset, b, c.problem.library)
    out.update(effective_coefficients=f.notes.get("discrepancy_edf"), tried=tried,
               likelihood_ratio=d.likelihood_ratio,
               log_k_per_coefficient=None if b is None else np.asarray(b).tolist())
    w = c.without_discrepancy
    k = c.problem.fit_names[lay.fitter.k_index] if lay.fitter.k_index is not None else None
    if k is not None:
        out["k_with"] = {"value": f.params[k], "std": f.params_std[k]}
        if w is not None:
            out["k_without"] = {"value": w.params[k], "std": w.params_std[k]}
    return out


def _or_list(items) -> str:
    words = [i.replace("_", " ") for i in items]
    if len(words) <= 1:
        return "".join(words) or "any variable"
    return ", ".join(words[:-1]) + " or " + words[-1]


def _candidate(s: Score, refit: FitResult | None, qualifies: bool,
               failure: str | None = None, library: Library = LIBRARY) -> dict:
    out = {"name": s.effect, "score": s.statistic, "p_value": s.p_value,
           "first_step": s.first_step}
    if failure:
        out["refit_failed"] = failure
    if learned.variable_of(s.effect) is not None:   # a discrepancy: no strength or shape
        if refit is not None:
            out.update(refit_chi2_fit=refit.chi2_fit, qualifies=qualifies,
                       effective_coefficients=refit.notes.get("discrepancy_edf"))
        return out
    shape = library.effect(s.effect).shape
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


def discrepancy_variables(data: Dataset, spec: str, library: Library = LIBRARY) -> tuple:
    """The ``--discrepancy`` option: 'all' (every variable of ``library`` the
    data can show), 'none', or comma-separated names, each checked against
    the data."""
    VARIABLES = library.variable_names
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
    learned.check_variables(data, names, library)
    return names


def calibrate(data: Dataset, settings: ModelSettings | None = None, *,
              top: int = DEFAULT_TOP, check: bool = True, discrepancy=None,
              outlook: Outlook | None = DEFAULT_OUTLOOK, log=print) -> Calibration:
    """The whole loop on one dataset (module notes).  ``check``: evaluate the
    chosen fit on the dynamic model too (when the fit ran on another);
    ``discrepancy``: the candidate variables of a learned discrepancy
    (None: every variable of ``settings.library``; empty: none);
    ``outlook``: the posterior, the life and the next measurement (None:
    none; default `DEFAULT_OUTLOOK`); ``settings`` default `ModelSettings()`.
    ``top`` is kept for compatibility: every candidate is refitted."""
    del top
    t0 = time.perf_counter()
    settings = ModelSettings() if settings is None else settings
    problem = Problem.from_dataset(data, settings)
    library = settings.library
    if discrepancy is None:
        discrepancy = library.variable_names
    discrepancy = tuple(discrepancy)
    if discrepancy != library.variable_names:
        # asked for by name: refuse what the data cannot show
        learned.check_variables(data, discrepancy, library)
    require_fit_points(data, problem.n_base)
    wall = problem.base0.get("wall")
    check_depths(data, None if wall is None else float(wall))
    if outlook is not None:
        outlook.resolved(data, problem)  # bad limits and horizons refused before the work
    fitter = Fitter(problem)
    check = check and problem.model.checked_on_dynamic
    # the dynamic model, compiled and evaluated beside the fits (`reference`)
    dynamic = DynamicCheck(data, settings) if check else None
    try:
        result = _loop(data, problem, fitter, discrepancy, dynamic, log)
    finally:
        if dynamic is not None:
            dynamic.close()
    if outlook is not None and result.base.dof > 0:
        _look_ahead(result, fitter, outlook, log)
    result.wall_time_s = time.perf_counter() - t0
    return result


def _look_ahead(c: "Calibration", fitter: Fitter, outlook: Outlook, log) -> None:
    """The chosen model's posterior (and, for an "A or B" answer, the second
    model's), the predictive bands' coverage of the held-out points, the life
    with its band and the next measurement."""
    final = c.final or c.base
    t0 = time.perf_counter()
    exact = getattr(fitter.problem.model, "name", "") == "quasi-static"
    method = outlook.method if exact else "linear"
    c.posterior = refined(fitter, posterior_of(fitter, final, method, log), log)
    if c.posterior.fit is not final:   # the same model at a better minimum
        c.final = final = c.posterior.fit
        for a in (*c.adopted, *c.partial, *([c.discrepancy] if c.discrepancy else [])):
            a.fit = final
    sel = c.selection
    alternatives = None
    if sel is not None and sel.ambiguous is not None:
        first, second = sel.ambiguous
        alternatives = (first.model, second.model)
        # the data have not chosen: the bands and the life are over both, by their weights
        weight, _ = second_weight(first, second)
        c.open_posterior = (refined(fitter, posterior_of(fitter, second.model, method, log), log),
                            weight)
    p = c.problem
    c.coverage = {"fit": coverage(c.pool, p.sigma, p.y, ~p.holdout),
                  "heldout": coverage(c.pool, p.sigma, p.y, p.holdout)}
    d = c.posterior.diagnostics
    log(f"posterior ({c.posterior.method}): " + (
        f"Pareto k {d['pareto_k']:.2f}, ESS {d['ess']:.0f}" if "pareto_k" in d else
        f"max R-hat {d.get('max_r_hat', math.nan):.3f}, min ESS {d.get('min_ess', math.nan):.0f}"
        f", {d.get('draws_per_chain', 0)} draws a chain")
        + f" ({time.perf_counter() - t0:.0f} s)")
    limit, horizon = outlook.resolved(c.dataset, p)
    if limit is None:
        return
    t0 = time.perf_counter()
    c.forecast = forecast(fitter, c.pool, c.dataset, limit, horizon, alternatives)
    life = c.forecast.life
    models = c.pool_models()
    if models:
        life["models"] = models
    log(f"life to {limit * 1e3:g} mm: {life['median']:,.0f} cycles (90 %: {life['q05']:,.0f}"
        f"-{life['q95']:,.0f}); next measurement: "
        f"{(c.forecast.next_measurement or {}).get('sentence', 'none')} "
        f"({time.perf_counter() - t0:.0f} s)")


def _loop(data: Dataset, problem: Problem, fitter: Fitter, discrepancy: tuple,
          dynamic: DynamicCheck | None, log) -> Calibration:
    """`calibrate`'s steps (module notes)."""
    kinds = problem.kind_of_point
    inspections = _inspections(data, problem)
    log(f"{problem.model.describe()}; fitting {', '.join(problem.fit_names)}")
    for effect, why in problem.refused:
        log(f"not a candidate: {effect} ({why})")
    base = fitter.fit(None)
    log(f"base fit: chi2 {base.chi2_fit:.1f} on {base.n_fit} points ({base.iterations} steps, "
        f"{base.wall_time_s:.1f} s)")
    stated_k = problem.base0.get("k")
    slips = unit_slips(data, problem, base, None if stated_k is None else float(stated_k))
    for w in slips:
        log(f"warning: {w['message']}")
    variables = tuple(v for v in discrepancy
                      if learned.unsupported(data, v, fitter.library) is None)
    too_few = base.n_fit - problem.n_base - 2 < MIN_DOF_FOR_EFFECT
    fitter.fits[(frozenset(), None)] = base
    if too_few:
        log(f"{base.n_fit} fit points for {problem.n_base} parameters: too few to fit an effect "
            "as well; candidates are scored, not refitted")
        sel = Selection(base, [], [])
        scores = score_tests(fitter, base, kinds)
    else:
        sel = select(fitter, base, kinds, inspections, data, log,
                     None if dynamic is None else _DynamicChi2(problem, dynamic), variables)
        scores = sel.stages[0].scores
    first = sel.stages[0] if sel.stages else None
    refits = {e: a.fit for e, a in first.assessed.items()} if first else {}
    qualifying = [e for e, a in first.assessed.items() if a.qualifies] if first else []
    failed = dict(first.failed) if first else {}
    chosen = sel.model
    final = chosen
    if sel.ambiguous is not None and not _members(chosen):
        final = sel.ambiguous[0].model  # either alternative stands for the fitted model
    gof = _gof(final)
    path = next((p for p in sel.paths if p.model is final), None)
    prediction = path.check if path is not None else (
        forward_check(fitter, final) if _members(final) else None)
    explained = gof["consistent_with_noise"] and (prediction is None or prediction.predicts)
    unexplained = not explained
    answer = (" or ".join(p.name for p in sel.ambiguous) if sel.ambiguous is not None else
              _name(chosen) or "no effect")
    log(f"selected: {answer}" + (" (the residual stays unexplained)" if unexplained else ""))
    suspects = []
    if ((not _members(chosen) or unexplained) and sel.ambiguous is None and problem.suspects
            and not too_few):
        suspects = _suspects(fitter, base, kinds, unexplained, log)
    members = list(sel.adopted)
    found = [a for a in members if learned.variable_of(a.effect) is None]
    learned_one = next((a for a in members if learned.variable_of(a.effect) is not None), None)
    without = None
    if learned_one is not None and final.discrepancy is not None:
        without = _fit_cached(fitter, final.effects, None, final)
        log(f"{learned.label(learned_one.effect)} adopted")
    partial = [] if explained else found
    found = found if explained else []
    if sel.ambiguous is not None and not found:
        identified = "ambiguous"
    else:
        identified = found[0].effect if found else "none"
    limits = (detection_limits(score_tests(fitter, final, kinds), fitter.library)
              if not too_few else {})
    result = Calibration(data, problem, base, scores, refits, qualifying, chosen, identified,
                         unexplained, gof, 0.0, suspects,
                         notes={"failed_refits": failed, "unit_warnings": slips},
                         selection=sel, discrepancy=learned_one, limits=limits, final=final,
                         adopted=found, partial=partial, prediction=prediction,
                         without_discrepancy=without)
    if dynamic is not None:
        result.check = model_check(problem, final, dynamic)
        c = result.check
        shown = (f"chi2 {c['chi2_fit']:.1f} on the fit points, {c['chi2_holdout']:.1f} held "
                 "out" if c["ok"] else "the model failed")
        log(f"check on the {c['model']} model: {shown} (fitted model {final.chi2_fit:.1f})")
        if not c["carries_over"]:
            log("warning: the fit does not carry over to the dynamic model; the quasi-static "
                "model's own error may have chosen the effects (refit with --model dynamic)")
    return result


def _suspects(fitter: Fitter, base: FitResult, kinds, unexplained: bool, log) -> list:
    """Every suspect scored at the base fit; the best refitted and named when
    something is left to explain and its score passes p = 0.001 over all
    suspects (module notes)."""
    problem = fitter.problem
    ranked = score_suspects(fitter, base, kinds)
    suspects = [Suspect(s.effect, float(problem.base0[s.effect]), s) for s in ranked]
    critical = chi2_isf(0.001 / len(ranked))
    if unexplained and ranked and ranked[0].statistic > critical:
        lead = suspects[0]
        try:
            lead.refit = fitter.fit_suspect(lead.name, np.asarray(base.notes["x"]),
                                            lead.score.first_step)
        except SolverError as err:  # a suspect that cannot be fitted is still named
            log(f"refit with {lead.name} free failed: {err}")
        log(f"suspect: {lead.sentence()}" if lead.plausible else lead.implausible())
    return suspects
