"""The infinitely long journal bearing with its groove at the maximum film,
in closed form (quadrature and a root find): the independent reference of the
finite film's long-bearing limit, under both cavitation conditions (with the
groove there they share the rupture boundary).

Imported by the tests (pytest puts ``tests/`` on ``sys.path``); not collected.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq


def long_bearing(eps):
    """(F_n, F_t, H*) of the infinitely long bearing with the Reynolds
    condition, per unit wedge B and unit length in zeta = z / R, in units of 6 mu R^4 / c^2: an
    independent route (quadrature and a root find).  Integrating the long
    Reynolds equation d/dpsi (H^3 dP/dpsi) = B sin psi = (B / eps) dH/dpsi once,
    H^3 P' = (B / eps) (H - H*), from the supply at the maximum film (P(pi) = 0)
    to the cavitation end psi_c in (2 pi, 3 pi), where H(psi_c) = H* and
    P(psi_c) = 0 (Swift-Stieber: P = P' = 0 there); H* from that condition.
    Past the rupture the Couette flux (B / eps) H theta keeps its value there,
    so the mass-conserving film's content is theta = H* / H."""
    def h(p):
        return 1 - eps * np.cos(p)

    def pressure(psi, h_star):
        return quad(lambda p: (h(p) - h_star) / (eps * h(p) ** 3), np.pi, psi,
                    epsabs=1e-12, epsrel=1e-10, limit=200)[0]

    def end(h_star):
        return 2 * np.pi + np.arccos((1 - h_star) / eps)

    h_star = brentq(lambda hs: pressure(end(hs), hs), 1 - eps + 1e-12, 1 - 1e-9, xtol=1e-15)
    psi_c = end(h_star)
    f_n = -quad(lambda p: pressure(p, h_star) * np.cos(p), np.pi, psi_c, limit=200)[0]
    f_t = -quad(lambda p: pressure(p, h_star) * np.sin(p), np.pi, psi_c, limit=200)[0]
    return f_n, f_t, h_star
