"""Planar rotation and cross-product helpers (SI units, radians)."""

from __future__ import annotations

from functools import lru_cache

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float


def grid_angles(n: int) -> Float[Array, " n"]:
    """theta_k = 2 pi k / n, k = 0..n-1 [rad]: the periodic angular grid of the
    bushing profiles and of the FE ring and pin meshes (the FEM wear route maps
    profile nodes to FE nodes one to one because both use this grid)."""
    return 2.0 * jnp.pi * jnp.arange(n) / n


@lru_cache(maxsize=None)
def grid_directions(n: int) -> np.ndarray:
    """(cos theta_k, sin theta_k) on the grid of `grid_angles`, shape (n, 2).

    A NumPy array on purpose: under ``jit`` it enters the program as a
    constant.  ``jnp.cos`` of the grid would be evaluated at run time, because
    XLA does not fold constants built from ``iota``, in every fused kernel
    that used the unit vectors (docs/notes/cpu-kernels.md).  Read-only.
    """
    theta = 2.0 * np.pi * np.arange(n) / n
    out = np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    out.flags.writeable = False
    return out


def rotation(phi: Float[Array, ""]) -> Float[Array, "2 2"]:
    """A(phi): body-frame vectors to the global frame."""
    c, s = jnp.cos(phi), jnp.sin(phi)
    return jnp.array([[c, -s], [s, c]])


def dot2(a: Float[Array | np.ndarray, "... 2"],
         b: Float[Array | np.ndarray, "... 2"]) -> Float[Array | np.ndarray, "..."]:
    """a . b over the last axis of length 2, written out: elementwise arithmetic
    that XLA fuses with its neighbours, where ``a @ b`` on such small operands
    is a kernel launch of its own on CPU (the right-hand side's small products
    cost more in launches than in arithmetic)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]


_PERP_SIGNS = np.array([-1.0, 1.0])


def perp(v: Float[Array, "... 2"]) -> Float[Array, "... 2"]:
    """k x v: the vector rotated by +90 degrees, (-v_y, v_x).  Written as a
    reversal times signs, not a stack of the two entries: elementwise, so
    XLA fuses it with its neighbours (a stack is a concatenation, on CPU
    often a kernel of its own, and more so in batched derivatives)."""
    return v[..., ::-1] * _PERP_SIGNS


def cross(a: Float[Array, "2"], b: Float[Array, "2"]) -> Float[Array, ""]:
    """z-component of a x b."""
    return a[0] * b[1] - a[1] * b[0]


def safe_norm(v: Float[Array, "... 2"], floor: float = 0.0) -> Float[Array, "..."]:
    """|v| over the last axis with a finite gradient at v = 0 (the "double
    where": the gradient there is 0).

    ``floor`` > 0 returns sqrt(|v|^2 + floor^2) - a smooth norm whose width is
    ``floor`` (same units as ``v``).
    """
    sq = jnp.sum(v * v, axis=-1)
    if floor > 0.0:
        return jnp.sqrt(sq + floor * floor)
    is_zero = sq == 0.0
    safe_sq = jnp.where(is_zero, 1.0, sq)
    return jnp.where(is_zero, 0.0, jnp.sqrt(safe_sq))


def safe_angle(v: Float[Array, "... 2"]) -> Float[Array, "..."]:
    """atan2(v_y, v_x) [rad] with a finite gradient at v = 0 (angle 0 there)."""
    is_zero = jnp.all(v == 0.0, axis=-1)
    x = jnp.where(is_zero, 1.0, v[..., 0])
    y = jnp.where(is_zero, 0.0, v[..., 1])
    return jnp.arctan2(y, x)
