"""The start-up transient of a run: when the forces settle onto the motion the
drivers force, so that a run's maxima can be given over the settled part.

A run starts from the file's assembly state, not from the periodic motion the
drivers impose: a clearance joint's pin starts centred and falls across the
clearance (an impact in the first milliseconds), an ideal mechanism's
Baumgarte terms pull the state onto the constraints.  Each force signal s(t)
is then the forced response p(t), smooth on the scale of the driver period P
(its harmonics), plus a start-up part r(t) that rings at the contact's or the
stabilisation's much higher rate and decays.

Criterion (per signal; the run's transient is the longest over its signals):

1. p(t) is estimated by a local quadratic least-squares fit (Savitzky-Golay)
   over a window of `WINDOW_OF_PERIOD` of the period (of the run, without a
   driver).  The fit reproduces a quadratic exactly, so its error on a
   harmonic k of the forced motion is of 4th order in the window: with
   w = 1/32 of the period it is 3e-4 of the amplitude at k = 3 and 9e-4 at
   k = 4 (401 states a period; tests/test_transient.py checks k = 3), below
   the tolerance of step 3.
2. |s - p|'s envelope e(t) is its running maximum over the same window (a
   ringing residual crosses zero; its envelope does not).
3. The threshold is the larger of `TOLERANCE` times the signal's size
   (max |p| after the transient) and `FLOOR_FACTOR` times the envelope's
   median over the last quarter of the run: the roughness the settled motion
   keeps (stick-slip, impacts every cycle, the fit's own error) is no
   transient.
4. The transient ends at the first instant the envelope is below the
   threshold.  From there on s stays within the threshold of p until a
   feature of the forced motion itself, so a maximum over the rest of the run
   is the forced motion's to within the threshold:
   |max s - max p| <= max |s - p|.

Checked (tests/test_transient.py): against decaying ringings whose settling
time is known in closed form, and on the four-bar, rig and clearance
slider-crank files, whose maxima after the transient are those of a full
period run on from the first run's end (to 1 %), a run that itself reports
no transient.

Not settled: a transient that lasts beyond `MAX_TRANSIENT_OF_RUN` of the
run (it is not told apart from the late roughness that sets the threshold),
and roughness that grows (above the tolerance in the last quarter, more
than `FLOOR_FACTOR` times its median of the first quarter, and its median
rising from quarter to quarter: an oscillation builds up).  Such a run's
maxima are those of the whole run.  A run with fewer than `MIN_WINDOWS`
windows of saved states is not judged.

Limits: a ringing that decays by less than `FLOOR_FACTOR` over the run's
last three quarters is taken for the settled motion's roughness (its maxima
are then the whole run's, stated with a transient of 0 s); a ringing slower
than the window is partly taken for the forced motion; impacts the settled
motion itself has right at the run's start (a pin that leaves the wall every
cycle at that crank angle) count into the transient, which then makes the
settled part shorter than it is, its maxima still the settled motion's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

# Window of the smoothing fit and of the envelope, as a fraction of the driver
# period: the fit's error on the forced motion's harmonics up to the 4th is
# below 1e-3 of their amplitude (module notes), while a ringing at 32 times
# the driver frequency or above is left in the residual.
WINDOW_OF_PERIOD = 1 / 32
# Half-width of the fit in saved states, at least: a quadratic through 5
# points is the smallest fit that does not interpolate the samples.
MIN_HALF_WIDTH = 2
# Relative size of a residual that no longer matters: a maximum over the
# settled part is within this fraction of the forced motion's (step 4).
TOLERANCE = 0.01
# The settled roughness's envelope scatters about its median; a transient is
# a residual at least twice that median.  A choice, not a derivation: it only
# matters where the settled roughness exceeds TOLERANCE / 2 of the signal
# (e.g. a pin that rattles every cycle), and there the maxima over the
# settled part carry that roughness anyway.
FLOOR_FACTOR = 2.0
# The late roughness is measured over the last quarter; a transient must
# decay within the first half to be told apart from it.
LATE_FRACTION = 0.25
MAX_TRANSIENT_OF_RUN = 0.5
# Windows of saved states a judgement needs (two for the transient, one for
# the late quarter's floor, one spare).
MIN_WINDOWS = 4


class Settling(NamedTuple):
    """``time_s``: the transient's length from the run's start [s] (0 when
    there is none; None when the run did not settle or cannot be judged);
    ``why``: a sentence for a run that did not settle, else ""."""

    time_s: float | None
    why: str = ""

    @property
    def settled(self) -> bool:
        return self.time_s is not None


def _quadratic_fit(s: np.ndarray, h: int) -> np.ndarray:
    """Local quadratic least-squares fit over 2h + 1 samples (Savitzky-Golay);
    the first and last h samples take the fit of the first and last window."""
    n, w = s.size, 2 * h + 1
    x = np.arange(-h, h + 1, dtype=float)
    vander = np.vander(x, 3, increasing=True)
    proj = np.linalg.pinv(vander)                       # (3, w): coefficients from samples
    out = np.empty(n)
    out[h:n - h] = np.correlate(s, proj[0], mode="valid")
    out[:h] = vander[:h] @ (proj @ s[:w])
    out[n - h:] = vander[h + 1:] @ (proj @ s[n - w:])
    return out


def _envelope(r: np.ndarray, h: int) -> np.ndarray:
    """Running maximum of ``r`` over 2h + 1 samples (shorter at the ends)."""
    padded = np.concatenate([np.full(h, -np.inf), r, np.full(h, -np.inf)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * h + 1)
    return windows.max(axis=1)


def half_width(ts: np.ndarray, period: float | None) -> int:
    """The fit's half-width in saved states for a run saved at ``ts`` whose
    forced motion has ``period`` [s] (None: the run's length)."""
    span = float(ts[-1] - ts[0])
    scale = span if period is None else min(float(period), span)
    dt = span / (ts.size - 1)
    return max(MIN_HALF_WIDTH, int(round(WINDOW_OF_PERIOD * scale / 2 / dt)))


def signal_settling(ts: np.ndarray, s: np.ndarray, period: float | None) -> Settling:
    """The transient of one signal ``s`` saved at ``ts`` (module notes)."""
    ts, s = np.asarray(ts, float), np.asarray(s, float)
    if ts.shape != s.shape or ts.ndim != 1:
        raise ValueError(f"times {ts.shape} and signal {s.shape}: one value per time")
    if not np.all(np.isfinite(s)):
        return Settling(None, "the signal is not finite")
    h = half_width(ts, period)
    if ts.size < MIN_WINDOWS * (2 * h + 1):
        return Settling(None, f"{ts.size} saved states are too few to tell a transient "
                              f"(at least {MIN_WINDOWS * (2 * h + 1)})")
    smooth = _quadratic_fit(s, h)
    envelope = _envelope(np.abs(s - smooth), h)
    span = ts[-1] - ts[0]
    late = ts >= ts[-1] - LATE_FRACTION * span
    size = float(np.max(np.abs(smooth)))
    if size == 0.0:
        return Settling(0.0)
    floor = float(np.median(envelope[late]))
    quarters = [float(np.median(q)) for q in np.array_split(envelope, 4)]
    if (FLOOR_FACTOR * floor > TOLERANCE * size and FLOOR_FACTOR * quarters[0] < floor
            and all(a <= b for a, b in zip(quarters, quarters[1:]))):
        return Settling(None, f"the forces' roughness grows over the run (median "
                              f"{quarters[0]:.3g} in its first quarter, {floor:.3g} in its last)")
    # The size is the smoothed signal's after the transient (the fit follows a
    # part of the ringing); a later start only shrinks it, which lowers the
    # threshold and moves the start on: iterate to the fixed point.
    start = 0
    while True:
        threshold = max(TOLERANCE * float(np.max(np.abs(smooth[start:]))), FLOOR_FACTOR * floor)
        below = np.flatnonzero(envelope[start:] <= threshold)
        if below.size == 0 or below[0] == 0:
            break
        start += int(below[0])
    end = float(ts[start] - ts[0]) if below.size else math.inf
    if end > MAX_TRANSIENT_OF_RUN * span:
        return Settling(None, f"the forces did not settle within the first "
                              f"{MAX_TRANSIENT_OF_RUN:.0%} of the run ({span:g} s)")
    return Settling(end)


def run_settling(ts: np.ndarray, signals: Mapping[str, np.ndarray],
                 period: float | None) -> Settling:
    """The run's transient: the longest of its ``signals`` (name -> values at
    ``ts``); not settled if any of them is not, naming it."""
    longest = 0.0
    for name, s in signals.items():
        one = signal_settling(ts, s, period)
        if not one.settled:
            return Settling(None, f"{name}: {one.why}")
        longest = max(longest, one.time_s or 0.0)
    return Settling(longest)


def settled_part(ts: np.ndarray, settling: Settling) -> np.ndarray:
    """Boolean mask of the saved states after the transient (all of them for
    a run that did not settle: its maxima are the whole run's)."""
    ts = np.asarray(ts, float)
    if settling.time_s is None:
        return np.ones(ts.shape, bool)
    # the settling time is one of the saved times, up to the rounding of ts[0] + (t - ts[0])
    return ts >= ts[0] + settling.time_s - 1e-9 * (ts[-1] - ts[0])


__all__ = ["MAX_TRANSIENT_OF_RUN", "TOLERANCE", "WINDOW_OF_PERIOD", "Settling", "half_width",
           "run_settling", "settled_part", "signal_settling"]
