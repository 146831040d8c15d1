"""Applied-force elements: gravity and linear springs.

A force element maps the state to generalised forces (one row of
(Fx, Fy, moment about COM) per body: a force on the ground is dropped).
Elements may carry auxiliary ODE states (``n_aux``), e.g. the impact-velocity
memory of a contact law or the wear accumulators of a clearance joint; their
derivatives are returned next to the forces.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_finite, check_positive
from .constraints import _vec2
from .frames import Frames
from .geometry import safe_norm

STANDARD_GRAVITY = 9.80665  # m/s^2, CGPM 1901 conventional value.


class AbstractForceElement(eqx.Module):
    """Generalised forces Q_A(q, qd, aux, t) (and d aux/dt) from one element."""

    name: eqx.AbstractVar[str]

    @property
    def n_aux(self) -> int:
        """Number of auxiliary ODE states (static: derived from array shapes)."""
        return 0

    @property
    def feedback_aux(self) -> tuple[int, ...]:
        """Entries of the element's aux state (0 .. n_aux - 1) that its forces or
        aux rates read.  The others are integrals of the motion that never feed
        back (e.g. wear accumulators); a solver may take their Jacobian columns
        as zero.  Default: all of them."""
        return tuple(range(self.n_aux))

    def for_state_jacobian(self) -> "AbstractForceElement":
        """The element with the same forces, differentiated cheaply along many
        state directions at once (a Jacobian of the right-hand side); default:
        itself.  A clearance joint maps the directions through its contact
        law's Jacobian in the pin's motion (`diffwear.contact.linearised`)."""
        return self

    @property
    @abc.abstractmethod
    def bodies(self) -> tuple[str, ...]:
        """Bodies the element acts on ("ground" allowed)."""

    def initial_aux(self, frames: Frames) -> Float[Array, " n_aux"]:
        """Auxiliary state at the start of a simulation."""
        return jnp.zeros(self.n_aux)

    @abc.abstractmethod
    def forces(
        self, frames: Frames, aux: Float[Array, " n_aux"], t: Float[Array, ""]
    ) -> tuple[Float[Array, "nb 3"], Float[Array, " n_aux"]]:
        """(generalised forces, one row per body; d aux / dt)."""


class Gravity(AbstractForceElement):
    """Uniform gravity on every body of the mechanism: m g at each COM
    (default g = (0, -g_n), i.e. the mechanism moves in a vertical plane)."""

    name: str = eqx.field(static=True)
    g: Float[Array, "2"]

    def __init__(self, g=(0.0, -STANDARD_GRAVITY), name: str = "gravity"):
        self.name = name
        self.g = _vec2("gravity: g [m/s^2]", g)

    @property
    def bodies(self):
        return ()

    def forces(self, frames, aux, t):
        q = frames.zero_forces()
        return q.at[:, :2].set(frames.masses[:, None] * self.g), aux

    def potential_energy(self, frames: Frames) -> Float[Array, ""]:
        """-sum m g . r [J]: zero at the origin."""
        return -jnp.sum(frames.masses * (frames.q[:, :2] @ self.g))


class LinearSpring(AbstractForceElement):
    """Linear spring(-damper) between point i of body i and point j of body j.

    Tension T = k (L - L0) + c dL/dt pulls the points together for T > 0
    (k in N/m, L0 in m, c in N s/m).  The length uses a smooth norm
    (width 1e-12 m) so that coincident points give a finite gradient.
    """

    name: str = eqx.field(static=True)
    body_i: str = eqx.field(static=True)
    body_j: str = eqx.field(static=True)
    point_i: Float[Array, "2"]
    point_j: Float[Array, "2"]
    stiffness: Float[Array, ""]
    free_length: Float[Array, ""]
    damping: Float[Array, ""]

    def __init__(self, name, body_i, point_i, body_j, point_j, stiffness, free_length, damping=0.0):
        self.name, self.body_i, self.body_j = name, body_i, body_j
        self.point_i = _vec2(f"spring {name!r}: point_i", point_i)
        self.point_j = _vec2(f"spring {name!r}: point_j", point_j)
        check_positive(f"spring {name!r}: stiffness [N/m]", stiffness, allow_zero=True)
        check_finite(f"spring {name!r}: free_length [m]", free_length)
        check_positive(f"spring {name!r}: damping [N s/m]", damping, allow_zero=True)
        self.stiffness = jnp.asarray(stiffness, dtype=float)
        self.free_length = jnp.asarray(free_length, dtype=float)
        self.damping = jnp.asarray(damping, dtype=float)

    @property
    def bodies(self):
        return (self.body_i, self.body_j)

    def forces(self, frames, aux, t):
        pi = frames.point(self.body_i, self.point_i)
        pj = frames.point(self.body_j, self.point_j)
        d = pj - pi
        length = safe_norm(d, floor=1e-12)
        u = d / length
        rate = (frames.point_velocity(self.body_j, self.point_j)
                - frames.point_velocity(self.body_i, self.point_i)) @ u  # dL/dt
        tension = self.stiffness * (length - self.free_length) + self.damping * rate
        f_i = tension * u
        q = frames.wrench(self.body_i, f_i, at=pi) + frames.wrench(self.body_j, -f_i, at=pj)
        return q, aux


class GuideFriction(AbstractForceElement):
    """Coulomb friction of a body sliding in a ground guide along ``axis``:
    F = -mu N tanh(v / v_s) axis at the body's centre of mass.

    ``normal_force`` N [N] is given, not computed from the guide's constraint
    reaction (e.g. the slider's weight when the guide carries it).  The sign
    function is smoothed over ``slip_width`` v_s [m/s]; at ``coefficient`` 0 the
    element adds exactly zero.
    """

    name: str = eqx.field(static=True)
    body: str = eqx.field(static=True)
    coefficient: Float[Array, ""]
    normal_force: Float[Array, ""]
    axis: Float[Array, "2"]
    slip_width: Float[Array, ""]

    def __init__(self, name, body, coefficient, normal_force, axis=(1.0, 0.0), slip_width=1e-2):
        self.name, self.body = name, body
        check_finite(f"guide friction {name!r}: coefficient", coefficient)
        check_positive(f"guide friction {name!r}: normal_force [N]", normal_force,
                       allow_zero=True)
        check_positive(f"guide friction {name!r}: slip_width [m/s]", slip_width)
        a = _vec2(f"guide friction {name!r}: axis", axis)
        self.coefficient = jnp.asarray(coefficient, dtype=float)
        self.normal_force = jnp.asarray(normal_force, dtype=float)
        self.axis = a / safe_norm(a, floor=1e-12)
        self.slip_width = jnp.asarray(slip_width, dtype=float)

    @property
    def bodies(self):
        return (self.body,)

    def forces(self, frames, aux, t):
        v = frames.velocity(self.body)[:2] @ self.axis
        f = -self.coefficient * self.normal_force * jnp.tanh(v / self.slip_width) * self.axis
        return frames.wrench(self.body, f), aux
