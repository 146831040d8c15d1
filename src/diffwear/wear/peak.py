"""The maximum of a wear-depth profile, as a smooth function of its grid values
(`peak_depth`), and without the grid's node-scale roughness (`arc_peak_depth`).

``jnp.max`` over the grid is the maximum of the grid values: when the deepest
node changes (the groove's peak moves between two nodes) its derivative jumps,
so a life defined by "max depth = limit" would have a derivative that jumps
too.  `peak_depth` instead returns the maximum of the periodic C1 cubic
interpolant of the profile (Catmull-Rom: cubic Hermite with central-difference
slopes), found by Newton's method on its derivative in the two cells beside the
deepest node.  Its derivative with respect to the grid values is the
interpolant's basis at the maximiser (envelope theorem), continuous as the
maximiser moves across a node; it is a kink only where two separate peaks swap
(a true corner of the maximum).  On a smooth profile it differs from the grid
maximum by O(dtheta^2) of the curvature.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

# Newton iterations on S'(x) = 0 from the vertex of the parabola through the
# deepest node and its neighbours: quadratic convergence, and the value S(x*)
# is stationary in x*, so 6 iterations leave an error far below rounding.
_NEWTON_ITERATIONS = 6


def _hermite(h: Float[Array, " n"], x: Float[Array, ""]):
    """Catmull-Rom interpolant of periodic ``h`` (grid index units) at x:
    (value, first derivative, second derivative) with respect to x."""
    n = h.shape[0]
    k = jnp.floor(x)
    t = x - k
    k = k.astype(int)
    p0, p1, p2, p3 = (h[(k + j) % n] for j in (-1, 0, 1, 2))
    m1, m2 = 0.5 * (p2 - p0), 0.5 * (p3 - p1)
    d = p1 - p2
    # S(t) = p1 + m1 t + (-3 p1 + 3 p2 - 2 m1 - m2) t^2 + (2 p1 - 2 p2 + m1 + m2) t^3
    a2 = 3.0 * (-d) - 2.0 * m1 - m2
    a3 = 2.0 * d + m1 + m2
    value = p1 + t * (m1 + t * (a2 + t * a3))
    slope = m1 + t * (2.0 * a2 + 3.0 * t * a3)
    curvature = 2.0 * a2 + 6.0 * t * a3
    return value, slope, curvature


def peak_depth(h: Float[Array, " n"]) -> Float[Array, ""]:
    """Maximum [units of h] of the periodic C1 cubic interpolant of ``h``.

    Never below ``max(h)``; exact for a constant profile; differentiable, with
    a derivative continuous while the peak moves along the bushing.
    """
    n = h.shape[0]
    i = jnp.argmax(h)
    left, mid, right = h[(i - 1) % n], h[i], h[(i + 1) % n]
    # vertex of the parabola through the three nodes (clipped to one cell)
    denom = left - 2.0 * mid + right
    safe = jnp.where(denom < 0.0, denom, -1.0)  # double where: no 0/0
    offset = jnp.where(denom < 0.0, 0.5 * (left - right) / safe, 0.0)
    x0 = i + jnp.clip(offset, -0.5, 0.5)
    lo, hi = i - 1.0, i + 1.0

    def newton(_, x):
        _, slope, curv = _hermite(h, x)
        ok = curv < 0.0
        step = jnp.where(ok, slope / jnp.where(ok, curv, -1.0), 0.0)
        return jnp.clip(x - step, lo, hi)

    x = lax.fori_loop(0, _NEWTON_ITERATIONS, newton, x0)
    value, _, _ = _hermite(h, x)
    return jnp.maximum(value, mid)


# Half-width of the arc over which `arc_peak_depth` averages: 4 deg, two nodes
# each side on the studies' 180-node grid.  The FEM route's worn profile keeps
# a node-to-node roughness of about one wear step (`wear.fem_route`), so its
# grid maximum moves by ~2 % between runs that differ at round-off; averaged
# over +-2 nodes it moves by ~0.4 % (eight rig-21400 runs each,
# benchmarks/records/fem_route_scatter.json).
ARC_HALF_WIDTH = math.radians(4.0)


def arc_peak_depth(h: Float[Array, " n"], half_width=ARC_HALF_WIDTH) -> Float[Array, ""]:
    """Largest mean of the periodic profile ``h`` over an arc of +- ``half_width``
    [rad] (rounded to whole grid spacings, at least 0): the peak of the groove
    without the grid's node-scale roughness.  Equals ``max(h)`` for a constant
    profile and, at ``half_width`` below half a spacing, for any."""
    n = h.shape[-1]
    half = max(int(round(half_width * n / (2.0 * math.pi))), 0)
    k = 2 * half + 1
    window = sum(jnp.roll(h, s, axis=-1) for s in range(-half, half + 1))
    return jnp.max(window / k, axis=-1)
