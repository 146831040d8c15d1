"""The chi-square distribution with any (real) number of degrees of freedom.

P(chi2_k > x) = Q(k / 2, x / 2), the regularised upper incomplete gamma
function, by its series below a + 1 and its continued fraction above
(Numerical Recipes, 3rd ed., Sec. 6.2, `gammq`): pure Python, so that the
calibration's tests of a discrepancy with a fractional effective number of
coefficients need no statistics library.
"""

from __future__ import annotations

import math

_EPS = 1e-15
_ITERATIONS = 500


def _lower_series(a: float, x: float) -> float:
    """P(a, x) by its series (x < a + 1)."""
    term = total = 1.0 / a
    ap = a
    for _ in range(_ITERATIONS):
        ap += 1.0
        term *= x / ap
        total += term
        if abs(term) < abs(total) * _EPS:
            break
    return total * math.exp(-x + a * math.log(x) - math.lgamma(a))


def _upper_fraction(a: float, x: float) -> float:
    """Q(a, x) by its continued fraction (x >= a + 1; modified Lentz)."""
    tiny = 1e-300
    b = x + 1.0 - a
    c = 1.0 / tiny
    d = 1.0 / b
    h = d
    for i in range(1, _ITERATIONS):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < _EPS:
            break
    return h * math.exp(-x + a * math.log(x) - math.lgamma(a))


def sf(x: float, dof: float = 1.0) -> float:
    """P(chi-square(``dof``) > ``x``)."""
    if not dof > 0:
        raise ValueError(f"chi-square degrees of freedom must be > 0, got {dof}")
    if not x > 0:
        return 1.0
    a, y = 0.5 * dof, 0.5 * x
    if y < a + 1.0:
        return max(0.0, 1.0 - _lower_series(a, y))
    return min(1.0, _upper_fraction(a, y))


def isf(p: float, dof: float = 1.0) -> float:
    """x with P(chi-square(``dof``) > x) = ``p`` (bisection on `sf`)."""
    if not 0.0 < p < 1.0:
        raise ValueError(f"a probability in (0, 1) is needed, got {p}")
    lo, hi = 0.0, max(10.0, 2.0 * dof)
    while sf(hi, dof) > p:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if sf(mid, dof) > p else (lo, mid)
        if hi - lo < 1e-12 * hi:
            break
    return 0.5 * (lo + hi)
