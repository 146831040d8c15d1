"""Does a fitted model predict?  Forward chaining inside the fit window.

A model whose fit residual is at the noise may still not predict: a library
effect can bend to fit a few inspections and miss the next one, where a
cause outside the library would not.  So a candidate model is refitted on
the fit points measured before the fit window's last inspection (the force
trace of the first cycle included) and asked to predict that inspection:

    Q = r^T (I + J C J^T)^-1 r,

r the residuals of the last inspection's points at the earlier points' fit
(units of each point's stated noise), J their derivatives by the fitted
unknowns and C those unknowns' Gauss-Newton covariance from the earlier
points: the predictive distribution of the inspection under the model,
parameter uncertainty included.  Q is chi-square with as many degrees of
freedom as the inspection has points when the model is right; the model
*predicts* when Q stays within the goodness-of-fit limit n + 4 sqrt(2 n)
(`identify.GOF_SIGMAS`).  Only fit points take part: the held-out
measurements are read after the choice.  (One-step-ahead forward chaining,
the prequential principle of Dawid, J. R. Stat. Soc. A 147 (1984) 278.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolverError
from .fit import FitResult, Fitter

GOF_SIGMAS = 4.0   # as `identify.GOF_SIGMAS`
# the earlier points must leave this many degrees of freedom beyond the
# model's unknowns, else there is nothing to predict from
MIN_DOF = 2


@dataclass
class PredictiveCheck:
    """The prediction of the fit window's last inspection (``cycles``) from
    the fit points before it."""

    cycles: float
    statistic: float      # Q (module notes)
    n: int                # points of the inspection
    rmse: float           # RMS residual of the inspection at the earlier fit [sigma]
    failure: str | None = None
    # -2 ln of the inspection's predictive density (up to a constant): Q + ln
    # det(I + J C J^T), the prequential score (lower predicts better)
    log_score: float = math.inf

    @property
    def limit(self) -> float:
        return self.n + GOF_SIGMAS * math.sqrt(2 * self.n)

    @property
    def predicts(self) -> bool:
        return self.failure is None and self.statistic <= self.limit

    def sentence(self) -> str:
        if self.failure is not None:
            return (f"its refit on the points before {self.cycles:g} cycles failed "
                    f"({self.failure}); not an explanation")
        verdict = "predicts" if self.predicts else "does not predict"
        return (f"{verdict} the inspection at {self.cycles:g} cycles from the earlier fit points "
                f"(Q {self.statistic:.1f} on {self.n} points, limit {self.limit:.1f}; "
                f"RMS {self.rmse:.2f} sigma; predictive score {self.log_score:.1f})")

    def entry(self) -> dict:
        return {"cycles": self.cycles, "statistic": self.statistic, "points": self.n,
                "limit": self.limit, "rmse": self.rmse, "predicts": self.predicts,
                "log_score": self.log_score, "failure": self.failure}


def split(fitter: Fitter, fit: FitResult) -> tuple | None:
    """(earlier rows, the last inspection's rows, its cycle count) of ``fit``'s
    fit points, or None when the fit window has a single wear inspection."""
    p = fitter.problem
    rows = np.asarray(fit.notes.get("rows", ~p.holdout), bool)
    kinds = np.asarray(p.kind_of_point)
    wear = kinds != "force"
    counts = np.asarray(p.cycles_of_point, float)
    seen = np.unique(counts[rows & wear])
    if seen.size < 2:
        return None
    # the last inspection: the last fitted profile's (weighings after it go
    # with it), else the last fitted wear measurement's
    profiles = np.unique(counts[rows & (kinds == "profile")])
    last = float(profiles[-1]) if profiles.size >= 2 else float(seen[-1])
    later = rows & (counts >= last)
    earlier = rows & ~later
    if int(earlier.sum()) < fit.notes["layout"].size + MIN_DOF:
        return None
    return earlier, later & wear, last


def forward_check(fitter: Fitter, fit: FitResult, data=None) -> PredictiveCheck | None:
    """``fit``'s model refitted on the earlier fit points predicts the last
    fit inspection (module notes); None when there is nothing to check."""
    del data  # the split is the problem's
    parts = split(fitter, fit)
    if parts is None:
        return None
    earlier, later, last = parts
    try:
        f = fitter.fit(fit.effects, start=fit, discrepancy=fit.discrepancy, rows=earlier)
    except SolverError as err:
        return PredictiveCheck(last, math.inf, int(later.sum()), math.inf, str(err))
    lay = f.notes["layout"]
    jac = fitter.linearise(f.notes["v"], lay.tangents).jac[later]
    r = f.residual[later]
    cov = np.asarray(f.notes["cov"])
    # (I + J C J^T)^-1 by Woodbury: I - J (C^-1 + J^T J)^-1 J^T, C^-1 from its
    # pseudo-inverse (a direction the earlier points do not see has no
    # information and an unbounded predictive spread)
    precision = np.linalg.pinv(cov)
    inner = precision + jac.T @ jac
    jr = jac.T @ r
    q = float(r @ r - jr @ np.linalg.lstsq(inner, jr, rcond=None)[0])
    # ln det(I + J C J^T) = ln det(I + R^T J^T J R), R R^T = C (a small matrix)
    lam, vec = np.linalg.eigh(0.5 * (cov + cov.T))
    root = vec * np.sqrt(np.clip(lam, 0.0, None))
    logdet = float(np.linalg.slogdet(np.eye(root.shape[1]) + root.T @ (jac.T @ jac) @ root)[1])
    return PredictiveCheck(last, q, int(later.sum()), float(np.sqrt(np.mean(r ** 2))),
                           log_score=q + logdet)
