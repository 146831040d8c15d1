"""Ready-made model functions for `sweep`: pure JAX functions of a dict of
scalar parameters returning a dict of scalar outputs.

Static settings (contact law, grid size, cycles, number of dynamic cycles) are
constructor arguments of small equinox Modules; the numbers are traced, so one
compilation serves a whole sweep.  ``rig_wear`` and ``clearance_force`` are
instances with the defaults.
"""

from __future__ import annotations

import math

import diffrax
import equinox as eqx
import jax.numpy as jnp

from ..contact import centred_state, contact_history
from ..dynamics import consistent_state, simulate
from ..mechanism.geometry import safe_norm
from ..models import AbstractWearModel, Dynamic
from ..presets import (
    BUSHING_DEPTH_CH5,
    BUSHING_WALL_CH3,
    FRICTION_CH3,
    PIN_RADIUS_CH3,
    RESTITUTION_CH3,
    RIG_CYCLES,
    RIG_JOINT,
    RIG_SPRING_FREE_LENGTH,
    TABLE_7_1,
    THESIS_CRANK_SPEED,
    SliderCrankParameters,
    WearJointDesign,
    clearance_slider_crank,
    rig_slider_crank,
    with_wear_joint,
)
from ..wear import Constant, CycleSettings, smooth_max, worn_volume
from ..wear.cycle import CYCLE_ATOL, CYCLE_RTOL
from ..wear.status import code, not_an_answer, not_computed

JOINT = "crank_rod"


class RigWear(eqx.Module):
    """Wear of the Ch. 7 rig's crank-rod PTFE bushing: `presets.rig_slider_crank`
    with `with_wear_joint`, evolved by `Dynamic().evolve` with `Constant(A)`.

    Parameters (SI): ``k`` wear coefficient [1/Pa], ``clearance`` [m], ``depth``
    bushing depth [m], ``diameter`` pin diameter [m], ``mu`` friction,
    ``free_length`` slider-spring free length [m].  Static: ``cycles`` real
    cycles, ``dynamic_cycles`` simulated wear cycles (constant A = cycles /
    dynamic_cycles; plus 1 warm-up cycle), ``n_theta`` profile grid, ``wall``
    and ``restitution`` of the bushing, ``temperature`` [m] of the smooth max,
    ``force_samples`` saved states of the force cycle, ``cycle_rtol`` /
    ``cycle_atol`` of each dynamic cycle's integration (default those of
    `wear.wear_cycle`; tighten them when gradients are checked against finite
    differences: AD holds the adaptive steps fixed).

    Outputs: ``max_depth_mm`` = `smooth_max` (logsumexp, temperature
    ``temperature``; within temperature x ln(n_theta) below the true maximum) of
    the final profile; ``volume_mm3`` (`worn_volume`); ``mean_joint_force_N``:
    time mean of |joint force| over one extra dynamic cycle run after the
    evolution on the final profile (``force_samples`` equally spaced states);
    ``status``: the code of the result's `diffwear.wear.RESULTS` member
    (`diffwear.wear.status.code`: 0 ok, 1 wall reached, 2 cycle model failed,
    3 run ended early), a float as every output.

    ``wear_model``: None (the dynamic model with the settings above) or any
    wear model, e.g. `QuasiStatic(...)` (milliseconds per point, exact
    gradients; its
    ``mean_joint_force_N`` is the ideal mechanism's, which wear does not change
    in that model, and ``status`` adds 4 = `RESULTS.contact_lost`: the model
    does not hold there).
    """

    cycles: float = eqx.field(static=True, default=float(RIG_CYCLES))
    dynamic_cycles: int = eqx.field(static=True, default=50)
    n_theta: int = eqx.field(static=True, default=180)
    force_samples: int = eqx.field(static=True, default=181)
    wall: float = eqx.field(static=True, default=float(RIG_JOINT.wall))
    restitution: float = eqx.field(static=True, default=float(RIG_JOINT.restitution))
    temperature: float = eqx.field(static=True, default=1e-7)
    cycle_rtol: float = eqx.field(static=True, default=CYCLE_RTOL)
    cycle_atol: float = eqx.field(static=True, default=CYCLE_ATOL)
    p: SliderCrankParameters = TABLE_7_1
    wear_model: AbstractWearModel | None = None

    param_names = ("k", "clearance", "depth", "diameter", "mu", "free_length")

    @property
    def defaults(self) -> dict[str, float]:
        """The thesis rig (Table 7-2 joint, calibrated spring free length)."""
        d = RIG_JOINT
        return {"k": float(d.k), "clearance": float(d.clearance), "depth": float(d.depth),
                "diameter": float(d.diameter), "mu": float(d.mu),
                "free_length": float(RIG_SPRING_FREE_LENGTH)}

    @property
    def period(self) -> float:
        return 2 * math.pi / float(self.p.omega)

    def design(self, params) -> WearJointDesign:
        return WearJointDesign(params["k"], params["clearance"], params["depth"],
                               params["diameter"], self.wall, params["mu"], self.restitution)

    def model(self) -> AbstractWearModel:
        """The wear model: ``wear_model``, or the dynamic model with this
        sweep's constant extrapolation A = cycles / dynamic_cycles and cycle
        tolerances."""
        if self.wear_model is not None:
            return self.wear_model
        return Dynamic(extrapolation=Constant(self.cycles / self.dynamic_cycles),
                       cycle=CycleSettings(self.cycle_rtol, self.cycle_atol))

    def __call__(self, params: dict) -> dict:
        mech0, q_guess = rig_slider_crank(self.p, free_length=params["free_length"])
        design = self.design(params)
        mech = with_wear_joint(mech0, design, n_theta=self.n_theta)
        # the ideal kinematics at t = 0 depend on no swept parameter
        y0 = centred_state(mech0, consistent_state(mech0, q_guess, check=False), mech)
        el = mech.element(JOINT)
        model = self.model()
        res = model.evolve(mech, (JOINT,), y0, period=self.period, cycles=self.cycles,
                           wall_thickness=design.wall)
        force = model.joint_force(mech, JOINT, y0, period=self.period, evolution=res,
                                  samples=self.force_samples - 1)
        depth = res.depth[0]
        # a failed point's outputs are NaN with NaN derivatives (its status says why)
        failed = not_computed(res.result)
        return {
            "max_depth_mm": not_an_answer(smooth_max(depth, self.temperature) * 1e3, failed,
                                          params),
            "volume_mm3": not_an_answer(
                worn_volume(depth, el.bushing_radius, el.law.depth) * 1e9, failed, params),
            "mean_joint_force_N": not_an_answer(jnp.mean(force), failed, params),
            "status": code(res.result).astype(float),
        }


class ClearanceForce(eqx.Module):
    """Joint force of the Table 2-1 slider-crank with a clearance crank-rod joint
    (`presets.clearance_slider_crank`), as in the ``clearance-sweep`` study
    (Tsit5, PID rtol = atol = 1e-6).

    Parameters: ``clearance`` [m], ``mu`` friction, ``restitution``, ``pin_radius``
    [m].  Static: ``law`` ("ln", "kv", "efm"), ``cycles`` simulated (the first
    ``transient_cycles`` are left out of the statistics), ``samples_per_cycle``,
    ``n_theta``.  Outputs over the kept cycles: ``peak_force_N`` (max |force|
    over the saved states), ``rms_force_N``, and ``integrator_steps`` (of the
    whole run: the cost).
    """

    law: str = eqx.field(static=True, default="ln")
    cycles: int = eqx.field(static=True, default=2)
    transient_cycles: int = eqx.field(static=True, default=1)
    samples_per_cycle: int = eqx.field(static=True, default=400)
    n_theta: int = eqx.field(static=True, default=180)
    rtol: float = eqx.field(static=True, default=1e-6)
    atol: float = eqx.field(static=True, default=1e-6)

    param_names = ("clearance", "mu", "restitution", "pin_radius")

    @property
    def defaults(self) -> dict[str, float]:
        """Table 3-2/3-3: clearance 0.5 mm, mu 0.13, e 0.8, pin radius 20 mm."""
        return {"clearance": 0.5e-3, "mu": FRICTION_CH3, "restitution": RESTITUTION_CH3,
                "pin_radius": PIN_RADIUS_CH3}

    def __call__(self, params: dict) -> dict:
        mech, y0 = clearance_slider_crank(
            self.law, params["clearance"], friction=params["mu"],
            restitution=params["restitution"], pin_radius=params["pin_radius"],
            depth=BUSHING_DEPTH_CH5, wall=BUSHING_WALL_CH3, n_theta=self.n_theta, check=False)
        period = 2 * math.pi / THESIS_CRANK_SPEED
        n = self.samples_per_cycle
        ts = jnp.linspace(0.0, self.cycles * period, self.cycles * n + 1)
        ctrl = diffrax.PIDController(rtol=self.rtol, atol=self.atol, pcoeff=0.3, icoeff=0.4)
        traj = simulate(mech, y0, ts[-1], ts=ts, stepsize_controller=ctrl)
        f = contact_history(mech, JOINT, traj.ys).force_magnitude[self.transient_cycles * n:]
        # a failed integration's forces are NaN with NaN derivatives
        failed = ~traj.succeeded
        return {"peak_force_N": not_an_answer(jnp.max(f), failed, params),
                "rms_force_N": not_an_answer(safe_norm(f) / math.sqrt(f.shape[-1]), failed,
                                             params),
                "integrator_steps": jnp.asarray(traj.num_steps, dtype=float)}


rig_wear = RigWear()
clearance_force = ClearanceForce()

__all__ = ["RigWear", "ClearanceForce", "rig_wear", "clearance_force"]
