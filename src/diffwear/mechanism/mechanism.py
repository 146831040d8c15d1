"""`Mechanism`: bodies + constraints + force elements -> the terms of the DAE.

State layout (one flat array, so that diffrax and `lax.scan` carry one leaf):

    y = [ q (3 nb) | qd (3 nb) | aux (sum of the force elements' n_aux) ]

with q = (x_1, y_1, phi_1, x_2, ...) in the order of ``bodies``.
"""

from __future__ import annotations

from collections import Counter

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..errors import InputError
from .body import GROUND, Body
from .constraints import AbstractConstraint
from .forces import AbstractForceElement, Gravity
from .frames import Frames


class Mechanism(eqx.Module):
    """A planar multibody system.

    Every method is a pure function of arrays; the structure (names, row counts)
    is static, the numbers (masses, lengths, stiffnesses) are pytree leaves and
    may be traced, swept with ``vmap`` or differentiated.
    """

    bodies: tuple[Body, ...]
    constraints: tuple[AbstractConstraint, ...]
    forces: tuple[AbstractForceElement, ...]

    def __init__(self, bodies, constraints=(), forces=()):
        self.bodies = tuple(bodies)
        self.constraints = tuple(constraints)
        self.forces = tuple(forces)

    def __check_init__(self):
        if not self.bodies:
            raise InputError("a mechanism needs at least one body, got none")
        names = [b.name for b in self.bodies]
        dup = [n for n, c in Counter(names).items() if c > 1]
        if dup:
            raise InputError(f"body names must be unique; repeated: {dup}")
        known = set(names) | {GROUND}
        elements = [*self.constraints, *self.forces]
        enames = [e.name for e in elements]
        dup = [n for n, c in Counter(enames).items() if c > 1]
        if dup:
            raise InputError(f"joint / force element names must be unique; repeated: {dup}")
        for element in elements:
            for body in element.bodies:
                if body not in known:
                    raise InputError(
                        f"{type(element).__name__} {element.name!r} names unknown body "
                        f"{body!r}; known bodies: {sorted(known)}"
                    )

    # ------------------------------------------------------------------ sizes
    @property
    def body_names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.bodies)

    @property
    def index(self) -> dict[str, int]:
        return {name: i for i, name in enumerate(self.body_names)}

    @property
    def n_coords(self) -> int:
        return 3 * len(self.bodies)

    @property
    def n_constraints(self) -> int:
        return sum(c.n_rows for c in self.constraints)

    @property
    def n_aux(self) -> int:
        return sum(f.n_aux for f in self.forces)

    @property
    def n_state(self) -> int:
        return 2 * self.n_coords + self.n_aux

    def for_state_jacobian(self) -> "Mechanism":
        """The same mechanism with each force element's `for_state_jacobian`
        (same right-hand side; cheaper full Jacobians, dearer single
        tangents).  The Rosenbrock solvers form their Jacobians on it."""
        return eqx.tree_at(lambda m: m.forces, self,
                           tuple(f.for_state_jacobian() for f in self.forces))

    @property
    def feedback_states(self) -> tuple[int, ...]:
        """Indices of the states the vector field reads: q, qd and each force
        element's `feedback_aux`.  The other states (wear accumulators) have zero
        Jacobian columns; `diffwear.dynamics.ROS3P` forms only these columns."""
        out = list(range(2 * self.n_coords))
        start = 2 * self.n_coords
        for f in self.forces:
            out += [start + i for i in f.feedback_aux]
            start += f.n_aux
        return tuple(out)

    def constraint_rows(self, name: str) -> slice:
        """Rows of Phi (and entries of lambda) that belong to constraint ``name``."""
        return _block(self.constraints, name, lambda c: c.n_rows, "constraint")

    def aux_slice(self, name: str) -> slice:
        """Entries of the aux state that belong to force element ``name``."""
        return _block(self.forces, name, lambda f: f.n_aux, "force element")

    def element(self, name: str):
        elements: tuple[AbstractConstraint | AbstractForceElement, ...] = (
            *self.constraints, *self.forces)
        for e in elements:
            if e.name == name:
                return e
        raise InputError(f"no joint or force element named {name!r}")

    # ------------------------------------------------------------ state packing
    def split(self, y: Float[Array, " s"]):
        n = self.n_coords
        return y[:n], y[n : 2 * n], y[2 * n :]

    def join(self, q, qd, aux=None) -> Float[Array, " s"]:
        aux = jnp.zeros(self.n_aux, dtype=q.dtype) if aux is None else aux
        return jnp.concatenate([q, qd, aux])

    def frames(self, q, qd=None) -> Frames:
        qd = jnp.zeros_like(q) if qd is None else qd
        return Frames(self.index, self.masses, q, qd)

    # ------------------------------------------------------------------ inertia
    @property
    def masses(self) -> Float[Array, " nb"]:
        return jnp.stack([b.mass for b in self.bodies])

    def mass_diagonal(self) -> Float[Array, " n"]:
        """diag(M) = (m_1, m_1, I_1, m_2, ...)."""
        return jnp.stack([jnp.stack([b.mass, b.mass, b.inertia]) for b in self.bodies]).reshape(-1)

    def kinetic_energy(self, qd) -> Float[Array, ""]:
        return 0.5 * jnp.sum(self.mass_diagonal() * qd * qd)

    def potential_energy(self, q) -> Float[Array, ""]:
        """Gravitational potential energy [J] (springs are not included)."""
        frames = self.frames(q)
        terms = [f.potential_energy(frames) for f in self.forces if isinstance(f, Gravity)]
        return sum(terms, jnp.zeros(()))

    # -------------------------------------------------------------- constraints
    def phi(self, q, t) -> Float[Array, " m"]:
        """Phi(q, t): all constraint rows in order."""
        if not self.constraints:
            return jnp.zeros(0, dtype=q.dtype)
        frames = self.frames(q)
        return jnp.concatenate([c.residual(frames, t) for c in self.constraints])

    def phi_q(self, q, t) -> Float[Array, "m n"]:
        return jax.jacfwd(self.phi, argnums=0)(q, t)

    def phi_t(self, q, t) -> Float[Array, " m"]:
        return jax.jvp(lambda tt: self.phi(q, tt), (t,), (jnp.ones_like(t),))[1]

    def phi_dot(self, q, qd, t) -> Float[Array, " m"]:
        """dPhi/dt = Phi_q qd + Phi_t."""
        return jax.jvp(self.phi, (q, t), (qd, jnp.ones_like(t)))[1]

    def gamma(self, q, qd, t) -> Float[Array, " m"]:
        """gamma = -(Phi_q qd)_q qd - 2 Phi_qt qd - Phi_tt.

        This is minus the second derivative of s -> Phi(q + s qd, t + s) at s = 0,
        computed with two nested JVPs (exact, no hand-written Jacobians).
        """
        dt = jnp.ones_like(t)

        def first(qq, tt):
            return jax.jvp(self.phi, (qq, tt), (qd, dt))[1]

        return -jax.jvp(first, (q, t), (qd, dt))[1]

    # ------------------------------------------------------------------ forces
    def applied_forces(self, q, qd, aux, t):
        """(Q_A of length n, d aux/dt): the sum over the force elements."""
        frames = self.frames(q, qd)
        total = frames.zero_forces()
        daux, start = [], 0
        for f in self.forces:
            a = aux[start : start + f.n_aux]
            start += f.n_aux
            qf, da = f.forces(frames, a, t)
            total = total + qf
            daux.append(da)
        daux = jnp.concatenate(daux) if daux else jnp.zeros(0, dtype=q.dtype)
        return total.reshape(-1), daux

    def initial_aux(self, q, qd) -> Float[Array, " a"]:
        frames = self.frames(q, qd)
        parts = [f.initial_aux(frames) for f in self.forces]
        return jnp.concatenate(parts) if parts else jnp.zeros(0, dtype=q.dtype)


def _block(elements, name: str, size, kind: str) -> slice:
    """The slice of element ``name`` in the concatenation of the elements' blocks."""
    start = 0
    for e in elements:
        if e.name == name:
            return slice(start, start + size(e))
        start += size(e)
    raise InputError(f"no {kind} named {name!r}; have {[e.name for e in elements]}")
