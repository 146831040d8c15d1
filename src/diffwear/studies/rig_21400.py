"""Study ``rig-21400``: thesis Ch. 7 experimental rig (Tables 7-1..7-6).

Rig slider-crank (Table 7-1, half-lengths), slider spring 525.4 N/m pulling the
slider away from the crank, crank-rod EFM PTFE bushing (Table 7-2), 30 rpm,
21,400 cycles.  The spring free length is calibrated (`calibrate_free_length`)
so that the worn volume equals the thesis models' 106.7 mm^3.
"""

from __future__ import annotations

import math

import jax

from ..io import OutputDir
from ..models import AbstractWearModel
from ..presets import (
    PTFE_DENSITY,
    RIG_CYCLES,
    RIG_JOINT,
    RIG_SPRING_ANCHOR_X,
    RIG_SPRING_FREE_LENGTH,
    RIG_SPRING_STIFFNESS,
    TABLE_7_1,
    THESIS_CRANK_SPEED,
    rig_slider_crank,
    with_wear_joint,
)
from ..report import Bullets
from ..wear import Constant, evolve, worn_volume
from ..wear.cycle import clearance_element
from . import _wear_common as common

NAME = "rig-21400"
DESCRIPTION = "Ch. 7: experimental rig, EFM crank-rod bushing wear over 21,400 cycles"

N_THETA = 180
DESIGN = RIG_JOINT  # the wearing joint (Table 7-2)
TARGET_DYNAMIC = 50
PERIOD = 2 * math.pi / THESIS_CRANK_SPEED
TARGET_VOLUME_MM3 = 106.7  # Table 7-4: FEM 106.71, EFM 106.68 mm^3
# The dynamic cycles' integrator (`wear.cycle.CYCLE_INTEGRATORS`).  The rig's pin
# stays pressed into the PTFE bushing all cycle, where an explicit step is held
# by the contact's stability limit (Tsit5: ~2,800 accepted steps a cycle at any
# rtol from 1e-4 to 1e-6) and the L-stable linearly implicit Rodas4 is not
# (~210 at rtol 1e-4).  Measured over the whole study (docs/notes/
# rosenbrock-rig-cycle.md): max depth and volume within 7e-5 of Tsit5 at rtol
# 1e-8, in ~1/8 of the time of Tsit5 at rtol 1e-6.  `--integrator tsit5` runs
# the explicit reference.  The FEM route (`--contact fem`) too runs on Rodas4,
# its cycles stepping onto the FE samples (`wear.fem_route`): the means of
# max depth, smoothed max depth and volume over eight runs from starts 1e-12 m
# apart within 0.5 % of Tsit5's (benchmarks/records/fem_route_scatter.json),
# at ~2/5 of its time.
INTEGRATOR = "rodas4"
# What the figures compare with and what is fitted (`WearStudy.cf`, `.calibrated`).
CF = "cf. Figs. 7-4/7-5"
CALIBRATED = (f"volume: the spring free length is fitted to the thesis models' "
              f"{TARGET_VOLUME_MM3:g} mm³ (Table 7-4), so only the measured volume is a "
              "comparison")

THESIS = {  # Tables 7-4..7-6
    "EFM (Table 7-4)": {"max_wear_depth_mm": 0.4263, "wear_volume_mm3": 106.68, "time_h": 7},
    "FEM (Table 7-4)": {"max_wear_depth_mm": 0.4779, "wear_volume_mm3": 106.71, "time_h": 11},
    "measured (Tables 7-5/7-6)": {"max_wear_depth_mm": 0.4850, "wear_volume_mm3": 116.27,
                                  "worn_mass_g": 0.2616},
}


def _setup(p=TABLE_7_1, free_length=None, n_theta=N_THETA):
    mech0, q_guess = rig_slider_crank(p, free_length=free_length)
    mech = with_wear_joint(mech0, RIG_JOINT, n_theta=n_theta)
    y0 = common.initial_state(mech0, q_guess, mech)
    return mech0, mech, y0


def calibrate_free_length(l0_guesses=(0.50, 0.56), *, cycles=RIG_CYCLES, dynamic=10,
                          iterations=4, p=TABLE_7_1, log=print) -> float:
    """Secant iteration on the spring free length L0 [m] so that the volume after
    ``cycles`` (constant A = cycles / ``dynamic``) equals 106.7 mm^3.  The volume is
    nearly linear in the spring force, hence in L0: 2-4 iterations suffice."""
    _, mech, y0 = _setup(p, l0_guesses[0])
    idx = clearance_element(mech, common.JOINT)[0]
    spring = next(i for i, f in enumerate(mech.forces) if f.name == "slider_spring")

    @jax.jit
    def volume(l0):
        import equinox as eqx

        m = eqx.tree_at(lambda m: m.forces[spring].free_length, mech, l0)
        r = evolve(m, common.JOINT, y0, cycles, period=PERIOD,
                   method=Constant(float(cycles) / dynamic))
        return worn_volume(r.depth[0], m.forces[idx].bushing_radius, m.forces[idx].law.depth) * 1e9

    x0, x1 = l0_guesses
    f0, f1 = float(volume(x0)) - TARGET_VOLUME_MM3, float(volume(x1)) - TARGET_VOLUME_MM3
    log(f"[{NAME}] calibrate L0: {x0:.5f} m -> {f0 + TARGET_VOLUME_MM3:.2f}; "
        f"{x1:.5f} m -> {f1 + TARGET_VOLUME_MM3:.2f} mm^3")
    for _ in range(iterations):
        if abs(f1) < 0.05:
            break
        x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
        f1 = float(volume(x1)) - TARGET_VOLUME_MM3
        log(f"[{NAME}] calibrate L0: {x1:.5f} m -> {f1 + TARGET_VOLUME_MM3:.2f} mm^3")
    return x1


def run(out: OutputDir, *, cycles: int = RIG_CYCLES, model: AbstractWearModel | None = None,
        free_length: float | None = None, log=print, resume: bool = False,
        progress: bool = False) -> dict:
    """The study over ``cycles`` on ``model`` (default: the dynamic model on
    `INTEGRATOR`, about `TARGET_DYNAMIC` dynamic cycles); ``free_length`` [m]:
    the slider spring's (default the calibrated one)."""
    model = (common.dynamic_model(cycles, TARGET_DYNAMIC, INTEGRATOR) if model is None
             else model)
    return common.run_wear_study(out, study(free_length, log), cycles=cycles, model=model,
                                 log=log, resume=resume, progress=progress)


def study(free_length: float | None = None, log=print) -> common.WearStudy:
    """The rig with its slider spring of ``free_length`` [m] as a wear study."""
    l0 = RIG_SPRING_FREE_LENGTH if free_length is None else free_length
    mech0, _, y0 = _setup(TABLE_7_1, l0)
    log(f"[{NAME}] spring free length L0 {l0:.5f} m")
    x3 = float(y0[6])  # slider position at t = 0 [m]
    spring_mid = RIG_SPRING_STIFFNESS * (RIG_SPRING_ANCHOR_X - x3 - l0)
    return common.WearStudy(
        name=NAME, mech_of=common.mech_builder(mech0, RIG_JOINT, N_THETA),
        p=common.params_of(RIG_JOINT), design=RIG_JOINT, y0=y0, period=PERIOD,
        thesis=THESIS, thesis_cycles=RIG_CYCLES, cf=CF, calibrated=CALIBRATED,
        description=(
            "Rig of thesis Ch. 7: Table 7-1 read as half-lengths (crank 38.1 mm, rod 101.6 mm "
            "COM distances), gravity -y in the plane, slider spring 525.4 N/m pulling the "
            f"slider away from the crank (anchor x = {RIG_SPRING_ANCHOR_X} m, free length "
            f"L0 = {l0:.5f} m, calibrated to 106.7 mm^3), EFM PTFE bushing R 9.533 mm on a "
            "9.500 mm pin, wall 6.342 mm, depth 13.1 mm, mu 0.13, k 5.05e-4 mm^3/(N m), "
            f"30 rpm. Worn mass with PTFE density {PTFE_DENSITY / 1e3:g} g/cm^3."),
        extra_summary={"spring_free_length_m": l0, "spring_force_at_t0_N": spring_mid},
        extra_report=(Bullets([f"spring force at t = 0 (crank angle 0): {spring_mid:.1f} N"]),))
