"""Smooth stand-ins for the non-smooth parts of contact, each with a width.

Every function converges to its non-smooth limit as the width goes to zero
(tests/test_smoothing_convergence.py); the widths used by default are stated
where the contact laws pick them.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def ramp(x, width):
    """max(x, 0) smoothed: width * softplus(x / width).  Error <= width * ln 2,
    and exponentially small for |x| >> width."""
    return width * jax.nn.softplus(x / width)


def step(x, width):
    """Heaviside(x) smoothed: sigmoid(x / width) (the derivative of `ramp`)."""
    return jax.nn.sigmoid(x / width)


def sign(x, width):
    """sign(x) smoothed: tanh(x / width)."""
    return jnp.tanh(x / width)


def magnitude(x, width):
    """|x| smoothed: sqrt(x^2 + width^2) - width (exact 0 at 0, finite gradient)."""
    return jnp.sqrt(x * x + width * width) - width
