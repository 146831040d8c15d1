"""The thesis mechanisms, with every number's source and every assumption.

Source: S. M. Mukras, *Analysis and design of planar multibody systems with
revolute joint wear*, PhD dissertation, University of Florida, 2009.  Several
tables are typeset with scrambled or mislabelled entries; the values here are
the ones consistent with the thesis's own plots and text (noted where they
differ from the printed table).

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

from ._checks import float_leaf
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
    l1=1.00, m1=10.00, inertia1=45.00,   # crank (Table 2-1)
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
# The Chapter 3-6 bushing outer radius is not in the thesis (Table 5-2 gives
# none).  We scale the rig bushing (Table 7-2: outer / inner = 15.875 / 9.533 =
# 1.665) to the 20.005 mm bore of the wear example: outer radius 33.31 mm, wall
# L = 13.31 mm.  The EFM stiffness k_f = E_W / L scales with 1 / L.
WEAR_5000_OUTER_RADIUS = 20.005e-3 * 15.875 / 9.533  # m (= 33.31 mm, our choice)
BUSHING_WALL_CH3 = WEAR_5000_OUTER_RADIUS - 20.005e-3  # m (= 13.31 mm)
# The EFM's Kelvin-Voigt damping time is set from the Table 3-3 restitution
# e_r = 0.8 for the bushing body (the rod, 15 kg) on the linearised
# half-circle contact stiffness (ElasticFoundation.damping_time_for_restitution).
CONTACT_LAWS = ("ln", "kv", "efm")


def efm_law(bushing, bore_radius, wall, depth, restitution, mass, **kwargs):
    """ElasticFoundation for a bushing of ``bushing`` material (bore radius,
    wall thickness, depth in m), damped to the restitution ``restitution`` for
    a body of ``mass`` kg (see ElasticFoundation.damping_time_for_restitution).
    ``kwargs`` (e.g. ``penetration_width``) go to `ElasticFoundation`."""
    from .contact import ElasticFoundation

    undamped = ElasticFoundation.from_material(bushing, wall, depth)
    tau = ElasticFoundation.damping_time_for_restitution(
        restitution, undamped.contact_stiffness(bore_radius), mass)
    return ElasticFoundation.from_material(bushing, wall, depth, damping_time=tau, **kwargs)


def clearance_slider_crank(law: str = "ln", clearance=0.5e-3, *,
                           p: SliderCrankParameters = TABLE_2_1,
                           friction=FRICTION_CH3, restitution=RESTITUTION_CH3,
                           pin_radius=PIN_RADIUS_CH3, depth=BUSHING_DEPTH_CH5,
                           wall=BUSHING_WALL_CH3, materials=None, wear=None,
                           n_theta: int = 180, check: bool = True):
    """Table 2-1 slider-crank with the crank-rod joint as a clearance joint
    (pin on the crank, bushing in the rod: thesis Ch. 3), Table 3-2/3-3 data.

    ``law``: "ln" (Lankarani-Nikravesh, Hertz stiffness from the radius
    difference), "kv" (Kelvin-Voigt with the LN secant stiffness at 1 kN) or
    "efm" (elastic foundation, PTFE wall ``wall``, depth ``depth``);
    ``materials``: (pin, bushing) `Material`s, default (steel, PTFE).
    Returns (mechanism, y0): y0 is the ideal mechanism's consistent state at
    t = 0 with the pin centred in the bushing (the thesis's start-up).
    """
    from .contact import (
        PTFE,
        STEEL,
        AbstractContactLaw,
        CoulombFriction,
        KelvinVoigt,
        LankaraniNikravesh,
        centred_state,
        with_clearance,
    )
    from .dynamics import consistent_state
    from .errors import InputError

    pin_material, bushing_material = (STEEL, PTFE) if materials is None else materials
    pin_radius = jnp.asarray(pin_radius, dtype=float)
    bore = pin_radius + jnp.asarray(clearance, dtype=float)
    contact: AbstractContactLaw
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
    return mech, centred_state(ideal, y_ideal, mech)


# ============================================================ wear joints
class WearJointDesign(eqx.Module):
    """A PTFE-bushing clearance joint with Archard wear, all numbers as arrays
    (so that studies can differentiate w.r.t. them).

    k: wear coefficient [1/Pa = m^3/(N m)]; clearance: radial c0 [m];
    depth: bushing depth (axial length) [m]; diameter: pin diameter [m];
    wall: elastic layer thickness L = outer minus inner bushing radius [m]
    (EFM stiffness E_W / L, and the wear limit); mu: friction coefficient;
    restitution: e_r for the EFM damping (thesis Table 3-3: 0.8).
    """

    k: jnp.ndarray
    clearance: jnp.ndarray
    depth: jnp.ndarray
    diameter: jnp.ndarray
    wall: jnp.ndarray
    mu: jnp.ndarray
    restitution: jnp.ndarray

    def __init__(self, k, clearance, depth, diameter, wall, mu=0.13, restitution=0.8):
        f = float_leaf
        self.k, self.clearance, self.depth = f(k), f(clearance), f(depth)
        self.diameter, self.wall, self.mu, self.restitution = (
            f(diameter), f(wall), f(mu), f(restitution))

    @property
    def pin_radius(self):
        return 0.5 * self.diameter

    @property
    def bushing_radius(self):
        return 0.5 * self.diameter + self.clearance


def with_wear_joint(mech: Mechanism, design: WearJointDesign, *, joint: str = "crank_rod",
                    bushing_body: str | None = None, damping_mass=None,
                    n_theta: int = 180, penetration_width=None) -> Mechanism:
    """Swap the ideal revolute ``joint`` for an EFM clearance joint with Archard wear.

    EFM (thesis Ch. 6): PTFE bushing (Table 3-2 / 7-2), foundation stiffness
    E_W / wall.  Damping time from the restitution coefficient with the
    half-circle contact stiffness and ``damping_mass`` (default: the mass of the
    bushing body).  Friction Coulomb mu.  ``bushing_body``: the body carrying
    the bushing (default: the joint's second body; see `with_clearance`).
    ``penetration_width`` [m]: the contact-onset smoothing band of the EFM
    springs (default `ElasticFoundation`'s).
    """
    from .contact import PTFE, CoulombFriction, with_clearance
    from .wear import ArchardWear

    old = mech.element(joint)
    bushing_body = old.body_j if bushing_body is None else bushing_body
    if damping_mass is None:
        damping_mass = next(b.mass for b in mech.bodies if b.name == bushing_body)
    extra = {} if penetration_width is None else {"penetration_width": penetration_width}
    law = efm_law(PTFE, design.bushing_radius, design.wall, design.depth, design.restitution,
                  damping_mass, **extra)
    return with_clearance(mech, joint, bushing_body=bushing_body, pin_radius=design.pin_radius,
                          bushing_radius=design.bushing_radius, law=law,
                          friction=CoulombFriction(design.mu), wear=ArchardWear(design.k),
                          n_theta=n_theta)


K_PTFE_MM3_PER_NM = 5.05e-4  # Tables 5-2/6-3/7-2: PTFE on steel, mm^3/(N m)
PTFE_DENSITY = 2250.0        # kg/m^3 (Table 7-2: 2.25 g/cm^3)

# Wear example of Ch. 5/6 (Tables 5-2, 5-3, 6-3): crank-rod
# clearance 0.005 mm, pin R 20 mm, depth 12.8 mm, k 5.05e-4 mm^3/(N m), mu 0.13,
# 30 rpm, 5,000 cycles; bushing wall as chosen above (BUSHING_WALL_CH3).
WEAR_5000 = WearJointDesign(
    k=K_PTFE_MM3_PER_NM * 1e-9, clearance=0.005e-3, depth=BUSHING_DEPTH_CH5, diameter=40.0e-3,
    wall=BUSHING_WALL_CH3, mu=FRICTION_CH3, restitution=RESTITUTION_CH3,
)
WEAR_5000_CYCLES = 5000


# ============================================================ Chapter 7 rig
TABLE_7_1 = SliderCrankParameters(
    l1=0.0381, m1=0.4045, inertia1=204.0e-6,   # crank (Table 7-1)
    l2=0.1016, m2=0.8175, inertia2=5500.0e-6,  # connecting rod
    m3=8.5,                                    # slider
)
"""Table 7-1 rig.  0.0381 / 0.1016 m (1.5 in / 4.0 in) are read as
**half-lengths** (thesis Eq. 2-9 convention): the inertias favour it (a
0.1016 m joint-to-joint rod of 0.8175 kg cannot reach I = 5.5e-3 kg m^2 even
with all its mass at the ends: I <= 2.1e-3; a uniform crank of I = 2.04e-4 and
0.4045 kg is ~78 mm long, i.e. 2 x 38.1 mm).  `TABLE_7_1_JOINT_TO_JOINT` is the
other reading (lengths halved)."""

TABLE_7_1_JOINT_TO_JOINT = SliderCrankParameters(
    l1=0.0381 / 2, m1=0.4045, inertia1=204.0e-6,
    l2=0.1016 / 2, m2=0.8175, inertia2=5500.0e-6, m3=8.5,
)

# Table 7-2: pin R 9.500 mm, bushing inner R 9.533 mm, outer R 15.875 mm,
# depth 13.1 mm, PTFE on hardened steel, mu 0.13, k 5.05e-4 mm^3/(N m).
RIG_JOINT = WearJointDesign(
    k=K_PTFE_MM3_PER_NM * 1e-9, clearance=(9.533 - 9.500) * 1e-3, depth=13.1e-3,
    diameter=19.0e-3, wall=(15.875 - 9.533) * 1e-3, mu=0.13, restitution=0.8,
)
RIG_CYCLES = 21_400          # Table 7-3
RIG_SPRING_STIFFNESS = 525.4  # N/m, Table 7-3

# The spring: "attached to the slider" to raise the joint force and keep the
# pin in contact (thesis Ch. 7); attachment, orientation and free length are
# not given.  We model a tension spring on the slider axis from the slider
# centre to a ground anchor at x = RIG_SPRING_ANCHOR_X: it pulls the slider
# AWAY from the crank (+x), so the rod stays in tension and the bushing wears
# one-sidedly near theta ~ pi (the "left side" of the thesis).  The force on
# the slider is k_s (ANCHOR_X - x_slider - L0) > 0; only ANCHOR_X - L0 matters.
RIG_SPRING_ANCHOR_X = 1.0  # m (our choice, far beyond the stroke 0.127..0.279 m)

# Free length L0 [m], CALIBRATED (not in the thesis): the value for which the
# model's worn volume after 21,400 cycles equals the thesis models' 106.7 mm^3
# (Table 7-4: FEM 106.71, EFM 106.68).  Obtained by `diffwear.studies.rig_21400
# .calibrate_free_length` (secant iteration on the coarse evolution, volume
# being nearly linear in the spring force), then checked with the full study.
RIG_SPRING_FREE_LENGTH = 0.5479  # m, calibrated (see above)
# Calibration record: secant on L0 with A = 2140 (10 dynamic cycles): 0.50 m ->
# 129.17 mm^3, 0.56 m -> 102.96 mm^3 (dV/dL0 ~ -437 mm^3/m), converged at
# 0.55175 m -> 106.69 mm^3.  The study itself (A = 428, 51 dynamic cycles) gave
# 105.48 mm^3 at 0.55175 m (extrapolation difference 1.1 %), so L0 was moved by
# -1.22 / 437 m to 0.5490 m.  After the wear cycle took the PID gains of
# `simulate` (0.3, 0.4) the study gave 106.22 mm^3 at 0.5490 m; the same slope
# moved L0 by -0.48 / 437 m to 0.5479 m.  Spring force k_s (1.0 - x3 - L0): 90-170 N over
# the stroke x3 = 0.127..0.279 m; mean joint force ~140 N (thesis Fig. 7-2: 0-200 N,
# a mean of about 130 N).

# Gravity: the rig's orientation is not stated.  We keep the project default,
# gravity -y in the mechanism plane (thesis Ch. 2 convention; the slider's
# weight is carried by its guide and only the crank and rod weights, ~12 N,
# reach the joint).


def rig_slider_crank(p: SliderCrankParameters = TABLE_7_1, *, free_length=None,
                     spring_stiffness=None, gravity: bool = True, extra_forces=()):
    """The Ch. 7 rig as an ideal slider-crank with the slider spring
    (clearance joint: add it with ``with_wear_joint(mech, RIG_JOINT)``);
    ``extra_forces``: further force elements (e.g. a `GuideFriction`)."""
    from .mechanism import LinearSpring

    l0 = RIG_SPRING_FREE_LENGTH if free_length is None else free_length
    ks = RIG_SPRING_STIFFNESS if spring_stiffness is None else spring_stiffness
    spring = LinearSpring("slider_spring", "ground", (RIG_SPRING_ANCHOR_X, 0.0), "slider",
                          (0.0, 0.0), ks, l0)
    return slider_crank(p, gravity=gravity, extra_forces=(spring, *extra_forces))
