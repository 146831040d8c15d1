"""Raimondi & Boyd's finite journal bearing: the reference values the finite
film (`FiniteBearingFilm`) is checked and drawn against.

Raimondi & Boyd, A solution for the finite journal bearing and its
application to analysis and design, ASLE Trans. 1 (1958) 159-209: the full
(360 deg) journal bearing, Reynolds cavitation, oil supplied at the maximum
film (reproduced in Shigley's Mechanical Engineering Design, Table 12-4 and
Figs. 12-16, 12-19).  By length-to-diameter ratio L/D and eccentricity ratio
eps: the Sommerfeld number S = (R / c)^2 mu N / P (N the journal speed in
rev/s, P = W / (2 R L) the load per projected area) and the attitude angle
phi [deg] between the load line and the line of centres.

The same values are held by tests/test_finite_bearing.py (to 2 %) and drawn
on the lubrication guide's comparison figure (docs/figures.py).
"""

from __future__ import annotations

__all__ = ["RAIMONDI_BOYD"]

RAIMONDI_BOYD: dict[float, dict[float, tuple[float, float]]] = {
    1.0: {0.2: (0.631, 74.02), 0.4: (0.264, 63.10), 0.6: (0.121, 50.58),
          0.8: (0.0446, 36.24), 0.9: (0.0188, 26.45)},
    0.5: {0.2: (2.03, 74.94), 0.4: (0.779, 61.45), 0.6: (0.319, 48.14),
          0.8: (0.0923, 33.31), 0.9: (0.0313, 23.66)},
    0.25: {0.2: (7.57, 75.18), 0.4: (2.83, 60.86), 0.6: (1.07, 46.72),
           0.8: (0.261, 31.04), 0.9: (0.0736, 21.85)},
}
"""L/D -> eps -> (S, attitude angle phi [deg]), Raimondi & Boyd (module notes)."""

