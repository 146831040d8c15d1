"""Smooth stand-ins for the non-smooth parts of contact, each with a width.

No exp/log: these run on hundreds of elastic-foundation grid points per
right-hand side.

- `ramp` (contact onset, no-tension clamps): a C1 cubic blend that is *exactly*
  0 for x <= 0 and exactly x for x >= width.  Exactness outside the band
  matters: a ramp that leaks (softplus: width ln 2 at x = 0) puts a spurious
  pressure on every non-contacting spring of the bushing, and over 300 degrees
  of bushing that biased the EFM resultant by width/delta (~1e-3 at 10 nm).
- `step`: its derivative (continuous, exact outside [0, width]).
- `sign`, `magnitude` (friction direction, sliding speed): algebraic,
  x / sqrt(x^2 + w^2) and sqrt(x^2 + w^2) - w, exact at 0 and with error <= w.

Each converges to its non-smooth limit as the width goes to zero
(tests/test_contact_laws.py); the widths used are stated where the contact
laws pick them.

Derivatives.  `ramp` and `step` carry hand-written JVP rules (`jax.custom_jvp`).
Autodiff of the nested ``jnp.where`` differentiates the cubic of the band *and*
both outer branches for every tangent and then selects; the rules below compute
the partial derivatives once, from the primal, and apply them to every tangent
with one multiply-add.  That matters in forward mode (``jax.jacfwd`` through a
whole wear evolution carries 4 tangents through every right-hand side, each
with several EFM arrays of ``n_theta`` points).  A tangent of the width is
handled too (it is zero in every current use: the widths are constants or
depend on non-differentiated inputs) and skipped when JAX knows it is zero.
The rules are exact: tests/test_contact_laws.py compares them with autodiff of
the plain formulas and with finite differences.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
from jax.custom_derivatives import SymbolicZero


def _band(x, width):
    """(below, above) masks of the blend band [0, width]."""
    return x <= 0.0, x >= width


def _ramp(x, width):
    below, above = _band(x, width)
    inside = x * x * (2.0 * width - x) / (width * width)
    return jnp.where(below, 0.0, jnp.where(above, x, inside))


def _step(x, width):
    below, above = _band(x, width)
    inside = x * (4.0 * width - 3.0 * x) / (width * width)
    return jnp.where(below, 0.0, jnp.where(above, 1.0, inside))


def _apply(primal, dx, x_dot, dw, w_dot):
    """primal, dx * x_dot + dw * w_dot (the width term only for a nonzero w_dot)."""
    t = dx * x_dot if not isinstance(x_dot, SymbolicZero) else jnp.zeros_like(primal)
    if not isinstance(w_dot, SymbolicZero):
        t = t + dw * w_dot
    return primal, t


@jax.custom_jvp
def ramp(x, width):
    """max(x, 0) smoothed over [0, width]: x^2 (2 w - x) / w^2 inside the band."""
    return _ramp(x, width)


@partial(ramp.defjvp, symbolic_zeros=True)
def _ramp_jvp(primals, tangents):
    # r = x^2 (2w - x) / w^2 = 2 x^2 / w - x^3 / w^2 inside the band (0 below, x above):
    #   dr/dx = 4 x / w - 3 x^2 / w^2 = x (4w - 3x) / w^2 = step(x, w)  (0 below, 1 above)
    #   dr/dw = -2 x^2 / w^2 + 2 x^3 / w^3 = -2 x^2 (w - x) / w^3       (0 outside)
    x, width = primals
    x_dot, w_dot = tangents
    below, above = _band(x, width)
    dw = jnp.where(below | above, 0.0, -2.0 * x * x * (width - x) / (width * width * width))
    return _apply(_ramp(x, width), _step(x, width), x_dot, dw, w_dot)


@jax.custom_jvp
def step(x, width):
    """Heaviside(x) smoothed over [0, width]: the derivative of `ramp`."""
    return _step(x, width)


@partial(step.defjvp, symbolic_zeros=True)
def _step_jvp(primals, tangents):
    # s = x (4w - 3x) / w^2 = 4 x / w - 3 x^2 / w^2 inside the band (0 below, 1 above):
    #   ds/dx = 4 / w - 6 x / w^2 = (4w - 6x) / w^2            (0 outside)
    #   ds/dw = -4 x / w^2 + 6 x^2 / w^3 = -2 x (2w - 3x) / w^3  (0 outside)
    x, width = primals
    x_dot, w_dot = tangents
    below, above = _band(x, width)
    out = below | above
    w2 = width * width
    dx = jnp.where(out, 0.0, (4.0 * width - 6.0 * x) / w2)
    dw = jnp.where(out, 0.0, -2.0 * x * (2.0 * width - 3.0 * x) / (w2 * width))
    return _apply(_step(x, width), dx, x_dot, dw, w_dot)


def ramp_integral(x, width):
    """The antiderivative of `ramp` that is 0 for x <= 0: x^3 (8 w - 3 x) / (12 w^2)
    inside the band, 5 w^2 / 12 + (x^2 - w^2) / 2 above it (the energy of a
    smoothed one-sided spring of unit stiffness)."""
    below, above = _band(x, width)
    inside = x * x * x * (8.0 * width - 3.0 * x) / (12.0 * width * width)
    return jnp.where(below, 0.0, jnp.where(above, 5.0 * width * width / 12.0
                                           + 0.5 * (x * x - width * width), inside))


def sign(x, width):
    """sign(x) smoothed: x / sqrt(x^2 + width^2)."""
    return x / jnp.sqrt(x * x + width * width)


def magnitude(x, width):
    """|x| smoothed: sqrt(x^2 + width^2) - width (exact 0 at 0, finite gradient)."""
    return jnp.sqrt(x * x + width * width) - width
