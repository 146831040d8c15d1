"""The thesis mechanisms, with every number's source and every assumption.

Source: S. M. Mukras, *Analysis and design of planar multibody systems with
revolute joint wear*, PhD dissertation, University of Florida, 2009; tables as
corrected in the project's thesis digest (the PDF text scrambles several).

Slider-crank conventions (thesis Eq. 2-9): the tabulated lengths l1, l2 are
**half-lengths** (joint to COM).  The crank turns about the origin; the crank
COM is at l1 (cos phi1, sin phi1), the crank pin at 2 l1; the rod COM is l2 from
either end; the slider moves on the global x axis.  Body frames: x from the
body's first joint to its second (crank: pivot -> pin; rod: crank end -> slider
end).  Gravity acts along -y (vertical plane), standard g.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp

from .mechanism import (
    Body,
    Driver,
    Gravity,
    Mechanism,
    RevoluteJoint,
    TranslationalJoint,
)

# Slider inertia is not in the thesis: the slider cannot rotate (phi_3 = 0 is
# a constraint), so its value changes no result; 1 kg m^2 keeps M regular.
SLIDER_INERTIA = 1.0  # kg m^2

THESIS_CRANK_SPEED = math.pi  # rad/s (30 rpm), every thesis example.


class SliderCrankParameters(eqx.Module):
    """Geometry [m], masses [kg], inertias [kg m^2], crank speed [rad/s]."""

    l1: float
    l2: float
    m1: float
    inertia1: float
    m2: float
    inertia2: float
    m3: float
    inertia3: float = SLIDER_INERTIA
    omega: float = THESIS_CRANK_SPEED


TABLE_2_1 = SliderCrankParameters(
    l1=1.00, m1=10.00, inertia1=45.00,   # crank (Table 2-1; digest section 4)
    l2=1.75, m2=15.00, inertia2=35.00,   # connecting rod
    m3=30.00,                            # slider
)
"""Table 2-1 (also 3-1, 5-1, 6-1, 8-1): lengths in m, masses in kg, inertias in
kg m^2.  The "mm"/"g" headers and the 1e-6 inertia factor of some copies are
typesetting errors (the plots, e.g. Fig. 2-5, fit m/kg/kg m^2)."""


def slider_crank(p: SliderCrankParameters = TABLE_2_1, *, gravity: bool = True,
                 extra_forces=()) -> tuple[Mechanism, jnp.ndarray]:
    """The ideal slider-crank and a consistent guess at t = 0 (phi1 = 0).

    Joints: ``ground_crank``, ``crank_rod``, ``rod_slider`` (revolute),
    ``slider_guide`` (translational, slider on the x axis), ``driver``
    (phi1 = omega t).  Bodies: ``crank``, ``rod``, ``slider``.
    """
    bodies = (
        Body("crank", p.m1, p.inertia1),
        Body("rod", p.m2, p.inertia2),
        Body("slider", p.m3, p.inertia3),
    )
    l1, l2 = jnp.asarray(p.l1, dtype=float), jnp.asarray(p.l2, dtype=float)
    zero = jnp.zeros((), dtype=float)
    constraints = (
        RevoluteJoint("ground_crank", "crank", "ground", jnp.stack([-l1, zero]), (0.0, 0.0)),
        RevoluteJoint("crank_rod", "crank", "rod", jnp.stack([l1, zero]), jnp.stack([-l2, zero])),
        RevoluteJoint("rod_slider", "rod", "slider", jnp.stack([l2, zero]), (0.0, 0.0)),
        TranslationalJoint("slider_guide", "slider", "ground"),
        Driver("driver", "crank", p.omega),
    )
    forces = ((Gravity(),) if gravity else ()) + tuple(extra_forces)
    mech = Mechanism(bodies, constraints, forces)
    q_guess = jnp.stack([l1, zero, zero, 2 * l1 + l2, zero, zero, 2 * l1 + 2 * l2, zero, zero])
    return mech, q_guess
