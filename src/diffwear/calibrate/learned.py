"""The learned discrepancy as a candidate cause, and its shape in words.

The wear coefficient's multiplicative discrepancy k (1 + delta(x))
(`discrepancy`) over a variable x is offered to the forward selection of
`identify` beside the library's effects, on the same footing: it is scored
at the model so far (a score test of its coefficients together, chi-square
with as many degrees of freedom as the data determine), refitted when the
score asks for it, and adopted by the same rule on the fit data alone (its
chi-square drop beyond the p = 0.001 critical value for its effective
number of coefficients, `effective_coefficients`, and the penalised
criterion).  An adopted discrepancy is described in words (`describe`):
lobes and peak angles for the bushing angle, the trend and its range for
the others.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from ..errors import InputError
from . import chi2
from .discrepancy import BushingAngle
from .effects import LIBRARY, Library
from .fit import FitResult, Fitter

# A discrepancy is refitted when its score test passes this p-value (a
# cheap screen: its refit costs several of an effect's)
SCREEN_P = 0.01
# The prefix of a discrepancy's name among the candidates
PREFIX = "discrepancy:"


def candidate(variable: str) -> str:
    """The candidate name of the discrepancy over ``variable``."""
    return PREFIX + variable


def variable_of(name: str) -> str | None:
    """The discrepancy variable of candidate ``name`` (None: a library effect)."""
    return name[len(PREFIX):] if name.startswith(PREFIX) else None


def label(name: str, library: Library = LIBRARY) -> str:
    """A candidate in words: "run_in", "discrepancy in the bushing angle"."""
    v = variable_of(name)
    if v is None:
        return name
    words = library.variable(v).words if v in library.variable_names else v.replace("_", " ")
    return f"discrepancy in {words}"


def unsupported(data, variable: str, library: Library = LIBRARY) -> str | None:
    """Why ``data`` cannot show a discrepancy in ``variable`` (None: they can)."""
    if variable not in library.variable_names:
        return f"unknown variable; allowed: {', '.join(library.variable_names)}"
    if not any(s.kind != "force" for s in data.series):
        return "the dataset has no wear measurement (profile, volume or depth)"
    return library.variable(variable).unsupported(data)


def effective_coefficients(fit: FitResult) -> float:
    """Effective number of the discrepancy's coefficients: sum of l / (1 + l)
    over the eigenvalues l of the data's information on them in prior units."""
    lay = fit.notes["layout"]
    nd = fit.n_discrepancy
    j = fit.notes["jacobian"][:, lay.size - nd:]
    lam = np.linalg.eigvalsh(j.T @ j)
    return float(np.sum(lam / (1.0 + np.clip(lam, 0.0, None))))


def score(fitter: Fitter, fit: FitResult, variable: str, jb: np.ndarray, v) -> dict:
    """Score test of the discrepancy over ``variable`` at ``fit`` (every
    coefficient at zero): S = g^T I^+ g, g = J_d^T r, I the efficient
    information of the coefficients against the fitted columns ``jb``
    (fit rows), chi-square with rank(I) degrees of freedom under "no
    discrepancy"."""
    rows = fit.notes.get("rows", ~fitter.problem.holdout)
    lay = fitter.layout(fit.effects, variable)
    nd = fitter.library.variable(variable).size
    jd = fitter.linearise(v, lay.tangents[-nd:]).jac[rows]
    r = fit.residual[rows]
    g = jd.T @ r
    cross = jb.T @ jd
    info = jd.T @ jd - (cross.T @ np.linalg.lstsq(jb.T @ jb, cross, rcond=None)[0]
                        if jb.size else 0.0)
    lam, vec = np.linalg.eigh(0.5 * (info + info.T))
    # a direction the fitted columns nearly span carries no information of its
    # own (its g is round-off): counted out at 1e-6 of the columns' own scale
    scale = float(np.max(np.linalg.eigvalsh(jd.T @ jd)))
    keep = lam > 1e-6 * max(scale, 1e-300)
    if not keep.any():
        return {"statistic": 0.0, "dof": 0, "p_value": 1.0}
    proj = vec[:, keep].T @ g
    stat = float(np.sum(proj ** 2 / lam[keep]))
    dof = int(keep.sum())
    return {"statistic": stat, "dof": dof, "p_value": chi2.sf(stat, dof)}


def curve(variable: str, coefficients, cov, span: tuple, total_cycles: float | None = None,
          log_k_per_coefficient=None, library: Library = LIBRARY):
    """(x in report units, delta, 1-sigma band) over ``span`` (SI), delta
    relative to the identified k: (1 + phi c) exp(b.c) - 1, b the move of ln k
    per coefficient (`fit.identified_k`; None: none); the band by
    the delta method.  ``total_cycles``: the cycle-count basis's time scale
    (default the span's end)."""
    var = library.variable(variable)
    lo, hi = span
    if var.log_spaced:
        x = np.geomspace(lo, hi, 200)
    else:
        x = np.linspace(lo, hi, 361 if variable == "angle" else 200)
    total = hi if total_cycles is None else total_cycles
    phi = np.asarray(var.basis(jnp.asarray(x), total))
    c = np.asarray(coefficients, dtype=float)
    b = np.zeros(c.size) if log_k_per_coefficient is None else np.asarray(log_k_per_coefficient)
    shift = math.exp(float(b @ c))
    d = (1.0 + phi @ c) * shift - 1.0
    grad = shift * (phi + np.outer(1.0 + phi @ c, b))
    band = np.sqrt(np.clip(np.einsum("ij,jk,ik->i", grad, cov, grad), 0.0, None))
    return x * var.scale, d, band


def span(variable: str, data, library: Library = LIBRARY) -> tuple:
    """The range (SI) over which ``variable``'s delta is drawn and described."""
    return library.variable(variable).span(data)


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


def _angle_shape(c, data, b) -> dict:
    """Lobes and peak angles of an angle discrepancy, read where the data see
    it: over the worn arc (`worn_arc`) the spacing of delta's extrema gives
    the period (adjacent extrema of opposite kind are half a period apart);
    the highest peak inside the arc, repeated at that period, gives the
    peaks round the bushing.  ``b``: the move of ln k per coefficient."""
    lo, hi = worn_arc(data) or (0.0, 360.0)
    if hi < lo:
        hi += 360.0
    x = np.linspace(lo, hi, max(int(4 * (hi - lo)), 16))
    d = ((1.0 + np.asarray(BushingAngle().basis(jnp.asarray(np.radians(x)))) @ c)
         * math.exp(float(b @ c)) - 1.0)
    maxima, minima = _extrema(d)
    extrema = sorted([(x[i], 1) for i in maxima] + [(x[i], -1) for i in minima])
    gaps = [q[0] - p[0] for p, q in zip(extrema, extrema[1:]) if p[1] != q[1]]
    if gaps:
        lobes = max(1, int(round(360.0 / (2.0 * float(np.median(gaps))))))
    else:  # no turn inside the arc: the largest harmonic
        lobes = int(np.argmax(np.hypot(c[0::2], c[1::2]))) + 1
    top = float(x[maxima[int(np.argmax(d[maxima]))]]) if maxima.size else float(x[np.argmax(d)])
    peaks = sorted((top + k * 360.0 / lobes) % 360.0 for k in range(lobes))
    a = float(np.max(np.abs(d)))
    listed = (", ".join(f"{v:.0f}" for v in peaks[:-1])
              + (f" and {peaks[-1]:.0f}" if len(peaks) > 1 else f"{peaks[-1]:.0f}"))
    where = ("the whole bore" if hi - lo >= 360.0 else
             f"the worn arc {lo % 360:.0f}-{hi % 360:.0f} deg")
    return {"worn_arc_deg": [lo, hi], "lobes": lobes, "peaks_deg": peaks, "amplitude": a,
            "shape": f"{lobes} lobe{'s' if lobes > 1 else ''}, peak"
                     f"{'s' if len(peaks) > 1 else ''} at {listed} deg, amplitude "
                     f"+-{100 * a:.0f} % (read over {where})"}


# A turn of delta is named when it moves delta by this share of its range
TURN_SHARE = 0.15


def _turns(d) -> list[int]:
    """Indices of delta's ends and of its turns that move it by `TURN_SHARE`
    of its range (smaller wiggles merged)."""
    span_ = float(np.max(d) - np.min(d))
    keep = [0]
    direction = 0
    for i in range(1, len(d)):
        step = d[i] - d[keep[-1]]
        if direction == 0:
            if abs(step) > TURN_SHARE * span_:
                direction = 1 if step > 0 else -1
                keep.append(i)
        elif step * direction > 0:
            keep[-1] = i          # still rising (falling): the turn moves on
        elif abs(step) > TURN_SHARE * span_:
            direction = -direction
            keep.append(i)
    if keep[-1] != len(d) - 1:
        keep.append(len(d) - 1)
    return keep


def describe(variable: str, coefficients, cov, data, log_k_per_coefficient=None,
             library: Library = LIBRARY) -> dict:
    """The discrepancy's shape in words and numbers, relative to the
    identified k (``log_k_per_coefficient``: `curve`), over the range the
    data cover."""
    c = np.asarray(coefficients)
    b = np.zeros(c.size) if log_k_per_coefficient is None else np.asarray(log_k_per_coefficient)
    out: dict = {"variable": variable, "coefficients": c.tolist(),
                 "coefficients_std": np.sqrt(np.clip(np.diag(cov), 0.0, None)).tolist()}
    if variable == "angle":
        out.update(_angle_shape(c, data, b))
        return out
    lo, hi = span(variable, data, library)
    if variable == "cycles":
        hi = float(data.fit_cycles)
    x, d, _ = curve(variable, c, cov, (lo, hi), float(data.fit_cycles), b, library)
    unit = library.variable(variable).unit
    points = _turns(d)
    values = [f"{100 * d[i]:+.0f} % at {x[i]:.3g} {unit}" for i in points]
    if len(points) == 2:
        words = f"{'rises' if d[-1] > d[0] else 'falls'} from {values[0]} to {values[1]}"
    else:
        moves = ["up" if d[j] > d[i] else "down" for i, j in zip(points, points[1:])]
        words = f"from {values[0]}, " + ", ".join(
            f"{m} to {v}" for m, v in zip(moves, values[1:]))
    out.update(shape=words, amplitude=float(np.max(np.abs(d))), turns=len(points) - 2,
               range=[float(lo), float(hi)])
    return out


def check_variables(data, variables, library: Library = LIBRARY) -> None:
    """Refuse (InputError) a requested variable the dataset cannot show."""
    for v in variables:
        why = unsupported(data, v, library)
        if why is not None:
            raise InputError(f"{data.path}: discrepancy variable {v!r}: {why}")
