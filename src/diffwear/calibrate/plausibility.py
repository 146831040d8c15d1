"""Are the measurements plausible for this mechanism, and in the stated units?

Two bookkeeping slips fit without complaint and give a wrong answer with a
small chi-square: a length in metres in a millimetre column (every depth
1,000 times too small: k comes out 1,000 times too small) and a value no
bushing could show.  Before fitting, `check_depths` refuses a depth beyond
the bushing wall (no wear can remove more than the wall).  After the base
fit, `unit_slips` reads each wear series' own best scale factor on the
model's prediction at the stated wear coefficient (the base fit's, which is
linear in k, scaled back): a factor a power of 1,000 away, give or take half
a decade (more than a stated k's usual error), is a unit slip, named for
the series, or for all of them when they agree.  These are warnings naming
the series and the likely slip: the fit is not changed.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError

# series whose prediction scales with the wear coefficient
WEAR_KINDS = ("profile", "max_depth", "volume")
# a factor within this many decades of 10^(3 m) (m = +-1, +-2) reads as a
# unit slip (mm <-> m, um <-> mm, um <-> m); the rest of the decade is what
# a wrong stated k or an unmodelled effect can give
SLIP_DECADES = 0.5
# the column units a slip would come from, per power of 1,000 (the series
# reads 10^(3 m) times what the model expects)
_SLIPS = {-1: "a length in metres in a millimetre column, or millimetres in a micrometre one",
          1: "a length in millimetres in a metre column, or micrometres in a millimetre one",
          -2: "micrometres expected, metres written", 2: "metres expected, micrometres written"}
_VOLUME_SLIPS = {-1: "a volume in cm^3 or a mass in kg where mm^3 or g were stated",
                 1: "a volume in mm^3 where cm^3 was meant, or a mass in mg in a gram column",
                 -3: "a volume in m^3 in a mm^3 column", 3: "mm^3 written where m^3 was meant"}


def check_depths(data, wall: float | None) -> None:
    """`InputError` naming the series, its file, the value and the wall when
    a measured depth exceeds the bushing wall ``wall`` [m]."""
    if wall is None or not math.isfinite(wall) or wall <= 0.0:
        return
    for s in data.series:
        if s.kind not in ("profile", "max_depth") or s.y.size == 0:
            continue
        i = int(np.argmax(s.y))
        if s.y[i] > wall:
            raise InputError(
                f"{data.path / s.file}: series {s.name!r}: a depth of {s.y[i] * 1e3:.4g} mm "
                f"(row {i + 1}) is beyond the bushing wall of {wall * 1e3:.4g} mm; allowed: "
                f"0 to {wall * 1e3:.4g} mm (a length in micrometres in a millimetre column?)")


def _factor(prediction, y, sigma) -> float:
    """The series' own best scale factor a on the prediction (least squares
    of a * prediction against y); nan where the prediction is zero."""
    p, y = np.asarray(prediction, float), np.asarray(y, float)
    den = float(np.sum((p / sigma) ** 2))
    return float(np.sum(p * y) / sigma**2 / den) if den > 0 else math.nan


def _slip(factor: float) -> int:
    """m where ``factor`` is 10^(3 m) within `SLIP_DECADES`, else 0."""
    if not factor > 0:
        return 0
    decades = math.log10(factor)
    m = round(decades / 3.0)
    return m if m and abs(decades - 3.0 * m) <= SLIP_DECADES else 0


def unit_slips(data, problem, base, stated_k: float | None) -> list[dict]:
    """Warnings (``{"series", "factor", "message"}``) for wear series that
    read a power of 1,000 away from the model at the stated wear coefficient
    (module notes): one per series, or one for all when they agree."""
    fitted_k = float(base.params.get("k", math.nan))
    # the base model's prediction scales with k: back to the stated k
    to_stated = (fitted_k / stated_k if stated_k and "k" in problem.fit_names
                 and math.isfinite(fitted_k) and fitted_k > 0 else 1.0)
    factors = {}
    for k, s in enumerate(data.series):
        if s.kind in WEAR_KINDS:
            rows = problem.series_of_point == k
            factors[k] = _factor(base.prediction[rows], s.y, s.sigma) * to_stated
    slips = {k: _slip(f) for k, f in factors.items()}
    flagged = [k for k, m in slips.items() if m]
    if not flagged:
        return []
    if len(flagged) == len(factors) > 1 and len({slips[k] for k in flagged}) == 1:
        f = float(np.exp(np.mean(np.log([factors[k] for k in flagged]))))
        m = slips[flagged[0]]
        return [{"series": None, "factor": f, "message": (
            f"every wear series reads {f:.3g} times what the model gives at the stated wear "
            f"coefficient (the fitted one is {to_stated:.3g} times it): likely "
            f"{_SLIPS.get(m, 'a unit slip')} in every file, or a stated k in the wrong unit; "
            "check the columns' units")}]
    out = []
    for k in flagged:
        s = data.series[k]
        m = slips[k]
        words = (_VOLUME_SLIPS if s.kind == "volume" else _SLIPS).get(m, "a unit slip")
        others = (" (the other wear series agree with the model)"
                  if len(flagged) < len(factors) else "")
        out.append({"series": s.name, "factor": factors[k], "message": (
            f"series {s.name!r} ({s.file}) reads {factors[k]:.3g} times what the model gives "
            f"at the stated wear coefficient{others}: likely {words}; check its column's unit")})
    return out
