"""Coulomb friction with a smoothed sign (thesis Eq. 3-9)."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive
from . import smoothing

# Slip speed over which the friction direction turns: 1 mm/s.  The thesis pins
# slide at R * |omega_rel| ~ 20 mm * 1..5 rad/s = 20..100 mm/s, so the smoothed
# law is fully developed except within 1 mm/s of a slip reversal.
DEFAULT_SLIP_WIDTH = 1e-3  # m/s


class CoulombFriction(eqx.Module):
    """Friction force mu * F_N opposing the slip velocity (smoothed with
    ``tanh(v / slip_width)``)."""

    coefficient: Float[Array, ""]
    slip_width: Float[Array, ""]

    def __init__(self, coefficient=0.13, slip_width=DEFAULT_SLIP_WIDTH):
        check_positive("friction coefficient mu", coefficient, allow_zero=True)
        check_positive("friction slip_width [m/s]", slip_width)
        self.coefficient = jnp.asarray(coefficient, dtype=float)
        self.slip_width = jnp.asarray(slip_width, dtype=float)

    def factor(self, slip_velocity: Float[Array, "..."]) -> Float[Array, "..."]:
        """mu * sign(slip): multiply by the normal force to get the friction force
        magnitude opposing the slip."""
        return self.coefficient * smoothing.sign(slip_velocity, self.slip_width)
