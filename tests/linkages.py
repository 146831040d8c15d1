"""Test mechanisms built only from the core API (no closed-form equations).

Imported by the tests (pytest puts ``tests/`` on ``sys.path``); not collected.
"""

from __future__ import annotations

import math

import jax.numpy as jnp

from diffwear.mechanism import Body, Driver, Gravity, Mechanism, RevoluteJoint

# Crank-rocker proportions [m]: crank a, coupler b, rocker c, ground link d.
# Grashof with the shortest link as the crank: s + l = a + d = 0.50 <= b + c = 0.65,
# so the crank turns fully; the transmission angle stays within about 54..100 deg
# (cos mu = (b^2 + c^2 - (d -+ a)^2) / (2 b c)), far from the toggle positions.
CRANK, COUPLER, ROCKER, GROUND_LINK = 0.10, 0.35, 0.30, 0.40

# Links are uniform slender bars: 25 mm x 10 mm steel flat bar,
# 7850 kg/m^3 * 2.5e-4 m^2 = 1.96 kg/m, rounded; I = m L^2 / 12 about the COM.
LINEAR_DENSITY = 2.0  # kg/m
CRANK_SPEED = 2.0 * math.pi  # rad/s: one revolution per second


def bar(name: str, length: float) -> Body:
    mass = LINEAR_DENSITY * length
    return Body(name, mass, mass * length**2 / 12.0)


def four_bar(a=CRANK, b=COUPLER, c=ROCKER, d=GROUND_LINK, *, omega=CRANK_SPEED, gravity=True):
    """Four-bar linkage, crank driven at ``omega`` from phi = 0 at t = 0.

    Ground pivots O2 = (0, 0) and O4 = (d, 0).  Each link's body frame runs
    along the link from its first joint to its second (crank O2 -> A, coupler
    A -> B, rocker O4 -> B), COM at the midpoint.  Returns the mechanism and a
    rough hand-sketched guess of the open assembly (B above the ground line)
    at t = 0, for `consistent_state` to refine.
    """
    bodies = (bar("crank", a), bar("coupler", b), bar("rocker", c))
    constraints = (
        RevoluteJoint("O2", "crank", "ground", (-a / 2, 0.0), (0.0, 0.0)),
        RevoluteJoint("A", "crank", "coupler", (a / 2, 0.0), (-b / 2, 0.0)),
        RevoluteJoint("B", "coupler", "rocker", (b / 2, 0.0), (c / 2, 0.0)),
        RevoluteJoint("O4", "rocker", "ground", (-c / 2, 0.0), (d, 0.0)),
        Driver("driver", "crank", omega),
    )
    forces = (Gravity(),) if gravity else ()
    q_guess = jnp.array([a / 2, 0.0, 0.0, 0.2, 0.15, 0.9, d - 0.05, 0.15, 1.9])
    return Mechanism(bodies, constraints, forces), q_guess


def seated_rotor(clearance, modulus, mu=0.13):
    """A driven, unbalanced 10 kg rotor on an EFM clearance pivot (pin R 10 mm,
    PTFE-like bushing of Young's modulus ``modulus``), the pin seated against
    the wall at the start so that the contact never opens (gravity plus the
    centripetal load): a smooth, well-conditioned problem for derivatives.
    Returns (mechanism, y0); the pivot is named "pivot"."""
    from diffwear.contact import PTFE, ClearanceJoint, CoulombFriction, Material
    from diffwear.presets import efm_law

    law = efm_law(Material(modulus, PTFE.poisson_ratio), 0.01 + clearance, 5e-3, 0.01, 0.3, 10.0)
    joint = ClearanceJoint("pivot", "rotor", (-0.05, 0.0), "ground", (0.0, 0.0), 0.01,
                           0.01 + clearance, law, friction=CoulombFriction(mu), n_theta=72)
    mech = Mechanism((Body("rotor", 10.0, 0.1),), (Driver("drive", "rotor", 2 * jnp.pi),),
                     (Gravity(), joint))
    q = jnp.stack([jnp.asarray(0.05), -clearance - 1e-6, jnp.asarray(0.0)])
    qd = jnp.array([0.0, 0.05 * 2 * jnp.pi, 2 * jnp.pi])
    return mech, mech.join(q, qd, mech.initial_aux(q, qd))
