"""A contact law's response, differentiated through the pin's motion once.

A law's force depends on the mechanism's state only through the pin's motion
in the bushing (offset, its rate, relative spin: 5 numbers) and the law's
memory.  A Jacobian of the mechanism's right-hand side (18 state directions
on the three-body rig, for the Rosenbrock solvers) would push every direction
through the law's whole evaluation (180 springs for the elastic foundation).
`LinearisedLaw` forms the law's Jacobian with respect to those few inputs
once per evaluation and maps each direction through it: one small matrix
product per direction.  Directions in the law's parameters, the radii, the
bushing profile or the friction (design derivatives) are pushed through the
law itself.  For a few directions (a gradient in 1-4 design parameters) the
plain law is cheaper, so only the Rosenbrock solvers' linearisations use it
(`Mechanism.for_state_jacobian`); their stages and tangents use the plain law.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jax.flatten_util import ravel_pytree

from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .laws import AbstractContactLaw
from .profile import BushingProfile


def _response(motion, memory, radii, law: AbstractContactLaw, profile: BushingProfile,
              friction: CoulombFriction) -> ContactResult:
    return law.evaluate(PinKinematics(*motion, *radii), memory, profile, friction)


_evaluate = eqx.filter_custom_jvp(_response)


def _dense(primal, tangent):
    """``tangent`` with its symbolic zeros (None) as zero arrays."""
    if tangent is None:
        return jax.tree.map(jnp.zeros_like, primal)
    return jax.tree.map(lambda t, p: jnp.zeros_like(p) if t is None else t, tangent, primal,
                        is_leaf=lambda v: v is None)


@_evaluate.def_jvp
def _evaluate_jvp(primals, tangents):
    motion, memory, *parameters = primals
    t_motion, t_memory, *t_parameters = tangents
    x, unravel = ravel_pytree((motion, memory))

    def response(x):
        return _response(*unravel(x), *parameters)

    out, linear = jax.linearize(response, x)
    columns = jax.vmap(linear)(jnp.eye(x.size, dtype=x.dtype))  # each leaf: (len(x), ...)
    dx, _ = ravel_pytree((_dense(motion, t_motion), _dense(memory, t_memory)))
    t_out = jax.tree.map(lambda c: jnp.tensordot(dx, c, axes=1), columns)
    if jax.tree.leaves(t_parameters):
        _, t_par = eqx.filter_jvp(lambda *p: _response(motion, memory, *p), tuple(parameters),
                                  tuple(t_parameters))
        t_out = jax.tree.map(lambda tp, t: t if tp is None else t + tp, t_par, t_out,
                             is_leaf=lambda v: v is None)
    return out, t_out


class LinearisedLaw(AbstractContactLaw):
    """``law`` with the forward-mode rule of the module notes (same values)."""

    law: AbstractContactLaw

    @property
    def n_memory(self) -> int:
        return self.law.n_memory

    def initial_memory(self):
        return self.law.initial_memory()

    def evaluate(self, kin, memory, profile, friction):
        return _evaluate((kin.offset, kin.offset_rate, kin.omega), memory,
                         (kin.pin_radius, kin.bushing_radius), self.law, profile, friction)
