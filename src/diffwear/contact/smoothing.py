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
"""

from __future__ import annotations

import jax.numpy as jnp


def ramp(x, width):
    """max(x, 0) smoothed over [0, width]: x^2 (2 w - x) / w^2 inside the band."""
    inside = x * x * (2.0 * width - x) / (width * width)
    return jnp.where(x <= 0.0, 0.0, jnp.where(x >= width, x, inside))


def step(x, width):
    """Heaviside(x) smoothed over [0, width]: the derivative of `ramp`."""
    inside = x * (4.0 * width - 3.0 * x) / (width * width)
    return jnp.where(x <= 0.0, 0.0, jnp.where(x >= width, 1.0, inside))


def sign(x, width):
    """sign(x) smoothed: x / sqrt(x^2 + width^2)."""
    return x / jnp.sqrt(x * x + width * width)


def magnitude(x, width):
    """|x| smoothed: sqrt(x^2 + width^2) - width (exact 0 at 0, finite gradient)."""
    return jnp.sqrt(x * x + width * width) - width
