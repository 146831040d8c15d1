"""Rigid bodies.  Coordinates of body i: q_i = (x_i, y_i, phi_i) of its centre of mass."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive
from ..errors import InputError

GROUND = "ground"
"""Reserved body name: the fixed frame (coordinates identically zero)."""


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
        self.name = name
        self.mass = jnp.asarray(mass, dtype=float)
        self.inertia = jnp.asarray(inertia, dtype=float)
