"""Is a measured profile in the model's angle frame?

The most common bookkeeping slip with bore profiles is the angle convention:
measured clockwise instead of counter-clockwise, or from another zero.  A
profile in the wrong frame fits badly however the parameters move, and the
loop would look for an effect that is not there.  `frame_check` compares the
base fit's prediction with the data read in every other frame (rotated by a
multiple of `STEP_DEG`, and mirrored and rotated) and reports the frame that
fits much better: chi-square lower by the factor `FACTOR` and by at least
`MIN_DROP` (so noise alone does not trigger it), with the manifest keys that
declare that frame (`diffwear.calibrate.dataset`, ``[rig]``
``bushing_angle_zero`` / ``bushing_angle_sense``).  A warning: the user
decides, the fit is not changed.  `frame_warnings` checks every profile of a
calibration.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .identify import Calibration

STEP_DEG = 5.0
FACTOR = 2.0
MIN_DROP = 25.0


def _periodic(theta, y):
    """Linear periodic interpolant of (theta, y) on [0, 2 pi)."""
    t = np.concatenate([theta - 2 * math.pi, theta, theta + 2 * math.pi])
    v = np.concatenate([y, y, y])
    return lambda a: np.interp(np.mod(a, 2 * math.pi), t, v)


def frame_check(theta, y, sigma, prediction) -> dict | None:
    """The frame in which the profile (``theta`` [rad], depth ``y``, noise
    ``sigma``) fits ``prediction`` (the model at ``theta``) much better than
    as given, or None.  Returns {"chi2_as_given", "chi2", "zero_deg",
    "sense", "transform"}: the data's own zero lies at ``zero_deg`` of the
    model frame and counts in ``sense``."""
    theta, y = np.asarray(theta, float), np.asarray(y, float)
    prediction = np.asarray(prediction, float)
    if theta.size < 8:
        return None
    data_at = _periodic(theta, y)

    def chi2(angles):
        return float(np.sum(((data_at(angles) - prediction) / sigma) ** 2))

    given = float(np.sum(((y - prediction) / sigma) ** 2))
    found = []
    for z in np.arange(0.0, 360.0, STEP_DEG):
        zr = math.radians(z)
        for sense, angles in (("counter-clockwise", theta - zr), ("clockwise", zr - theta)):
            if sense == "counter-clockwise" and z == 0.0:
                continue  # as given
            found.append((chi2(angles), z, sense))
    lowest = min(c for c, _, _ in found)
    # a groove symmetric about its centre fits mirrored as well as rotated:
    # among the frames that fit as well (within noise), name the simplest slip
    # (a rotation, then a mirror about the zero, then both; the smallest angle)
    near = [f for f in found if f[0] <= lowest + max(1.0, 0.01 * lowest)]
    c, z, sense = min(near, key=lambda f: (f[2] != "counter-clockwise", f[1] != 0.0,
                                           min(f[1], 360.0 - f[1])))
    if not (c * FACTOR < given and given - c > MIN_DROP):
        return None
    what = ("mirrored" if sense == "clockwise" else "rotated") + (
        f", zero at {z:g} deg" if z or sense == "counter-clockwise" else "")
    return {"chi2_as_given": given, "chi2": c, "zero_deg": float(z), "sense": sense,
            "transform": what}


def frame_warnings(c: Calibration) -> list[dict]:
    """The profiles of a calibration that fit its base model much better in
    another angle frame (`frame_check`), with the manifest keys that would
    declare that frame.

    **Arguments:**

    - ``c``: a finished calibration (`diffwear.calibrate.identify.calibrate`);
      each profile series is compared with the base fit's prediction.

    **Returns:** one dict per such profile: `frame_check`'s result plus
    ``series`` (its name) and ``message`` (the warning in words, naming
    ``bushing_angle_zero`` and ``bushing_angle_sense`` for ``[rig]``).
    """
    found = []
    final = c.final or c.chosen
    for k, s in enumerate(c.dataset.series):
        if s.kind != "profile":
            continue
        rows = c.problem.series_of_point == k
        f = frame_check(s.x, s.y, s.sigma, c.base.prediction[rows])
        if f is None:
            continue
        f["series"] = s.name
        f["message"] = (
            f"profile {s.name!r} fits the base model much better {f['transform']} (chi2 "
            f"{f['chi2']:.0f} against {f['chi2_as_given']:.0f} as given): if it was measured "
            f"in that frame, declare it in [rig]: bushing_angle_zero = \"{f['zero_deg']:g} deg\", "
            f"bushing_angle_sense = \"{f['sense']}\"")
        # the chosen model may fit it as given as well (a lobed k can mimic a
        # mirror): both readings are then open, and the warning says so
        chi2_final = float(np.sum(final.residual[rows] ** 2))
        f["chi2_final_as_given"] = chi2_final
        if final is not c.base and chi2_final <= f["chi2"]:
            f["message"] += (f"; the chosen model fits it as given as well (chi2 "
                             f"{chi2_final:.0f}): check the frame before trusting either")
        found.append(f)
    return found
