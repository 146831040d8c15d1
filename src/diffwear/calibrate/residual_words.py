"""The base fit's residual structure, in words for the report.

Each sentence states a measured number and what such a structure usually
means; the numbers come from `residual_structure`.  Thresholds: a
series is "at the noise" when its RMS residual is below `NOISE_RMS` sigma; a
harmonic "dominates" when it carries more than `DOMINANT_SHARE` of the
residual's harmonic power.
"""

from __future__ import annotations

import numpy as np

NOISE_RMS = 1.5
DOMINANT_SHARE = 0.5


def _dominant(harmonics: dict) -> tuple[int, float, float] | None:
    """(order, amplitude, share of the power) of the strongest harmonic."""
    if not harmonics:
        return None
    orders = list(harmonics)
    amp = np.array([harmonics[o] for o in orders])
    power = amp**2
    if power.sum() <= 0:
        return None
    k = int(np.argmax(power))
    return int(orders[k]), float(amp[k]), float(power[k] / power.sum())


def describe_residuals(c, structure: dict) -> list[str]:
    """Sentences on where the base fit's residual sits (see module notes)."""
    p, r = c.problem, c.base.residual
    words = []
    kinds = np.array([c.dataset.series[k].kind for k in p.series_of_point])
    loud = []
    for kind in ("profile", "volume", "max_depth", "force"):
        m = kinds == kind
        if m.any():
            rms = float(np.sqrt(np.mean(r[m] ** 2)))
            if rms >= NOISE_RMS:
                loud.append(f"{kind} {rms:.2g} sigma")
    if not loud:
        if c.notes.get("unit_warnings"):  # a fit at the noise level of a mis-scaled series
            return ["every series fits the base model at the noise level (RMS < "
                    f"{NOISE_RMS} sigma), but see the unit warning: the fitted numbers "
                    "may be off by a power of 1,000"]
        return ["every series fits the base model at the noise level (RMS < "
                f"{NOISE_RMS} sigma): nothing for an effect to explain"]
    words.append("base-fit RMS residual above the noise: " + ", ".join(loud))
    dom = _dominant(structure.get("profile_residual_harmonics", {}))
    if dom and dom[2] > DOMINANT_SHARE and dom[1] > 1.0:
        order, amp, share = dom
        what = ("an angle-dependent shape of the bore the library lacks (e.g. an oval or "
                "lobed bore, or wear that depends on the bushing angle)" if order >= 2 else
                "a profile displaced to one side: the load direction, or the angle frame of "
                "the measurement")
        words.append(f"profile residual concentrated at {order} theta-harmonic(s) "
                     f"({amp:.2g} sigma, {share:.0%} of its harmonic power): {what}")
    trend = structure.get("profile_mean_residual_by_cycles")
    if trend and len(trend) >= 2:
        values = list(trend.values())
        if abs(values[-1] - values[0]) > 1.0:
            sense = "grows" if values[-1] > values[0] else "falls"
            words.append(f"the mean profile residual {sense} with the cycle count "
                         f"({values[0]:+.2g} to {values[-1]:+.2g} sigma): a wear rate that "
                         "changes in time (run-in, film, debris) or a missing depth offset")
    dom = _dominant(structure.get("force_residual_harmonics", {}))
    if dom and dom[1] > 1.0:
        order, amp, share = dom
        near = structure.get("force_residual_rms_near_reversal")
        far = structure.get("force_residual_rms_elsewhere")
        if near is not None and far is not None and near > 2.0 * max(far, 1e-12):
            words.append(f"force residual concentrated at slider reversal ({near:.2g} against "
                         f"{far:.2g} sigma elsewhere): friction in the slider guide")
        else:
            words.append(f"force residual at crank order {order} ({amp:.2g} sigma, "
                         f"{share:.0%} of its harmonic power): the mechanism's geometry, "
                         "masses or spring rather than wear (see the suspects)")
    return words
