"""Quasi-static model cases: the ``rig-21400`` wear run, dry and in oil."""

from __future__ import annotations

from harness import time_jitted


def rig_21400_quasi_static(repeats: int) -> dict:
    """``rig-21400`` on the quasi-static model (`QuasiStatic()` defaults: 180
    load samples, 40 steps of the wear ODE), compiled once; the dynamic
    route's figure is the ``rig-21400 (constant A)`` case."""
    import jax

    from diffwear.models import QuasiStatic
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies.rig_21400 import PERIOD, RIG_JOINT, _setup
    from diffwear.wear import worn_volume

    _, mech, y0 = _setup()
    model = QuasiStatic()
    fn = jax.jit(lambda m: model.evolve(m, ("crank_rod",), y0, period=PERIOD,
                                        cycles=float(RIG_CYCLES), wall_thickness=RIG_JOINT.wall))
    res, metrics = time_jitted(fn, (mech,), repeats)
    el = mech.element("crank_rod")
    depth = res.depth[0]
    return {**metrics, "max_wear_depth_mm": float(depth.max()) * 1e3,
            "wear_volume_mm3": float(worn_volume(depth, el.bushing_radius, el.law.depth)) * 1e9,
            "status": int(res.status), "pair": "rig-21400 (constant A)", "goal_s": 0.5}


def rig_lubricated_quasi_static(repeats: int) -> dict:
    """The ``rig-lubricated`` study's wear run: the Ch. 7 rig with its
    crank-rod joint in oil (`MixedLubrication`: short-bearing film and
    asperities) over 21,400 cycles on the quasi-static model, beside the dry
    rig's in the same run (``ratio_lubricated_to_dry``: what the film's
    equilibrium costs), each compiled once."""
    import jax

    from diffwear.models import QuasiStatic
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies.rig_21400 import PERIOD, RIG_JOINT, _setup
    from diffwear.studies.rig_lubricated import lubricated

    _, dry, y0 = _setup()
    model = QuasiStatic()
    out: dict = {}
    for tag, mech in (("dry", dry), ("lubricated", lubricated(dry))):
        fn = jax.jit(lambda m: model.evolve(m, ("crank_rod",), y0, period=PERIOD,
                                            cycles=float(RIG_CYCLES),
                                            wall_thickness=RIG_JOINT.wall))
        res, m = time_jitted(fn, (mech,), repeats)
        out.update({f"{tag}_compile_s": m["compile_s"], f"{tag}_run_s": m["run_s"],
                    f"{tag}_max_wear_depth_mm": float(res.depth[0].max()) * 1e3,
                    f"{tag}_status": int(res.status)})
    return {"compile_s": out["lubricated_compile_s"], "run_s": out["lubricated_run_s"],
            "ratio_lubricated_to_dry": out["lubricated_run_s"] / out["dry_run_s"], **out,
            "repeats": repeats}
