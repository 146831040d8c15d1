"""Learn the discrepancy the library lacks, then name it by its shape.

When the chosen model still leaves a residual above the noise, the fit is
repeated with the learned discrepancy k (1 + delta(x)) (`discrepancy`) over
each candidate variable x in turn, the model's effects refitted with it.  A
variable *cuts the held-out error* when its held-out chi-square falls by
more than `LR_CRITICAL` [1] and its held-out RMSE by at least `HELDOUT_CUT`
(with held-out data), and the penalised criterion
(`selection.criterion`, the discrepancy counted by its effective number of
coefficients) falls too; among those, the lowest criterion names the
variable.  Its delta is then described in words (`describe`): lobes and peak
angles for the bushing angle, the trend and its range for the others.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import jax.numpy as jnp
import numpy as np

from ..errors import InputError, SolverError
from . import discrepancy as disc
from .fit import FitResult, Fitter
from .selection import LR_CRITICAL, criterion

# A discrepancy names the missing variable only when it cuts the held-out
# RMSE by at least this share (a few per cent is a flexible fit, not a cause)
HELDOUT_CUT = 0.25


def unsupported(data, variable: str) -> str | None:
    """Why ``data`` cannot show a discrepancy in ``variable`` (None: they can)."""
    if variable not in disc.VARIABLES:
        return f"unknown variable; allowed: {', '.join(disc.VARIABLES)}"
    wear = [s for s in data.series if s.kind != "force"]
    if not wear:
        return "the dataset has no wear measurement (profile, volume or depth)"
    if variable == "angle":
        angles = sum(s.x.size for s in data.series if s.kind == "profile")
        if angles < 2 * disc.SIZES["angle"]:
            return ("it needs worn profiles over the bushing angle (at least "
                    f"{2 * disc.SIZES['angle']} points); the dataset has {angles}")
    if variable == "cycles":
        counts = {float(c) for s in wear for c in np.unique(s.cycle_counts)}
        if len(counts) < 2:
            return "it needs wear measured at two or more cycle counts"
    return None


def effective_coefficients(fit: FitResult) -> float:
    """Effective number of the discrepancy's coefficients: sum of l / (1 + l)
    over the eigenvalues l of the data's information on them in prior units."""
    lay = fit.notes["layout"]
    nd = fit.n_discrepancy
    j = fit.notes["jacobian"][:, lay.size - nd:]
    lam = np.linalg.eigvalsh(j.T @ j)
    return float(np.sum(lam / (1.0 + np.clip(lam, 0.0, None))))


@dataclass
class Trial:
    variable: str
    fit: FitResult | None
    criterion: float = math.inf
    cuts: bool = False
    failure: str | None = None

    @property
    def model(self) -> FitResult:
        """The fit (a trial that cuts the error always has one)."""
        assert self.fit is not None, f"discrepancy in {self.variable}: {self.failure}"
        return self.fit


@dataclass
class Search:
    """The discrepancy search at ``reference`` (the chosen model)."""

    reference: FitResult
    trials: list = field(default_factory=list)
    chosen: Trial | None = None
    skipped: dict = field(default_factory=dict)   # variable -> why the data cannot show it


def search(fitter: Fitter, reference: FitResult, data, variables, log=print) -> Search:
    """Fit the discrepancy over each of ``variables`` (module notes)."""
    out = Search(reference)
    base_crit = criterion(reference)
    for v in variables:
        why = unsupported(data, v)
        if why is not None:
            out.skipped[v] = why
            continue
        try:
            f = fitter.fit(reference.effects, start=reference, discrepancy=v)
        except SolverError as err:
            out.trials.append(Trial(v, None, failure=str(err)))
            log(f"discrepancy in {v}: {err}")
            continue
        f.notes["discrepancy_edf"] = effective_coefficients(f)
        crit = criterion(f)
        held = (reference.n_holdout == 0
                or (reference.chi2_holdout - f.chi2_holdout > LR_CRITICAL[1]
                    and f.rmse_holdout <= (1.0 - HELDOUT_CUT) * reference.rmse_holdout))
        cuts = held and crit < base_crit - LR_CRITICAL[1]
        out.trials.append(Trial(v, f, crit, cuts))
        log(f"discrepancy in {v}: chi2 {f.chi2_fit:.1f}, held-out RMSE "
            f"{f.rmse_holdout:.3g} sigma, {f.notes['discrepancy_edf']:.2g} effective "
            f"coefficients{' (cuts the error)' if cuts else ''}")
    cutting = [t for t in out.trials if t.cuts]
    out.chosen = min(cutting, key=lambda t: t.criterion, default=None)
    return out


def curve(variable: str, coefficients, cov, span: tuple):
    """(x in report units, delta, 1-sigma band) over ``span`` (SI)."""
    lo, hi = span
    if variable in ("pressure", "sliding_speed"):
        x = np.geomspace(lo, hi, 200)
    else:
        x = np.linspace(lo, hi, 361 if variable == "angle" else 200)
    total = hi if variable == "cycles" else 1.0
    phi = np.asarray(disc.basis(variable, jnp.asarray(x), total))
    d = phi @ np.asarray(coefficients)
    band = np.sqrt(np.clip(np.einsum("ij,jk,ik->i", phi, cov, phi), 0.0, None))
    scale = {"angle": 180.0 / math.pi, "pressure": 1e-6, "sliding_speed": 1e3,
             "cycles": 1.0, "depth": 1e3}[variable]
    return x * scale, d, band


def span(variable: str, data) -> tuple:
    """The range (SI) over which ``variable``'s delta is drawn and described."""
    if variable == "angle":
        return (0.0, 2 * math.pi)
    if variable == "pressure":
        return (1e5, 1e7)        # 0.1-10 MPa around the 1 MPa reference
    if variable == "sliding_speed":
        return (3e-3, 3e-1)      # 3-300 mm/s around the 30 mm/s reference
    if variable == "cycles":
        return (0.0, float(data.max_cycles))
    deepest = max((float(np.max(s.y)) for s in data.series if s.kind == "profile"),
                  default=disc.H_REF)
    return (0.0, max(deepest, 1e-6))


def worn_arc(data) -> tuple | None:
    """(first, last) bushing angle [deg] where the deepest measured profile
    stands 3 sigma above zero: where the data see the wear coefficient at
    all (None without profiles).  The arc may wrap through 0 deg."""
    prof = [s for s in data.series if s.kind == "profile"] if data is not None else []
    if not prof:
        return None
    deepest = max(prof, key=lambda s: float(np.max(s.y)))
    theta = np.degrees(np.mod(deepest.x, 2 * math.pi))
    order = np.argsort(theta)
    theta, worn = theta[order], (deepest.y > 3 * deepest.sigma)[order]
    if not worn.any():
        return None
    if worn.all():
        return (0.0, 360.0)
    # the longest run of worn angles around the circle
    start = int(np.flatnonzero(~worn)[0])
    rolled = np.roll(worn, -start)
    best, run, end = 0, 0, 0
    for i, w in enumerate(rolled):
        run = run + 1 if w else 0
        if run > best:
            best, end = run, i
    first = theta[(start + end - best + 1) % theta.size]
    last = theta[(start + end) % theta.size]
    return (float(first), float(last))


def _extrema(d):
    """(maxima, minima): indices of the interior local extrema of ``d``."""
    up = (d[1:-1] > d[:-2]) & (d[1:-1] >= d[2:])
    down = (d[1:-1] < d[:-2]) & (d[1:-1] <= d[2:])
    return np.flatnonzero(up) + 1, np.flatnonzero(down) + 1


def _angle_shape(c, data) -> dict:
    """Lobes and peak angles of an angle discrepancy, read where the data see
    it: over the worn arc (`worn_arc`) the spacing of delta's extrema gives
    the period (adjacent extrema of opposite kind are half a period apart);
    the highest peak inside the arc, repeated at that period, gives the
    peaks round the bushing."""
    lo, hi = worn_arc(data) or (0.0, 360.0)
    if hi < lo:
        hi += 360.0
    x = np.linspace(lo, hi, max(int(4 * (hi - lo)), 16))
    d = np.asarray(disc.basis("angle", jnp.asarray(np.radians(x)))) @ c
    maxima, minima = _extrema(d)
    extrema = sorted([(x[i], 1) for i in maxima] + [(x[i], -1) for i in minima])
    gaps = [b[0] - a[0] for a, b in zip(extrema, extrema[1:]) if a[1] != b[1]]
    if gaps:
        lobes = max(1, int(round(360.0 / (2.0 * float(np.median(gaps))))))
    else:  # no turn inside the arc: the largest harmonic
        lobes = int(np.argmax(np.hypot(c[0::2], c[1::2]))) + 1
    top = float(x[maxima[int(np.argmax(d[maxima]))]]) if maxima.size else float(x[np.argmax(d)])
    peaks = sorted((top + k * 360.0 / lobes) % 360.0 for k in range(lobes))
    a = float(np.max(np.abs(d)))
    listed = ", ".join(f"{v:.0f}" for v in peaks[:-1]) + \
        (f" and {peaks[-1]:.0f}" if len(peaks) > 1 else f"{peaks[-1]:.0f}")
    where = ("the whole bore" if hi - lo >= 360.0 else
             f"the worn arc {lo % 360:.0f}-{hi % 360:.0f} deg")
    return {"worn_arc_deg": [lo, hi], "lobes": lobes, "peaks_deg": peaks, "amplitude": a,
            "shape": f"{lobes} lobe{'s' if lobes > 1 else ''}, peak"
                     f"{'s' if len(peaks) > 1 else ''} at {listed} deg, amplitude "
                     f"+-{100 * a:.0f} % (read over {where})"}


def describe(variable: str, coefficients, cov, data) -> dict:
    """The discrepancy's shape in words and numbers."""
    c = np.asarray(coefficients)
    x, d, band = curve(variable, c, cov, span(variable, data))
    unit = disc.UNITS[variable]
    out: dict = {"variable": variable, "coefficients": c.tolist(),
                 "coefficients_std": np.sqrt(np.clip(np.diag(cov), 0.0, None)).tolist()}
    if variable == "angle":
        out.update(_angle_shape(c, data))
        return out
    i_max, i_min = int(np.argmax(d)), int(np.argmin(d))
    rising = d[-1] > d[0]
    interior = 0 < (i_max if rising else i_min) < len(d) - 1 and \
        abs(d[i_max] - max(d[0], d[-1])) > 0.25 * (np.max(d) - np.min(d))

    def fmt(v):
        return f"{v:.3g} {unit}"

    if interior:
        words = f"peaks at {fmt(x[i_max])} ({100 * d[i_max]:+.0f} %)"
    else:
        words = (f"{'rises' if rising else 'falls'} from {100 * d[0]:+.0f} % at {fmt(x[0])} "
                 f"to {100 * d[-1]:+.0f} % at {fmt(x[-1])}")
    out.update(shape=words, amplitude=float(np.max(np.abs(d))))
    return out


def check_variables(data, variables) -> None:
    """Refuse (InputError) a requested variable the dataset cannot show."""
    for v in variables:
        why = unsupported(data, v)
        if why is not None:
            raise InputError(f"{data.path}: discrepancy variable {v!r}: {why}")
