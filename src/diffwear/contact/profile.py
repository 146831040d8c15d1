"""`BushingProfile`: the clearance of a (possibly worn) bushing as a function of angle."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import check_positive, concrete
from ..errors import InputError
from ..mechanism.geometry import grid_angles, grid_directions


class BushingProfile(eqx.Module):
    """Radial clearance c(theta) [m] on a periodic grid of the bushing angle.

    theta_k = 2 pi k / n, k = 0..n-1, measured counter-clockwise from the
    bushing body's x axis (for the thesis slider-crank: the rod axis, pointing
    from the crank end toward the slider).  ``clearance[k] = c0 + wear depth``.
    """

    clearance: Float[Array, " n"]

    def __init__(self, clearance):
        c = jnp.asarray(clearance, dtype=float)
        if c.ndim != 1 or c.shape[0] < 8:
            raise InputError(
                "bushing profile needs a 1-D angular grid of at least 8 points, "
                f"got shape {c.shape}"
            )
        check_positive("bushing clearance c(theta) [m]", c, allow_zero=True)
        self.clearance = c

    @classmethod
    def circular(cls, clearance, n: int = 360) -> "BushingProfile":
        """A round bushing: c(theta) = clearance [m] on ``n`` grid points."""
        if not isinstance(n, int) or n < 8:
            raise InputError(f"angular grid size must be an integer >= 8, got {n!r}")
        v = concrete(clearance)
        if v is not None and v.ndim != 0:
            raise InputError(f"clearance must be a scalar [m], got shape {v.shape}")
        return cls(jnp.full(n, jnp.asarray(clearance, dtype=float)))

    @property
    def n(self) -> int:
        return self.clearance.shape[0]

    @property
    def theta(self) -> Float[Array, " n"]:
        return grid_angles(self.n)

    @property
    def normals(self) -> Float[np.ndarray, "n 2"]:
        """u_k = (cos theta_k, sin theta_k): the unit vectors from the bushing
        centre to its grid points (constants, see `grid_directions`)."""
        return grid_directions(self.n)

    @property
    def tangents(self) -> Float[np.ndarray, "n 2"]:
        """t_k = k x u_k = (-sin theta_k, cos theta_k): the counter-clockwise
        unit tangents at the grid points."""
        u = grid_directions(self.n)
        return np.stack([-u[:, 1], u[:, 0]], axis=-1)

    @property
    def dtheta(self) -> float:
        return 2.0 * jnp.pi / self.n

    def worn(self, depth: Float[Array, " n"]) -> "BushingProfile":
        """The profile after removing ``depth`` [m] of bushing material."""
        return BushingProfile(self.clearance + depth)
