"""`AbstractWearModifier`: what changes a wear model's cycle wear from outside
the model (the calibration's candidate effects and learned discrepancy).

A model evaluates the wear of one cycle at a profile; a modifier changes it
by two hooks, and the mechanism it runs on by a third that its owner applies
when it builds the mechanism:

* ``growth`` (on the profile): the clearance the cycle sees is c0 + g h, h
  the worn depth (g = 1: none; creep grows it without mass loss);
* ``rate`` (on the rate): a factor per profile node of the wear over the
  real cycles [n, n + dn] of a step, from the worn profile and the joint's
  geometry (`JointGeometry`);
* the mechanism (its forces, its wear law) is the owner's: a model takes the
  mechanism it is given.

The rate over a step must be known when the step is taken, so a model takes
a modifier only with steps fixed in advance (`QuasiStatic` with a ``grid``,
`Dynamic` with a constant extrapolation).  The linearly implicit step is
then (I + dn g G A) dh = dn G w(g h), G = diag(rate factor).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float


class JointGeometry(eqx.Module):
    """What a rate factor may read of the wearing joint: the profile's node
    angles ``theta`` [rad], the bushing's radius and depth [m]."""

    theta: Float[Array, " n"]
    bushing_radius: Float[Array, ""]
    bushing_depth: Float[Array, ""]

    @classmethod
    def of(cls, joint) -> "JointGeometry":
        """The geometry of clearance joint ``joint`` (a `ClearanceJoint`; its
        bushing depth that of the foundation that wears, `wear_parts`)."""
        from .cycle import wear_parts

        foundation, _ = wear_parts(joint)
        return cls(joint.profile.theta, joint.bushing_radius, foundation.depth)


class AbstractWearModifier(eqx.Module):
    """A change of a model's cycle wear (module notes); the identity here."""

    def growth(self):
        """g: the clearance profile the cycle sees is c0 + g h."""
        return 1.0

    def rate(self, h: Float[Array, " n"], n, dn, geometry: JointGeometry):
        """The factor per node of the rate over the real cycles [n, n + dn]
        at worn profile ``h``."""
        return jnp.ones_like(h)


def modulated(cw, h, n, dn, modifier: AbstractWearModifier, geometry: JointGeometry):
    """The cycle wear ``cw`` (one joint) with ``modifier``'s rate factor over
    [n, n + dn]; its response (if any) scaled by the growth and the factor."""
    g = modifier.rate(h[0], n, dn, geometry)
    response = cw.response
    if response is not None:
        response = (modifier.growth() * g[:, None] * response[0],)
    return eqx.tree_at(lambda c: (c.rate, c.response), cw, ((g * cw.rate[0],), response),
                       is_leaf=lambda x: x is None)


__all__ = ["AbstractWearModifier", "JointGeometry", "modulated"]
