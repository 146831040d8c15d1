"""Score tests and detection limits of the library's effects at a fitted model.

With the fitted model's residual r and the Jacobian J_b of everything it
fits (fit points only), the efficient score test of effect e at zero
strength uses g = J_e^T r and the efficient information

    I_e = J_e^T J_e - J_e^T J_b (J_b^T J_b)^-1 J_b^T J_e,

S_e = g^2 / I_e is chi-square(1) under "no effect"; it is the chi-square drop
a first Gauss-Newton step in s_e would give.  An effect whose strength is
bounded below by zero scores 0 when the residual asks for a negative
strength.  An effect with a shape is scored at `SHAPE_GRID` points of its
prior (the shape is not identified at zero strength): its statistic is the
largest, its p-value Bonferroni-corrected for the grid.

The same information gives each effect's **detection limit**: the strength
that would have stood `DETECTION_SIGMAS` standard deviations from zero,
DETECTION_SIGMAS / sqrt(I_e), at the shape where the data are most
sensitive to it.  "No effect" then reads "none above these limits".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .effects import LIBRARY, Library

# Shapes at which a shaped effect is scored: ln(shape / default) in units of
# its prior spread (+-1.5 sigma: a factor 32 either way for a decade prior)
SHAPE_GRID = (-1.5, -0.75, 0.0, 0.75, 1.5)
# A detected effect stands this many standard deviations from zero (the
# adoption rule of `identify`, `STRENGTH_SIGMAS`)
DETECTION_SIGMAS = 3.0


@dataclass
class Score:
    effect: str
    statistic: float     # S_e (chi-square(1) under "no effect")
    first_step: float    # the Gauss-Newton strength step -g / I
    p_value: float
    log_shape: float = 0.0   # ln(shape / default) where the statistic was largest
    by_kind: dict = field(default_factory=dict)  # share of g per series kind
    information: float = 0.0   # the largest efficient information over the shapes
    limit_log_shape: float = 0.0  # ln(shape / default) where it is largest

    @property
    def detection_limit(self) -> float:
        """The smallest strength these data would detect (module notes)."""
        if not self.information > 0.0:
            return math.inf
        return DETECTION_SIGMAS / math.sqrt(self.information)


def chi2_sf(x: float) -> float:
    """P(chi-square(1) > x) = erfc(sqrt(x / 2))."""
    return math.erfc(math.sqrt(max(x, 0.0) / 2.0))


def chi2_isf(p: float) -> float:
    """x with P(chi-square(1) > x) = p (bisection on `chi2_sf`)."""
    lo, hi = 0.0, 200.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if chi2_sf(mid) > p else (lo, mid)
    return 0.5 * (lo + hi)


def efficient_score(name, j, jb, r, lower, kinds) -> Score:
    """The efficient score test of column ``j`` against the fitted columns ``jb``."""
    g = float(j @ r)
    cross = jb.T @ j
    info = (float(j @ j - cross @ np.linalg.lstsq(jb.T @ jb, cross, rcond=None)[0])
            if jb.size else float(j @ j))
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
    return Score(name, stat, step, chi2_sf(stat), by_kind=share, information=info)


def score_tests(fitter, fit, kinds, exclude=()) -> list[Score]:
    """Every effect not in ``exclude`` (nor fitted by ``fit``) scored at the
    fitted model ``fit`` (module notes), best first."""
    p = fitter.problem
    rows = ~p.holdout
    x = np.asarray(fit.notes["x"])
    fitted = tuple(getattr(fit, "effects", ())) + tuple(exclude)
    plain = not getattr(fit, "effects", ()) and getattr(fit, "discrepancy", None) is None
    if plain:
        jb, _, _ = fitter.parameter_jacobian(x, names=())
        jb = jb[rows]
        v = None
    else:
        jb, v = fit.notes["jacobian"], fit.notes["v"]
    r = fit.residual[rows]
    best: dict[str, Score] = {}
    info: dict[str, tuple[float, float]] = {}
    lib = fitter.library
    log_std = lib.log_std
    for g in SHAPE_GRID:
        je = (fitter.effect_jacobian(x, log_std * g) if v is None
              else fitter.effect_jacobian(x, log_std * g, v))[rows]
        for k, eff in enumerate(lib.effects):
            if eff.name in fitted or (eff.shape is None and g != 0.0):
                continue
            s = efficient_score(eff.name, je[:, k], jb, r, eff.lower, kinds[rows])
            s.log_shape = float(log_std[k] * g)
            if s.information > info.get(eff.name, (-1.0, 0.0))[0]:
                info[eff.name] = (s.information, s.log_shape)
            if eff.name not in best or s.statistic > best[eff.name].statistic:
                best[eff.name] = s
    for name, s in best.items():
        s.information, s.limit_log_shape = info[name]
        if lib.effect(name).shape is not None:  # the grid's largest: Bonferroni
            s.p_value = min(1.0, len(SHAPE_GRID) * s.p_value)
    return sorted(best.values(), key=lambda s: -s.statistic)


def score_suspects(fitter, base, kinds) -> list[Score]:
    """Score tests of the problem's suspects (rig parameters on a log scale)."""
    p = fitter.problem
    rows = ~p.holdout
    jb, ju, _ = fitter.parameter_jacobian(np.asarray(base.notes["x"]), names=p.suspects)
    r = base.residual[rows]
    out = [efficient_score(n, ju[rows, k], jb[rows], r, -math.inf, kinds[rows])
           for k, n in enumerate(p.suspects)]
    return sorted(out, key=lambda s: -s.statistic)


def detection_limits(scores: list[Score], library: Library = LIBRARY) -> dict:
    """{effect: {"strength": limit, "shape": SI shape where it holds or None}}."""
    out = {}
    for s in scores:
        eff = library.effect(s.effect)
        shape = (eff.shape.default * math.exp(s.limit_log_shape)) if eff.shape else None
        limit = s.detection_limit
        out[s.effect] = {"strength": limit if math.isfinite(limit) else None, "shape": shape}
    return out
