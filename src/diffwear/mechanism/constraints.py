"""Kinematic constraints: ideal revolute and translational joints and a driver.

Each constraint gives its residual rows Phi(q, t) from the poses of the bodies it
names; the `Mechanism` differentiates them (Phi_q, Phi_t, gamma) with JAX, so no
constraint writes its Jacobian by hand.
"""

from __future__ import annotations

import abc
import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import check_finite, concrete
from ..errors import InputError
from .frames import Frames
from .geometry import dot2, perp


def _vec2(what: str, value) -> Float[Array, "2"]:
    arr = jnp.asarray(value, dtype=float)
    if arr.shape != (2,):
        raise InputError(f"{what} must be a 2-vector (body frame, m), got shape {arr.shape}")
    check_finite(what, arr)
    return arr


class AbstractConstraint(eqx.Module):
    """Holonomic constraint rows Phi(q, t) = 0 between named bodies."""

    name: eqx.AbstractVar[str]
    n_rows: eqx.AbstractClassVar[int]

    @property
    @abc.abstractmethod
    def bodies(self) -> tuple[str, ...]:
        """Names of the bodies this constraint connects (may include "ground")."""

    @abc.abstractmethod
    def residual(self, frames: Frames, t: Float[Array, ""]) -> Float[Array, " rows"]:
        """Phi rows at configuration ``frames`` and time ``t``."""


class RevoluteJoint(AbstractConstraint):
    """Ideal pin joint: point ``point_i`` of body i coincides with ``point_j`` of body j.

    Residual: r_i + A_i s_i - r_j - A_j s_j (2 rows, m).  Its multipliers give the
    joint reaction (see `diffwear.dynamics.reaction_wrench`).
    """

    name: str = eqx.field(static=True)
    body_i: str = eqx.field(static=True)
    body_j: str = eqx.field(static=True)
    point_i: Float[Array, "2"]
    point_j: Float[Array, "2"]
    n_rows: ClassVar[int] = 2

    def __init__(self, name: str, body_i: str, body_j: str, point_i, point_j):
        self.name, self.body_i, self.body_j = name, body_i, body_j
        self.point_i = _vec2(f"joint {name!r}: point_i", point_i)
        self.point_j = _vec2(f"joint {name!r}: point_j", point_j)

    @property
    def bodies(self):
        return (self.body_i, self.body_j)

    def residual(self, frames, t):
        return frames.point(self.body_i, self.point_i) - frames.point(self.body_j, self.point_j)


class TranslationalJoint(AbstractConstraint):
    """Prismatic joint: body i slides along ``axis_j`` (body j frame) with fixed
    relative rotation ``angle``.

    Rows: the offset of point i from point j normal to the axis, and
    phi_i - phi_j - angle.  The thesis slider (y = 0, phi = 0) is body i on the
    ground with the defaults.
    """

    name: str = eqx.field(static=True)
    body_i: str = eqx.field(static=True)
    body_j: str = eqx.field(static=True)
    point_i: Float[Array, "2"]
    point_j: Float[Array, "2"]
    axis_j: Float[Array, "2"]
    angle: Float[Array, ""]
    n_rows: ClassVar[int] = 2

    def __init__(self, name, body_i, body_j, point_i=(0.0, 0.0), point_j=(0.0, 0.0),
                 axis_j=(1.0, 0.0), angle=0.0):
        self.name, self.body_i, self.body_j = name, body_i, body_j
        self.point_i = _vec2(f"joint {name!r}: point_i", point_i)
        self.point_j = _vec2(f"joint {name!r}: point_j", point_j)
        axis = _vec2(f"joint {name!r}: axis_j", axis_j)
        v = concrete(axis)
        if v is not None and not np.any(v):
            raise InputError(f"joint {name!r}: axis_j must be non-zero, got {v.tolist()}")
        self.axis_j = axis / jnp.linalg.norm(axis)
        self.angle = jnp.asarray(angle, dtype=float)

    @property
    def bodies(self):
        return (self.body_i, self.body_j)

    def residual(self, frames, t):
        d = frames.point(self.body_i, self.point_i) - frames.point(self.body_j, self.point_j)
        normal = frames.to_global(self.body_j, perp(self.axis_j))
        rel = frames.pose(self.body_i)[2] - frames.pose(self.body_j)[2] - self.angle
        return jnp.stack([dot2(normal, d), rel])


class Driver(AbstractConstraint):
    """Constant-speed rotational driver: phi_body - angle0 - omega t = 0 (rad, rad/s).

    The multiplier gives the driving torque (see `diffwear.dynamics.driver_torque`).
    """

    name: str = eqx.field(static=True)
    body: str = eqx.field(static=True)
    omega: Float[Array, ""]
    angle0: Float[Array, ""]
    n_rows: ClassVar[int] = 1

    def __init__(self, name: str, body: str, omega, angle0=0.0):
        self.name, self.body = name, body
        check_finite(f"driver {name!r}: omega [rad/s]", omega)
        self.omega = jnp.asarray(omega, dtype=float)
        self.angle0 = jnp.asarray(angle0, dtype=float)

    @property
    def bodies(self):
        return (self.body,)

    @property
    def period(self) -> float:
        """One revolution, 2 pi / |omega| [s], as a number (the cycle that wear
        and reports count; infinite for a driver at rest)."""
        speed = abs(float(self.omega))
        return 2 * math.pi / speed if speed > 0 else math.inf

    def residual(self, frames, t):
        return jnp.atleast_1d(frames.pose(self.body)[2] - self.angle0 - self.omega * t)
