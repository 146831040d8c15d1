"""Archard's wear law, dh/ds = k p (thesis Eq. 4-1)."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive

MM3_PER_NM = 1e-9  # 1 mm^3/(N m) = 1e-9 m^3/(N m) = 1e-9 1/Pa

# Width of the smoothed |relative angular velocity| in the sliding rate, rad/s:
# the thesis joints turn at 1-5 rad/s relative, so 1e-3 rad/s only rounds the
# instants of slip reversal.
SLIP_RATE_WIDTH = 1e-3  # rad/s


class ArchardWear(eqx.Module):
    """Dimensional wear coefficient k [1/Pa = m^3/(N m)] of the bushing.

    The wear depth rate at bushing angle theta is k p(theta) R_b |omega_rel|
    (sliding distance ds = R_b |d(phi_pin - phi_bushing)|, thesis Eq. 5-3).
    ``scale`` multiplies the rate: it is the extrapolation factor A (one
    simulated cycle stands for A real cycles, Eq. 4-18); 1 by default.
    """

    coefficient: Float[Array, ""]

    def __init__(self, coefficient):
        check_positive("wear coefficient k [1/Pa]", coefficient, allow_zero=True)
        self.coefficient = jnp.asarray(coefficient, dtype=float)

    @classmethod
    def from_mm3_per_Nm(cls, k_mm3_per_Nm) -> "ArchardWear":
        """From the tribologists' unit: 5.05e-4 mm^3/(N m) (PTFE on steel)."""
        return cls(jnp.asarray(k_mm3_per_Nm, dtype=float) * MM3_PER_NM)

    def depth_rate(self, pressure, sliding_rate):
        """dh/dt [m/s] at contact pressure ``pressure`` [Pa] (per node) and
        sliding speed ``sliding_rate`` [m/s]: k p ds/dt.  Subclasses change
        the law (e.g. `diffwear.calibrate.effects.ModifiedArchardWear`)."""
        return self.coefficient * pressure * sliding_rate
