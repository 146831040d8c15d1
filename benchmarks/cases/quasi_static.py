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
    from diffwear.wear.status import name

    _, mech, y0 = _setup()
    model = QuasiStatic()
    fn = jax.jit(lambda m: model.evolve(m, ("crank_rod",), y0, period=PERIOD,
                                        cycles=float(RIG_CYCLES), wall_thickness=RIG_JOINT.wall))
    res, metrics = time_jitted(fn, (mech,), repeats)
    el = mech.element("crank_rod")
    depth = res.depth[0]
    return {**metrics, "max_wear_depth_mm": float(depth.max()) * 1e3,
            "wear_volume_mm3": float(worn_volume(depth, el.bushing_radius, el.law.depth)) * 1e9,
            "status": name(res.result), "pair": "rig-21400 (constant A)", "goal_s": 0.5}


def rig_lubricated_quasi_static(repeats: int) -> dict:
    """The ``rig-lubricated`` study's wear run: the Ch. 7 rig with its
    crank-rod joint in oil (`MixedLubrication`: the finite-length film from
    its shipped tables, and the asperities) over 21,400 cycles on the
    quasi-static model, beside the dry rig's in the same run
    (``ratio_lubricated_to_dry``: what the film's equilibrium costs), each
    compiled once."""
    import jax

    from diffwear.models import QuasiStatic
    from diffwear.presets import RIG_CYCLES
    from diffwear.studies.rig_21400 import PERIOD, RIG_JOINT, _setup
    from diffwear.studies.rig_lubricated import lubricated
    from diffwear.wear.status import name

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
                    f"{tag}_status": name(res.result)})
    return {"compile_s": out["lubricated_compile_s"], "run_s": out["lubricated_run_s"],
            "ratio_lubricated_to_dry": out["lubricated_run_s"] / out["dry_run_s"], **out,
            "repeats": repeats}


def file_runs(repeats: int) -> dict:
    """The shipped four-bar files as a user runs them, end to end in a fresh
    process: ``diffwear run four_bar_lubricated --cycles 1000000 --limit
    0.05`` (the file's header command: the motion on Rodas4, the quasi-static
    wear with the journal's orbit, its life, the film report) beside the dry
    ``four_bar_wear --cycles 100000 --limit 0.2``.  Each twice on an empty
    compilation cache of its own: the first run compiles everything (a
    user's first run; ``*_wall_s``), the second finds the compiled programs
    (``*_warm_wall_s``).  Wall seconds; ``repeats`` is not used (each run
    takes minutes)."""
    import json
    import os
    import subprocess
    import sys
    import tempfile
    import time
    from pathlib import Path

    runs = {"lubricated": ("four_bar_lubricated", "1000000", "0.05"),
            "dry": ("four_bar_wear", "100000", "0.2")}
    out: dict = {}
    for tag, (name, cycles, limit) in runs.items():
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "DIFFWEAR_COMPILATION_CACHE": cache}
            walls, summary = [], {}
            for _ in range(2):
                with tempfile.TemporaryDirectory() as tmp:
                    started = time.perf_counter()
                    subprocess.run([sys.executable, "-m", "diffwear.cli", "run", name,
                                    "--cycles", cycles, "--limit", limit, "--out", tmp,
                                    "--overwrite", "--quiet"], check=True, capture_output=True,
                                   env=env)
                    walls.append(time.perf_counter() - started)
                    summary = json.loads((Path(tmp) / "summary.json").read_text())
        joint = next(iter(summary["joints"].values()))
        out.update({f"{tag}_wall_s": walls[0], f"{tag}_warm_wall_s": walls[1],
                    f"{tag}_max_wear_depth_mm": joint["max_wear_depth_mm"],
                    f"{tag}_cycles_to_limit": joint["cycles_to_limit"]})
    return {"run_s": out["lubricated_wall_s"], "goal_s": 120.0, **out}
