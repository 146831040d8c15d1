"""Thesis Ch. 8 design cases: the optimisation, and the two-joint lives on the
quasi-static model (their Jacobian, a 1,000-design sweep)."""

from __future__ import annotations

import time

from harness import QUICK_REPEATS, time_jitted, timed


def ch8_optimisation(repeats: int) -> dict:
    """Thesis Ch. 8 design optimisation, owned by `diffwear.design`: the case
    calls ``diffwear.cli.design.benchmark_case(quick)`` (quick when ``repeats`` is
    the quick count) and reports ``available: False`` until that module exists."""
    import importlib

    try:
        design = importlib.import_module("diffwear.cli.design")
    except ModuleNotFoundError as err:
        if err.name not in ("diffwear.design",):
            raise  # the module exists but one of its imports is broken: say so
        return {"available": False, "note": "not available (no diffwear.design yet)"}
    return {"available": True, **design.benchmark_case(quick=repeats <= QUICK_REPEATS)}


def quasi_static_life_gradient(repeats: int) -> dict:
    """Ch. 8 lives (cyc1, cyc2) at the Table 8-4 design on the quasi-static
    model (`TwoJointLife().prepared()`, defaults) and their exact Jacobian
    w.r.t. (d1, d2, h1, h2) by `jax.jacfwd` (4 tangents): cost of the Jacobian
    over one forward run.  The dynamic route's pointwise life derivative is
    not usable (docs: which derivatives to trust); its Jacobian is 8 central-
    difference runs, i.e. a ratio of 8."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.design import TwoJointLife
    from diffwear.design.two_joint import TABLE_8_4

    model = TwoJointLife().prepared()
    x = jnp.asarray(TABLE_8_4)
    value, m_fwd = time_jitted(jax.jit(lambda x: model(x)), (x,), repeats)
    jac, m_jac = time_jitted(jax.jit(jax.jacfwd(model)), (x,), repeats)
    return {"cycles": np.asarray(value).tolist(), "jacobian_cycles_per_mm":
            (np.asarray(jac) * 1e-3).tolist(), "forward_s": m_fwd["run_s"],
            "forward_compile_s": m_fwd["compile_s"], "compile_s": m_jac["compile_s"],
            "run_s": m_jac["run_s"], "ratio_gradient_to_forward": m_jac["run_s"] / m_fwd["run_s"],
            "dynamic_ratio_central_differences": 8.0, "goal_ratio": 3.0}


SWEEP_DESIGNS, SWEEP_DESIGNS_QUICK, SWEEP_CHUNK = 1000, 64, 250


def quasi_static_life_sweep(repeats: int) -> dict:
    """Lives of 1,000 designs (quick: 64) spread over the Table 8-3 box
    (uniform, seeded) on the quasi-static model, `jax.vmap` in chunks of
    ``SWEEP_CHUNK`` (one compile), at the sweep settings
    `diffwear.design.SWEEP_MODEL` (their lives against the defaults' at the
    Table 8-4 design are reported); once, compiles excluded.  Beside it: the
    dynamic model's one life (steps 10) times the number of designs."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from diffwear.design import SWEEP_MODEL, TwoJointLife
    from diffwear.design.two_joint import LOWER, TABLE_8_4, UPPER
    from diffwear.models import Dynamic

    quick = repeats <= QUICK_REPEATS
    n = SWEEP_DESIGNS_QUICK if quick else SWEEP_DESIGNS
    chunk = min(SWEEP_CHUNK, n)
    rng = np.random.default_rng(3)
    xs = LOWER + (UPPER - LOWER) * rng.uniform(size=(n, 4))
    model = SWEEP_MODEL.prepared()
    f = jax.jit(jax.vmap(model))
    _, first = timed(f, jnp.asarray(xs[:chunk]))
    t0 = time.perf_counter()
    lives = np.concatenate([np.asarray(f(jnp.asarray(xs[i:i + chunk])))
                            for i in range(0, n, chunk)])
    run = time.perf_counter() - t0
    sweep_84 = model.life(TABLE_8_4)
    default = TwoJointLife().prepared()
    default_84 = default.life(TABLE_8_4)
    out = {"designs": n, "chunk": chunk, "run_s": run, "compile_s": max(first - run * chunk / n, 0),
           "s_per_design": run / n, "finite": bool(np.all(np.isfinite(lives))),
           "life_range": [float(lives.min()), float(lives.max())],
           "table_8_4_sweep_settings": sweep_84.tolist(),
           "table_8_4_default_settings": default_84.tolist(),
           "sweep_settings_rel_error": float(np.max(np.abs(sweep_84 / default_84 - 1))),
           "goal_s": 20.0}
    if not quick:
        check = np.asarray(jax.jit(jax.vmap(lambda x: default(x)))(jnp.asarray(xs[:32])))
        out["sweep_settings_max_rel_error_32_designs"] = float(
            np.max(np.abs(lives[:32] / check - 1)))
        dyn = TwoJointLife(wear_model=Dynamic(steps=10))
        dyn.life(TABLE_8_4)  # compile
        t0 = time.perf_counter()
        dyn.life(TABLE_8_4)
        one = time.perf_counter() - t0
        out.update({"dynamic_one_life_s": one, "dynamic_estimate_s": one * n,
                    "speedup_vs_dynamic": one * n / run})
    out["note"] = (f"{n} designs, {run / n * 1e3:.1f} ms each; settings within "
                   f"{100 * out['sweep_settings_rel_error']:.2f} % of the defaults")
    return out
