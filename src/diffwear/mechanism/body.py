"""Rigid bodies.  Coordinates of body i: q_i = (x_i, y_i, phi_i) of its centre of mass."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive, concrete
from ..errors import InputError

GROUND = "ground"
"""Reserved body name: the fixed frame (coordinates identically zero)."""

MIN_GYRATION = 1e-6
"""Smallest radius of gyration sqrt(inertia / mass) [m] accepted: below 1 um
the body's rotation is numerically singular beside its translation (the mass
matrix's condition number, (1 m / 1 um)^2 = 1e12 for a metre-scale
mechanism, leaves float64 too few digits), and the solve fails later with a
message that cannot name the body."""


class Body(eqx.Module):
    """A rigid planar body: mass [kg] and centroidal moment of inertia [kg m^2]."""

    name: str = eqx.field(static=True)
    mass: Float[Array, ""]
    inertia: Float[Array, ""]

    def __init__(self, name: str, mass, inertia):
        if not isinstance(name, str) or not name:
            raise InputError(f"body name must be a non-empty string, got {name!r}")
        if name == GROUND:
            raise InputError(f"body name {GROUND!r} is reserved for the fixed frame")
        check_positive(f"body {name!r}: mass [kg]", mass)
        check_positive(f"body {name!r}: inertia [kg m^2]", inertia)
        m, j = concrete(mass), concrete(inertia)
        if m is not None and j is not None and float(j) < float(m) * MIN_GYRATION**2:
            raise InputError(
                f"body {name!r}: inertia [kg m^2] = {float(j):.3g} gives a radius of gyration "
                f"of {(float(j) / float(m)) ** 0.5:.3g} m for its {float(m):g} kg; allowed: "
                f">= mass x (1 um)^2 = {float(m) * MIN_GYRATION**2:.3g} kg m^2 (a rotation "
                "that small is numerically singular)")
        self.name = name
        self.mass = jnp.asarray(mass, dtype=float)
        self.inertia = jnp.asarray(inertia, dtype=float)
