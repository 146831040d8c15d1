"""`Frames`: named access to body poses, velocities and points during a trace.

Force elements and constraints address bodies by name.  ``Frames`` holds the
coordinate arrays, one row per body, and turns point forces into generalised
forces.  The ground is no row: a lookup of ``"ground"`` resolves while tracing
to the fixed frame (zero pose and velocity, identity rotation), so it costs
no operations in the compiled right-hand side.  ``Frames`` is built inside
the traced right-hand side; it is not a pytree.
"""

from __future__ import annotations

from collections.abc import Mapping

import jax.numpy as jnp
from jaxtyping import Array, Float

from .body import GROUND
from .geometry import cross, perp


class Frames:
    def __init__(
        self,
        index: Mapping[str, int],
        masses: Float[Array, " nb"],
        q: Float[Array, " n"],
        qd: Float[Array, " n"],
    ):
        self._index = index
        self.masses = masses
        self.n_bodies = q.shape[0] // 3
        self.q = q.reshape(-1, 3)
        self.qd = qd.reshape(-1, 3)
        # cos and sin of every body angle, once per evaluation: every rotation
        # of a point, force or offset reads them
        self._cos, self._sin = jnp.cos(self.q[:, 2]), jnp.sin(self.q[:, 2])

    def row(self, name: str) -> int | None:
        """The body's row of ``q`` and of a generalised force; None for the ground."""
        return None if name == GROUND else self._index[name]

    def pose(self, name: str) -> Float[Array, "3"]:
        r = self.row(name)
        return jnp.zeros(3, self.q.dtype) if r is None else self.q[r]

    def velocity(self, name: str) -> Float[Array, "3"]:
        r = self.row(name)
        return jnp.zeros(3, self.qd.dtype) if r is None else self.qd[r]

    def to_global(self, name: str, s: Float[Array, "2"]) -> Float[Array, "2"]:
        """A(phi) s: the body-frame vector ``s`` of body ``name`` in the global
        frame (written out, not a 2 x 2 matrix product: see `geometry.dot2`)."""
        r = self.row(name)
        return s if r is None else self._cos[r] * s + self._sin[r] * perp(s)

    def to_body(self, name: str, v: Float[Array, "2"]) -> Float[Array, "2"]:
        """A(phi)^T v: the global vector ``v`` in the frame of body ``name``."""
        r = self.row(name)
        return v if r is None else self._cos[r] * v - self._sin[r] * perp(v)

    def point(self, name: str, s: Float[Array, "2"]) -> Float[Array, "2"]:
        """Global position of the body-fixed point ``s`` (body frame)."""
        if self.row(name) is None:
            return s
        return self.pose(name)[:2] + self.to_global(name, s)

    def point_velocity(self, name: str, s: Float[Array, "2"]) -> Float[Array, "2"]:
        if self.row(name) is None:
            return jnp.zeros_like(s)
        v = self.velocity(name)
        return v[:2] + v[2] * perp(self.to_global(name, s))

    def zero_forces(self) -> Float[Array, "nb 3"]:
        return jnp.zeros_like(self.q)

    def wrench(
        self,
        name: str,
        force: Float[Array, "2"],
        at: Float[Array, "2"] | None = None,
        torque: Float[Array, ""] | float = 0.0,
    ) -> Float[Array, "nb 3"]:
        """Generalised force of ``force`` applied at global point ``at`` (default:
        the COM) plus a pure ``torque``, as rows (Fx, Fy, moment about the COM);
        on the ground, none."""
        r = self.row(name)
        if r is None:
            return self.zero_forces()
        arm = jnp.zeros(2) if at is None else at - self.q[r, :2]
        row = jnp.array([force[0], force[1], cross(arm, force) + torque])
        return self.zero_forces().at[r].add(row)
