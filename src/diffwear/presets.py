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


# --------------------------------------------------------------------------
# Chapter 3 / 5 / 6: the crank-rod joint as a clearance joint
# --------------------------------------------------------------------------

PIN_RADIUS_CH3 = 0.020  # m, Table 3-2 (steel pin R = 20 mm)
CLEARANCES_CH3 = (0.0005e-3, 0.05e-3, 0.5e-3, 5e-3)  # m, Table 3-2 (bushing R 20.0005..25 mm)
FRICTION_CH3 = 0.13  # Table 3-3
RESTITUTION_CH3 = 0.8  # Table 3-3
BUSHING_DEPTH_CH5 = 12.8e-3  # m, Tables 5-2 / 6-3
# The Chapter 3-6 bushing wall is not in the thesis (digest Table 5-2 note).  We
# take a 5 mm PTFE wall (outer radius = bore + 5 mm, so the 5 mm-clearance
# bushing is still a ring): the EFM stiffness k_f = E_W / L scales with 1 / L.
BUSHING_WALL_CH3 = 5e-3  # m, assumption
# The EFM's Kelvin-Voigt damping time is set from the Table 3-3 restitution
# e_r = 0.8 for the bushing body (the rod, 15 kg) on the linearised
# half-circle contact stiffness (ElasticFoundation.damping_time_for_restitution).
CONTACT_LAWS = ("ln", "kv", "efm")


def efm_law(bushing, bore_radius, wall, depth, restitution, mass):
    """ElasticFoundation for a bushing of ``bushing`` material (bore radius,
    wall thickness, depth in m), damped to the restitution ``restitution`` for
    a body of ``mass`` kg (see ElasticFoundation.damping_time_for_restitution)."""
    from .contact import ElasticFoundation

    undamped = ElasticFoundation.from_material(bushing, wall, depth)
    tau = ElasticFoundation.damping_time_for_restitution(
        restitution, undamped.contact_stiffness(bore_radius), mass)
    return ElasticFoundation.from_material(bushing, wall, depth, damping_time=tau)


def clearance_slider_crank(law: str = "ln", clearance=0.5e-3, *, p: SliderCrankParameters = TABLE_2_1,
                           friction=FRICTION_CH3, restitution=RESTITUTION_CH3,
                           pin_radius=PIN_RADIUS_CH3, depth=BUSHING_DEPTH_CH5,
                           wall=BUSHING_WALL_CH3, pin_material=None, bushing_material=None,
                           wear=None, n_theta: int = 180, check: bool = True):
    """Table 2-1 slider-crank with the crank-rod joint as a clearance joint
    (pin on the crank, bushing in the rod: thesis Ch. 3), Table 3-2/3-3 data.

    ``law``: "ln" (Lankarani-Nikravesh, Hertz stiffness from the radius
    difference), "kv" (Kelvin-Voigt with the LN secant stiffness at 1 kN) or
    "efm" (elastic foundation, PTFE wall ``wall``, depth ``depth``).
    Returns (mechanism, y0): y0 is the ideal mechanism's consistent state at
    t = 0 with the pin centred in the bushing (the thesis's start-up).
    """
    from .contact import PTFE, STEEL, CoulombFriction, KelvinVoigt, LankaraniNikravesh, with_clearance
    from .dynamics import consistent_state
    from .errors import InputError

    pin_material = STEEL if pin_material is None else pin_material
    bushing_material = PTFE if bushing_material is None else bushing_material
    pin_radius = jnp.asarray(pin_radius, dtype=float)
    bore = pin_radius + jnp.asarray(clearance, dtype=float)
    if law in ("ln", "kv"):
        contact = LankaraniNikravesh.from_materials(pin_material, bushing_material, pin_radius,
                                                    bore, restitution)
        if law == "kv":
            contact = KelvinVoigt.matched_to(contact)
    elif law == "efm":
        contact = efm_law(bushing_material, bore, wall, depth, restitution, p.m2)
    else:
        raise InputError(f"contact law must be one of {CONTACT_LAWS}, got {law!r}")
    ideal, q_guess = slider_crank(p)
    y_ideal = consistent_state(ideal, q_guess, check=check)
    mech = with_clearance(ideal, "crank_rod", pin_radius=pin_radius, bushing_radius=bore,
                          law=contact, friction=CoulombFriction(friction), wear=wear,
                          n_theta=n_theta)
    q, qd, _ = ideal.split(y_ideal)
    return mech, mech.join(q, qd, mech.initial_aux(q, qd))
