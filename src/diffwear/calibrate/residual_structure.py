"""Where a calibration's residual sits, in numbers.

`locate_residual` measures the base fit's residual (in units of each
series' stated noise) by bushing angle, by cycle count and by harmonic order:
the structure a missing effect leaves.  `residual_words` puts these numbers
in words; `series_rms` gives each series' RMS residual before and after the
effects were added.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from .fit import FitResult
    from .identify import Calibration

HARMONIC_ORDERS = 8  # harmonics 1..8 of the bushing angle or the crank angle
SECTORS = 12  # 30-degree sectors of the bushing angle
REVERSAL_DEG = 20.0  # crank angles within this of 0 and 180 deg: slider reversal


def _harmonics(angle, residual, orders) -> dict[int, float]:
    """Amplitude of each order's cos/sin pair fitted to the residual (least
    squares, so uneven angles are allowed; the mean taken out)."""
    basis = np.column_stack([f(o * angle) for o in orders for f in (np.cos, np.sin)])
    coef, *_ = np.linalg.lstsq(basis, residual - residual.mean(), rcond=None)
    amp = np.hypot(coef[0::2], coef[1::2])
    return {int(o): float(a) for o, a in zip(orders, amp)}


def locate_residual(c: Calibration) -> dict:
    """Where the base fit's residual sits: the numbers behind the report's
    "Residual structure" section and `describe_residuals`.

    **Arguments:**

    - ``c``: a finished calibration (`diffwear.calibrate.identify.calibrate`);
      its base fit's normalised residual is read.

    **Returns:** a dict with those of these keys the dataset supports:

    - ``profile_rms_by_30deg_sector``: RMS profile residual in each 30-degree
      sector of the bushing angle (None for a sector without points);
    - ``profile_residual_harmonics``: {order: amplitude} of bushing-angle
      harmonics 1..8 of the profile residual (16 points or more);
    - ``<kind>_mean_residual_by_cycles`` for kind profile, volume, max_depth,
      force: {cycle count: mean residual} (the first 40 counts);
    - ``force_residual_harmonics``: {order: amplitude} of crank-angle
      harmonics of the first force series' residual (8 points or more;
      orders 1..min(8, n // 2 - 1) for n points);
    - ``force_residual_rms_near_reversal``, ``force_residual_rms_elsewhere``:
      its RMS within 20 degrees of crank angle 0 and 180 (slider reversal)
      and elsewhere;
    - ``note_mass_vs_profile``: a note when weighed volumes and profiles are
      both present.
    """
    p, r = c.problem, c.base.residual
    out: dict[str, Any] = {}
    kinds = [s.kind for s in c.dataset.series]
    which = p.series_of_point
    prof = np.isin(which, [k for k, kd in enumerate(kinds) if kd == "profile"])
    if prof.any():
        theta = np.concatenate([s.x for s in c.dataset.series if s.kind == "profile"])
        bins = np.linspace(0, 2 * np.pi, SECTORS + 1)
        idx = np.clip(np.digitize(theta, bins) - 1, 0, SECTORS - 1)
        rp = r[prof]
        out["profile_rms_by_30deg_sector"] = [
            float(np.sqrt(np.mean(rp[idx == b] ** 2))) if np.any(idx == b) else None
            for b in range(SECTORS)]
        if theta.size >= 2 * HARMONIC_ORDERS:
            # theta-harmonic content of the profile residual
            out["profile_residual_harmonics"] = _harmonics(
                theta, rp, np.arange(1, HARMONIC_ORDERS + 1))
    cyc = np.concatenate([s.cycle_counts for s in c.dataset.series])
    for kind in ("profile", "volume", "max_depth", "force"):
        m = np.isin(which, [k for k, kd in enumerate(kinds) if kd == kind])
        if not m.any():
            continue
        levels = np.unique(cyc[m])
        out[f"{kind}_mean_residual_by_cycles"] = {
            f"{n:g}": float(np.mean(r[m & (cyc == n)])) for n in levels[:40]}
    force = [k for k, kd in enumerate(kinds) if kd == "force"]
    if force:
        k = force[0]
        m = which == k
        x = c.dataset.series[k].x
        if x.size >= HARMONIC_ORDERS:
            # harmonic content of the residual (crank orders)
            out["force_residual_harmonics"] = _harmonics(
                x, r[m], np.arange(1, min(HARMONIC_ORDERS + 1, x.size // 2)))
            # slider reversal: crank angle 0 and pi (+-20 deg) vs elsewhere
            off = np.minimum(np.abs(np.angle(np.exp(1j * x))),
                             np.abs(np.angle(np.exp(1j * (x - np.pi)))))
            near = off < np.radians(REVERSAL_DEG)
            rr = r[m]
            out["force_residual_rms_near_reversal"] = (
                float(np.sqrt(np.mean(rr[near] ** 2))) if near.any() else None)
            out["force_residual_rms_elsewhere"] = (
                float(np.sqrt(np.mean(rr[~near] ** 2))) if (~near).any() else None)
    if any(s.kind == "volume" and s.basis == "mass" for s in c.dataset.series) and prof.any():
        # data-only check: volume of the measured profiles vs weighed volume
        out["note_mass_vs_profile"] = ("compare the 'volume' residual (mass-based) with the "
                                       "profile residual: a profile that grows without mass "
                                       "loss (creep) shows as a positive profile residual and "
                                       "an unbiased mass residual")
    return out


def series_rms(c: Calibration, final: FitResult) -> dict[str, tuple[float, float]]:
    """Each series' RMS residual [sigma] before and after the effects were added.

    **Arguments:**

    - ``c``: a finished calibration.
    - ``final``: the fit to compare with its base fit (the calibration's
      final model).

    **Returns:** {series name: (RMS of the base fit's residual, RMS of ``final``'s)}.
    """
    out = {}
    for k, s in enumerate(c.dataset.series):
        m = c.problem.series_of_point == k
        out[s.name] = (float(np.sqrt(np.mean(c.base.residual[m] ** 2))),
                       float(np.sqrt(np.mean(final.residual[m] ** 2))))
    return out
