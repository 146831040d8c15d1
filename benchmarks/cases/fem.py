"""The FEM wear route: ``rig-21400`` by the FEM route beside the EFM route."""

from __future__ import annotations

from harness import time_jitted


def rig_21400_fem_route(repeats: int) -> dict:
    """``rig-21400`` by the FEM wear route (docs "FEM contact and the FEM wear
    route": FE ring contact for the wear pressure, 65 samples per cycle) next
    to the EFM route, both as the study runs them by default: their cycles on
    the study's integrator (`rig_21400.INTEGRATOR`, Rodas4 at rtol 1e-4; the
    FEM route's cycles step onto its samples), the FEM route with
    `default_model`.  Each compiled once, then ``min(repeats, 3)`` timed runs
    (a run is 1-10 s: the median keeps a load spike on the shared machine
    out of the ratio); ``ratio_fem_to_efm`` is the route's cost measure
    (target <= 5; thesis 11 h / 7 h = 1.6)."""
    import jax

    from diffwear.models import FemRoute
    from diffwear.models.execution import RunTimes
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import (
        INTEGRATOR,
        N_THETA,
        PERIOD,
        RIG_JOINT,
        TARGET_DYNAMIC,
        _setup,
    )
    from diffwear.wear.fem_route import default_model

    mech0, _, y0 = _setup()
    mech_of_p = common.mech_builder(mech0, RIG_JOINT, N_THETA)
    efm = common.dynamic_model(RIG_CYCLES, TARGET_DYNAMIC, INTEGRATOR)
    fem_model = default_model(RIG_JOINT)
    fem = FemRoute(fem=fem_model, extrapolation=efm.extrapolation, cycle=efm.cycle,
                   dynamic_cycles=efm.dynamic_cycles)
    p = common.params_of(RIG_JOINT)
    n_runs = min(repeats, 3)
    out: dict = {"integrator": INTEGRATOR, "refresh_interval": float(fem_model.refresh_interval),
                 "samples_per_cycle": fem_model.n_samples + 1}
    for tag, model in (("efm", efm), ("fem", fem)):
        # the computation the study compiles (`Dynamic.run`: the evolver's
        # solve; the study runs its slots in chunks with checkpoints, the same
        # result), in one jitted call
        run = jax.jit(lambda p, y, model=model: model.evolver(
            mech_of_p(p), common.JOINT, RIG_CYCLES, period=PERIOD,
            wall_thickness=RIG_JOINT.wall).solve(y))
        res, m = time_jitted(run, (p, y0), n_runs)
        res.check(f"benchmark rig-21400 {tag} route")
        nums = common.route_numbers(res, RIG_JOINT,
                                    RunTimes(m["compile_s"], m["run_s"], {}))
        out.update({f"{tag}_{k}": v for k, v in nums.items()})
        out[f"{tag}_run_s_all"] = m["run_s_all"]
    # the route's change against its run before it moved to Rodas4 (relative)
    out.update({f"fem_change_{k}": out[f"fem_{k}"] / v - 1.0
                for k, v in FEM_ROUTE_ON_TSIT5.items()})
    change = {k: 100.0 * out[f"fem_change_{k}"] for k in FEM_ROUTE_ON_TSIT5}
    note = (f"FEM route against its Tsit5 run: max depth {change['max_wear_depth_mm']:+.1f} %, "
            f"+-4 deg mean {change['arc_peak_depth_mm']:+.2f} %, "
            f"volume {change['wear_volume_mm3']:+.2f} %")
    return {"compile_s": out["fem_compile_time_s"], "run_s": out["fem_wall_time_s"],
            "note": note, "dynamic_cycles": out["fem_dynamic_cycles_simulated"],
            "ratio_fem_to_efm": out["fem_wall_time_s"] / out["efm_wall_time_s"], **out,
            "repeats": n_runs}


# The FEM route's rig-21400 run before its cycles moved to Rodas4 (Tsit5 at
# rtol 1e-6, the samples interpolated, the compliance rebuilt every cycle, J
# from every 8th sample): its stored run, from the study's start
# (design_studies/results/studies/rig-21400-fem before it was regenerated;
# benchmarks/records/fem_route_scatter.json, "before", run 0).  Its grid
# maximum is one draw of a profile with node-scale roughness (+-2 % between
# runs); the +-4 deg mean and the volume by ~0.4 %.
FEM_ROUTE_ON_TSIT5 = {"max_wear_depth_mm": 0.461346, "arc_peak_depth_mm": 0.456383,
                      "wear_volume_mm3": 106.2749}
