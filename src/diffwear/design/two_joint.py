"""The Chapter 8 design problem: a slider-crank with two wearing joints.

Thesis Ch. 8 (Tables 8-1 to 8-5): the Table 2-1 slider-crank
(Table 8-1 = Table 2-1) with PTFE bushings in the connecting rod at both of its
joints, hardened steel pins (Table 8-2 = Table 3-2 materials, k = 5.05e-4
mm^3/(N m), mu = 0.13), 30 rpm.  Joint 1 is crank-rod (pin on the crank),
joint 2 rod-slider (pin on the slider).  The design is the bushing bore
diameter d_j and the bushing depth (axial length) h_j of each joint, inside the
Table 8-3 box; the life of joint j is the number of crank cycles until its
maximum wear depth reaches 2 mm (Table 8-3), `cycles_to_limit`.

Assumptions beyond the thesis (also in the docs, "Assumptions beyond the thesis"):

* Clearance 0.0005 mm (Table 3-2's smallest; the thesis's Ch. 8 text gives no
  other value), the same at both joints; the bore diameter d is the pin
  diameter plus twice that (d and the pin diameter differ by 1 um).
* Bushing wall (the EFM layer thickness L) is not in the thesis: we keep the
  rig's proportions (Table 7-2: outer / inner radius = 15.875 / 9.533), as for
  the Ch. 5/6 example, so L = 0.6653 x bore radius (6.65 mm at d = 20 mm,
  23.3 mm at d = 70 mm: always thicker than the 2 mm limit).  The EFM stiffness
  E / L therefore falls with d; a fixed wall would change the pressures.
* Damping of each EFM joint from e_r = 0.8 (Table 3-3) with the rod's mass.
* After a joint reaches 2 mm its profile is held (end of life); the other joint
  wears on.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import check_finite, check_int_option, check_positive, concrete
from ..contact import centred_state
from ..dynamics import consistent_state
from ..errors import InputError, SolverError
from ..models import AbstractWearModel, QuasiStatic, WearSolution, cycles_to_limit
from ..presets import (
    FRICTION_CH3,
    K_PTFE_MM3_PER_NM,
    RESTITUTION_CH3,
    TABLE_2_1,
    SliderCrankParameters,
    WearJointDesign,
    slider_crank,
    with_wear_joint,
)
from ..wear.status import RESULTS, message
from ..wear.status import name as status_name

JOINTS = ("crank_rod", "rod_slider")
BUSHING_BODY = "rod"
VARIABLES = ("d1", "d2", "h1", "h2")  # bore diameters, bushing depths [m]

WEAR_LIMIT = 2.0e-3                     # m, Table 8-3 (max allowable wear depth)
DIAMETER_BOUNDS = (20.0e-3, 70.0e-3)    # m, Table 8-3
DEPTH_BOUNDS = (10.0e-3, 50.0e-3)       # m, Table 8-3
LOWER = np.array([DIAMETER_BOUNDS[0]] * 2 + [DEPTH_BOUNDS[0]] * 2)
UPPER = np.array([DIAMETER_BOUNDS[1]] * 2 + [DEPTH_BOUNDS[1]] * 2)

CLEARANCE_CH8 = 0.0005e-3               # m (Table 3-2's smallest; see module notes)
WALL_PER_RADIUS = 15.875 / 9.533 - 1.0  # Table 7-2 rig proportions (our choice)

# Table 8-4: the surrogate optimum (d1, d2, h1, h2) [m]; Table 8-5: its check.
TABLE_8_4 = np.array([46.58e-3, 48.60e-3, 37.25e-3, 14.00e-3])
TABLE_8_5 = {"surrogate_cycles": 119_435, "full_model_cyc1": 121_600,
             "full_model_cyc2": 117_600, "rel_gap": 4000 / 119_600}


def check_design(x, *, what: str = "design") -> None:
    """Raise `InputError` unless ``x`` = (d1, d2, h1, h2) [m] lies in the Table 8-3 box."""
    v = concrete(x)
    if v is None:
        return
    if v.shape != (4,):
        raise InputError(f"{what}: expected 4 values (d1, d2, h1, h2) in m, got shape {v.shape}")
    for name, value, lo, hi in zip(VARIABLES, v, LOWER, UPPER):
        if not (math.isfinite(value) and lo - 1e-12 <= value <= hi + 1e-12):
            raise InputError(f"{what}: {name} = {value * 1e3:.6g} mm is outside the Table 8-3 "
                             f"range [{lo * 1e3:g}, {hi * 1e3:g}] mm")


def bushing(diameter, depth, *, clearance=CLEARANCE_CH8, k=K_PTFE_MM3_PER_NM * 1e-9,
            mu=FRICTION_CH3) -> WearJointDesign:
    """One Ch. 8 PTFE bushing of bore ``diameter`` and ``depth`` [m]."""
    diameter = jnp.asarray(diameter, dtype=float)
    pin = diameter - 2 * clearance
    wall = WALL_PER_RADIUS * 0.5 * diameter
    return WearJointDesign(k, clearance, depth, pin, wall, mu, RESTITUTION_CH3)


class TwoJointLife(eqx.Module):
    """cycles-to-limit of both joints as a function of x = (d1, d2, h1, h2) [m].

    ``model(x)`` -> [cyc1, cyc2] (jit-able, vmap-able, differentiable);
    ``model.evaluate(x)`` -> the `WearSolution` (lives: ``.life``);
    ``model.life(x)`` checks its result (`SolverError` on failure) and returns NumPy cycles.

    ``wear_model``: `QuasiStatic()` (default: smooth, exact gradients by
    `jax.jacfwd` / `jax.grad`, checked against central differences) or
    `Dynamic(...)` (the reference; its pointwise derivative at the 2 mm limit
    is not usable, see `diffwear.wear.life`: use
    `diffwear.design.finite_difference_jacobian` with it).  ``n_theta``:
    profile grid; ``limit``: wear-depth limit [m].
    """

    wear_model: AbstractWearModel = QuasiStatic()
    n_theta: int = eqx.field(static=True, default=90)
    limit: float = eqx.field(static=True, default=WEAR_LIMIT)
    # Contact-onset band of the EFM springs [m].  The default 10 nm made the
    # reverse-mode derivative of one dynamic cycle's wear 1000x off the central
    # difference on this mechanism (springs crossing the band inside one
    # integrator step); 1 um (2 % of the ~50 um penetration at 2 kN) gives
    # 0.15 % agreement (measured, one cycle at the Table 8-4 design).  The
    # ramp is exact outside the band, so only springs within 1 um of the edge
    # of the contact arc carry less load.
    penetration_width: float = eqx.field(static=True, default=1e-6)
    p: SliderCrankParameters = TABLE_2_1

    def __check_init__(self):
        if not isinstance(self.wear_model, AbstractWearModel):
            raise InputError(f"TwoJointLife: wear_model must be a wear model (QuasiStatic(), "
                             f"Dynamic()), got {self.wear_model!r}")
        # the profile grid: the range the design command allows (12 to 720 nodes)
        check_int_option("TwoJointLife: n_theta", self.n_theta, 12, 720)
        check_positive("TwoJointLife: limit [m]", self.limit)

    @property
    def exact_gradients(self) -> bool:
        """Autodiff Jacobians are meaningful (the quasi-static model)."""
        return self.wear_model.exact_gradients

    @property
    def period(self) -> float:
        return 2 * math.pi / float(self.p.omega)

    def mechanism(self, x, wear_scale=None):
        """The wearing mechanism for design x and its ideal parent;
        ``wear_scale`` (2,): each bushing's wear coefficient over the nominal
        5.05e-4 mm^3/(N m) (default 1, 1)."""
        ideal, q_guess = slider_crank(self.p)
        mech = ideal
        scale = jnp.ones(2) if wear_scale is None else jnp.asarray(wear_scale, dtype=float)
        for joint, d, h, s in zip(JOINTS, (x[0], x[1]), (x[2], x[3]), scale):
            mech = with_wear_joint(mech, bushing(d, h, k=s * K_PTFE_MM3_PER_NM * 1e-9),
                                   joint=joint, bushing_body=BUSHING_BODY,
                                   n_theta=self.n_theta, penetration_width=self.penetration_width)
        return ideal, q_guess, mech

    def prepared(self) -> "TwoJointLife":
        """This model with the quasi-static joint loads computed once (they do
        not depend on the bushing design): cheaper evaluations and compiles."""
        if not self.wear_model.precomputes:
            return self
        model = _prepared(self, jnp.asarray(0.5 * (LOWER + UPPER)))
        return eqx.tree_at(lambda m: m.wear_model, self, model)

    def evaluate(self, x: Float[Array, "4"], wear_scale=None) -> WearSolution:
        check_design(x)
        x = jnp.asarray(x, dtype=float)
        ideal, q_guess, mech = self.mechanism(x, wear_scale)
        # the ideal kinematics at t = 0 do not depend on the design
        y0 = centred_state(ideal, consistent_state(ideal, q_guess, check=False), mech)
        return cycles_to_limit(mech, JOINTS, y0, period=self.period, limit=self.limit,
                               model=self.wear_model)

    def __call__(self, x: Float[Array, "4"]) -> Float[Array, "2"]:
        # compiled as one program even when called eagerly (op by op, a life
        # is hundreds of small compilations); inside jit / vmap / jacfwd the
        # inner jit is inlined.  Its shape is checked, and a non-finite value
        # is an `InputError` (concrete) or stops the program with the same
        # words (`eqx.error_if`, inside a trace); the Table 8-3 box is
        # `life`'s check (a derivative at a bound may step past it)
        check_finite("design", x)
        if jnp.shape(x) != (4,):
            raise InputError(f"design: expected 4 values (d1, d2, h1, h2) in m, got shape "
                             f"{jnp.shape(x)}")
        x = eqx.error_if(jnp.asarray(x, dtype=float), ~jnp.all(jnp.isfinite(x)),
                         "design: every value of (d1, d2, h1, h2) must be finite")
        return _evaluate(self, x).life

    def life(self, x) -> np.ndarray:
        """[cyc1, cyc2] at a concrete design, as NumPy; `SolverError` on failure."""
        check_design(x)
        res = _evaluate(self, jnp.asarray(x, dtype=float))
        if bool(res.result != RESULTS.ok):
            raise SolverError(f"{self.wear_model.name} life at design "
                              f"{np.round(np.asarray(x) * 1e3, 4).tolist()} mm: "
                              f"{message(res.result)} (status {status_name(res.result)})")
        return np.asarray(res.life)


@eqx.filter_jit
def _prepared(model: TwoJointLife, x):
    ideal, q_guess, mech = model.mechanism(x)
    y0 = centred_state(ideal, consistent_state(ideal, q_guess, check=False), mech)
    return model.wear_model.prepared(mech, JOINTS, y0, model.period)


@eqx.filter_jit
def _evaluate(model: TwoJointLife, x) -> WearSolution:
    return model.evaluate(x)


SWEEP_MODEL = TwoJointLife(wear_model=QuasiStatic(samples=36, steps=16), n_theta=36)
"""Coarser quasi-static settings for sweeps over many designs (36 load
samples, 16 wear steps, 36 profile nodes): lives within 0.3 % of the
defaults' over the Table 8-3 box (32 random designs; the ``quasi-static life
sweep`` benchmark case measures it), ~25x cheaper per design (the
alternatives measured: docs/notes/design-solver.md)."""

