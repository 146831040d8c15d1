"""What a calibration says about the future: the life with its band, and the
inspection that would teach the most.

**Life.**  The chosen model (effects and discrepancy included) is run past
the campaign, to `horizon`, on the quasi-static model's grid extended beyond
the fit window (`quasi_static.cycle_grid`), at every posterior draw
(`posterior`): the cycle count at which the maximum wear depth reaches the
limit, and the depth at the horizon, each with the draws' 90 % band.  A draw
that does not reach the limit by the run's end is censored there (the band
then reads "beyond").  When the answer is "A or B", the data have not chosen
between two models, so neither's band alone is the life's: both are run,
each on its own posterior's draws, and the draws are pooled with the models'
weights exp(-criterion / 2), normalised (Bayesian model averaging with BIC
weights: Hoeting, Madigan, Raftery and Volinsky, Stat. Sci. 14 (1999) 382;
for two discrepancies that fit alike, by their fits: `identify.second_weight`).

**The next measurement.**  Over the cycle counts after the dataset's last
inspection, up to the horizon, each kind of inspection the dataset holds (a
worn profile at the dataset's angles and precision, a weighing at its
precision) is scored by what it would teach, on the model linearised at
the fit (Gauss-Newton: the inspection's rows J_m / sigma added to the
information):

* when the answer is "A or B", the separation it would give them: its
  predictions under the two models apart, in units of the noise and both
  models' predictive spreads (for a profile, the root of the sum over its
  points); the best is the one that settles the question;
* otherwise the share by which it would narrow the life's band (its
  standard deviation through the life's derivative, g^T C g, before and
  after).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, SolverError
from .fit import FitResult, Fitter, ModelSettings, Problem
from .model import Observation
from .posterior import BAND, Posterior, _weighted_quantile
from .quasi_static import QuasiStaticRigHistory

# Candidate cycle counts of the next inspection: this many, evenly over
# (last inspection, horizon] (with the horizon itself)
CANDIDATES = 24
# The life run goes this far past the first estimate of the life (the wear
# rate may fall as the bore conforms; a linear estimate comes early)
LIFE_MARGIN = 2.5
# Samples of the maximum depth per run (the crossing is interpolated)
DEPTH_SAMPLES = 400
# Posterior draws run to the life (resampled by weight): the 5 % and 95 %
# quantiles from 64 draws carry a Monte Carlo error of a few per cent of the
# band, well inside its width
FORECAST_DRAWS = 64


@dataclass(frozen=True)
class Outlook:
    """What is asked of the posterior: the method (`posterior.METHODS`), the
    depth limit of the life [m] (None: the bushing wall) and the horizon
    [cycles] (None: twice the last inspection)."""

    method: str = "laplace"
    limit: float | None = None
    horizon: float | None = None

    def resolved(self, data, problem: Problem) -> tuple[float | None, float]:
        """(limit, horizon) with the defaults filled in, checked (`check_request`)."""
        wall = default_limit(problem)
        check_request(data, self.limit, self.horizon, wall)
        limit = self.limit if self.limit is not None else wall
        horizon = self.horizon if self.horizon is not None else 2.0 * float(data.max_cycles)
        return limit, horizon


# What a calibration looks ahead to by default (the life to the dataset's or
# mechanism's limit, the posterior, the next measurement)
DEFAULT_OUTLOOK = Outlook()


@dataclass
class Forecast:
    limit: float                 # m, the maximum wear depth that ends the life
    horizon: float               # cycles: the depth is forecast here, inspections up to it
    life: dict
    depth: dict
    next_measurement: dict | None
    # the maximum depth's median and band over the run (cycles, q05, q50, q95) [m]
    trajectory: tuple = ()
    # each candidate inspection's score: {kind: (cycles, score)}
    scores: dict = dataclasses.field(default_factory=dict)

    def entry(self) -> dict:
        return {"limit_mm": self.limit * 1e3, "horizon_cycles": self.horizon,
                "life": self.life, "depth_at_horizon": self.depth,
                "next_measurement": self.next_measurement}


def check_request(data, limit: float | None, horizon: float | None, wall: float | None) -> None:
    """Refuse (InputError) a horizon before the last inspection and a limit
    beyond the bushing wall (or not positive)."""
    last = float(data.max_cycles)
    if horizon is not None and not (math.isfinite(horizon) and horizon > last):
        raise InputError(f"--horizon {horizon:g}: the horizon must lie beyond the dataset's last "
                         f"inspection ({last:g} cycles); allowed: > {last:g}")
    if limit is not None:
        if not (math.isfinite(limit) and limit > 0):
            raise InputError(f"--limit {limit * 1e3:g} mm: allowed a depth > 0")
        if wall is not None and limit > wall:
            raise InputError(f"--limit {limit * 1e3:g} mm: deeper than the bushing wall "
                             f"({wall * 1e3:g} mm); allowed: 0 < limit <= {wall * 1e3:g} mm")


class _Extended:
    """The problem's model run to ``cycles`` with observations of the maximum
    depth on the run's grid and of the candidate inspections."""

    def __init__(self, fitter: Fitter, cycles: float, candidates: np.ndarray, angles, data):
        p = fitter.problem
        model = p.model
        if not isinstance(model, QuasiStaticRigHistory):  # the dynamic model: its twin
            model = ModelSettings(n_theta=model.n_theta).build(
                float(data.max_cycles), (), float(data.fit_cycles))
        assert isinstance(model, QuasiStaticRigHistory)
        model = dataclasses.replace(model, cycles=float(cycles),
                                    checkpoints=tuple(sorted({*model.checkpoints,
                                                              *map(float, candidates)})))
        self.grid = np.asarray(model.grid, float)
        depth_at = np.unique(np.concatenate([self.grid[1:], np.linspace(
            self.grid[1], self.grid[-1], DEPTH_SAMPLES)]))
        obs = [Observation("max_depth", depth_at)]
        self.depth_cycles = depth_at
        self.parts = {"depth": slice(0, depth_at.size)}
        at = depth_at.size
        obs.append(Observation("volume", np.asarray(candidates, float)))
        self.parts["volume"] = slice(at, at + candidates.size)
        at += candidates.size
        self.profile_parts = []
        if angles is not None:
            for n in candidates:
                obs.append(Observation("profile", np.asarray(angles, float), cycles=float(n)))
                self.profile_parts.append(slice(at, at + len(angles)))
                at += len(angles)
        size = at
        problem = dataclasses.replace(
            p, model=model, observations=tuple(obs), y=np.zeros(size), sigma=np.ones(size),
            holdout=np.zeros(size, bool), series_of_point=np.zeros(size, int),
            cycles_of_point=np.zeros(size), kinds=("forecast",))
        self.fitter = Fitter(problem)

    def predictions(self, v) -> np.ndarray:
        return self.fitter.residuals(v)

    def linearised(self, fit: FitResult):
        lay = fit.notes["layout"]
        lin = self.fitter.linearise(np.asarray(fit.notes["v"]), lay.tangents)
        return lin.r, lin.jac


def _crossing(cycles: np.ndarray, depth: np.ndarray, limit: float) -> float:
    """The first cycle count where ``depth`` reaches ``limit`` (linear between
    samples), inf when it does not."""
    above = np.flatnonzero(depth >= limit)
    if above.size == 0:
        return math.inf
    i = int(above[0])
    if i == 0:
        return float(cycles[0])
    d0, d1 = depth[i - 1], depth[i]
    return float(cycles[i - 1] + (limit - d0) / (d1 - d0) * (cycles[i] - cycles[i - 1]))


def _band(values: np.ndarray, w: np.ndarray, end: float = math.inf) -> dict:
    """Median and `BAND` of weighted ``values``; a value beyond the run (inf)
    stands at the run's ``end``, a lower bound, and its share is reported."""
    lo, hi = 0.5 * (1 - BAND), 0.5 * (1 + BAND)
    beyond = np.isposinf(values)
    capped = np.where(beyond, end, values)
    known = np.isfinite(capped)
    if not known.any():
        return {"median": math.nan, "q05": math.nan, "q95": math.nan,
                "beyond_run": float(np.sum(w[beyond])), "band": BAND}
    cw = w[known] / np.sum(w[known])
    return {"median": _weighted_quantile(capped[known], cw, 0.5),
            "q05": _weighted_quantile(capped[known], cw, lo),
            "q95": _weighted_quantile(capped[known], cw, hi),
            "beyond_run": float(np.sum(w[beyond])), "band": BAND}


def _resampled(post: Posterior, size: int) -> np.ndarray:
    """``size`` of the posterior's draws, equally weighted: systematic
    resampling by their weights (Kitagawa, J. Comput. Graph. Stat. 5 (1996) 1),
    so that each forecast run stands for the same share of the posterior."""
    w = np.asarray(post.weights, float)
    if len(w) <= size and np.allclose(w, w[0]):
        return post.z
    edges = np.cumsum(w / w.sum())
    u = (np.arange(size) + 0.5) / size
    return post.z[np.minimum(np.searchsorted(edges, u), len(w) - 1)]


def _first_estimate(fitter: Fitter, fit: FitResult, limit: float) -> float:
    """A first life estimate: the deepest fitted profile carried on at the rate
    between the last two fitted profiles (late: past any run-in), else at its
    mean rate."""
    p = fitter.problem
    rows = np.asarray(fit.notes["rows"], bool) & np.asarray(p.kind_of_point == "profile")
    window = float(getattr(p.model, "fit_window", p.model.cycles))
    if not rows.any():
        return 10.0 * window
    counts = np.asarray(p.cycles_of_point)[rows]
    seen = np.unique(counts)
    deepest = [float(np.max(fit.prediction[rows][counts == c])) for c in seen]
    if seen.size >= 2 and deepest[-1] > deepest[-2]:
        rate = (deepest[-1] - deepest[-2]) / (seen[-1] - seen[-2])
    else:
        rate = deepest[-1] / seen[-1] if deepest[-1] > 0 else 0.0
    if not rate > 0:
        return 10.0 * window
    return float(seen[-1] + max(limit - deepest[-1], 0.0) / rate)


def inspection_candidates(last: float, horizon: float) -> np.ndarray:
    """The cycle counts at which the next inspection is scored: `CANDIDATES`
    of them, evenly over (``last``, ``horizon``]: the next inspection of this
    bushing comes after its last one."""
    step = (horizon - last) / CANDIDATES
    return last + step * np.arange(1, CANDIDATES + 1)


def forecast(fitter: Fitter, pool: Sequence[tuple[Posterior, float]], data, limit: float,
             horizon: float, alternatives: tuple | None = None) -> Forecast:
    """The life to ``limit`` and the depth at ``horizon`` with their bands, and
    the next measurement (module notes).  ``pool``: (posterior, weight) of
    each model the answer holds (`Calibration.pool`: the chosen model's
    alone, or both of an "A or B" answer), their draws pooled by the weights;
    ``alternatives``: the two fits of an "A or B" answer."""
    fit = pool[0][0].fit
    estimate = _first_estimate(fitter, fit, limit)
    end = max(horizon, min(LIFE_MARGIN * estimate, 1e3 * horizon))
    candidates = inspection_candidates(float(data.max_cycles), horizon)
    profiles = [s for s in data.series if s.kind == "profile"]
    angles = np.asarray(profiles[-1].x, float) if profiles else None
    ext = _Extended(fitter, end, candidates, angles, data)
    lives, depths, runs, shares = [], [], [], []
    n = ext.depth_cycles
    for p, weight in pool:
        lay = p.fit.notes["layout"]
        draws = _resampled(p, max(2, round(weight * FORECAST_DRAWS)))
        for zi in draws:
            d = ext.predictions(lay.pack(zi))[ext.parts["depth"]]
            runs.append(d)
            lives.append(_crossing(n, d, limit))
            depths.append(float(np.interp(horizon, n, d)))
            shares.append(weight / len(draws))
    runs_ = np.asarray(runs)
    ok = np.all(np.isfinite(runs_), axis=1)   # a draw whose run failed stands for nothing
    if not ok.any():
        raise SolverError("forecast: the model fails on every posterior draw past the campaign")
    runs_ = runs_[ok]
    w = np.asarray(shares)[ok] / np.sum(np.asarray(shares)[ok])
    trajectory = (n, *(np.array([_weighted_quantile(runs_[:, j], w, q)
                                 for j in range(n.size)])
                       for q in (0.5 * (1 - BAND), 0.5, 0.5 * (1 + BAND))))
    life = _band(np.asarray(lives)[ok], w, float(n[-1]))
    life.update(run_to_cycles=float(n[-1]), failed_draws=int((~ok).sum()))
    depth = {k: (v * 1e3 if k in ("median", "q05", "q95") else v)
             for k, v in _band(np.asarray(depths)[ok], w).items()}
    depth["unit"] = "mm"
    scores: dict = {}
    nxt = _next_measurement(ext, fit, data, candidates, limit, alternatives, scores, horizon)
    return Forecast(limit, horizon, life, depth, nxt, trajectory, scores)


def _kinds(data) -> dict:
    """{kind: sigma} of the inspections the dataset holds (profile, weighing)."""
    out: dict[str, float] = {}
    for s in data.series:
        if s.kind == "profile":
            out["profile"] = min(out.get("profile", math.inf), float(s.sigma))
        elif s.kind == "volume":
            out["weighing"] = min(out.get("weighing", math.inf), float(s.sigma))
    return out


def _rows(ext: _Extended, kind: str, k: int) -> slice:
    return (slice(ext.parts["volume"].start + k, ext.parts["volume"].start + k + 1)
            if kind == "weighing" else ext.profile_parts[k])


def _next_measurement(ext: _Extended, fit: FitResult, data, candidates, limit,
                      alternatives, scores: dict, horizon: float = 0.0) -> dict | None:
    """The best inspection (module notes); each candidate's score in ``scores``."""
    kinds = _kinds(data)
    if not kinds:
        return None
    if alternatives is not None:
        return _separating(ext, alternatives, candidates, kinds, scores)
    pred, jac = ext.linearised(fit)
    cov = np.asarray(fit.notes["cov"])
    n = ext.depth_cycles
    d = pred[ext.parts["depth"]]
    life = _crossing(n, d, limit)
    target = "life"
    if math.isfinite(life):
        i = int(np.searchsorted(n, life))
        i = min(max(i, 1), n.size - 1)
        frac = (life - n[i - 1]) / (n[i] - n[i - 1])
        dd_dz = (1 - frac) * jac[ext.parts["depth"]][i - 1] + frac * jac[ext.parts["depth"]][i]
        slope = (d[i] - d[i - 1]) / (n[i] - n[i - 1])
        g = -dd_dz / slope                    # d life / dz
    else:  # the fit's own run does not reach the limit: the depth at the horizon instead
        target = "depth"
        i = int(np.argmin(np.abs(n - horizon)))
        g = jac[ext.parts["depth"]][i]
    var0 = float(g @ cov @ g)
    if not var0 > 0:
        return None
    precision = np.linalg.pinv(cov)
    best = None
    for kind, sigma in kinds.items():
        gains = []
        for k, cycles in enumerate(candidates):
            rows = _rows(ext, kind, k)
            jm = jac[rows] / sigma
            var1 = float(g @ np.linalg.pinv(precision + jm.T @ jm) @ g)
            gain = 1.0 - math.sqrt(max(var1, 0.0) / var0)
            gains.append(gain)
            if best is None or gain > best[0] + 1e-12:
                best = (gain, kind, float(cycles))
        scores[kind] = (np.asarray(candidates, float), np.asarray(gains))
    assert best is not None
    gain, kind, cycles = best
    before, after = math.sqrt(var0), math.sqrt(var0) * (1.0 - gain)
    what = "worn profile" if kind == "profile" else "weighing"
    if target == "life":
        return {"kind": kind, "cycles": cycles, "life_band_reduction": gain,
                "life_std_cycles": before, "life_std_after_cycles": after,
                "sentence": (f"a {what} at about {cycles:,.0f} cycles would narrow the life's "
                             f"band most: its 1-sigma from {before:,.0f} to {after:,.0f} "
                             "cycles (linearised)")}
    return {"kind": kind, "cycles": cycles, "depth_band_reduction": gain,
            "depth_std_mm": 1e3 * before, "depth_std_after_mm": 1e3 * after,
            "sentence": (f"a {what} at about {cycles:,.0f} cycles would narrow the band of the "
                         f"depth at {horizon:,.0f} cycles most: its 1-sigma from "
                         f"{1e3 * before:.3g} to {1e3 * after:.3g} mm (linearised; the fit's "
                         "own run does not reach the limit)")}


def _separating(ext: _Extended, alternatives, candidates, kinds, scores: dict) -> dict:
    a, b = alternatives
    pa, ja = ext.linearised(a)
    pb, jb = ext.linearised(b)
    va = np.einsum("ij,jk,ik->i", ja, np.asarray(a.notes["cov"]), ja)
    vb = np.einsum("ij,jk,ik->i", jb, np.asarray(b.notes["cov"]), jb)
    best = None
    for kind, sigma in kinds.items():
        seps = []
        for k, cycles in enumerate(candidates):
            rows = _rows(ext, kind, k)
            gap = pa[rows] - pb[rows]
            spread = sigma ** 2 + va[rows] + vb[rows]
            sep = math.sqrt(float(np.sum(gap ** 2 / spread)))
            seps.append(sep)
            if best is None or sep > best[0]:
                best = (sep, kind, float(cycles))
        scores[kind] = (np.asarray(candidates, float), np.asarray(seps))
    assert best is not None
    sep, kind, cycles = best
    what = "worn profile" if kind == "profile" else "weighing"
    return {"kind": kind, "cycles": cycles, "expected_separation_sigma": sep,
            "sentence": f"a {what} at about {cycles:,.0f} cycles would separate them best: "
                        f"{sep:.2g} sigma of its noise and the two models' spread"
                        + ("" if sep >= 3 else " (not enough to settle it: below 3 sigma)")}


def default_limit(problem: Problem) -> float | None:
    """The bushing wall, where the dataset's model has one: the joint is worn
    through."""
    wall = problem.base0.get("wall")
    return None if wall is None else float(wall)
