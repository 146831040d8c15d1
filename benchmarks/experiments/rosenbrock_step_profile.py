"""Experiment: where a Rodas4 step's time goes on one rig wear cycle, and which
cheaper variants of the solver's own work pay.

Rodas4 takes ~210 steps a rig wear cycle at its preset rtol 1e-4 (the step is
set by accuracy: `rosenbrock_rig_cycle.py`, `rosenbrock_higher_order.py`), so
a faster cycle needs a cheaper step.  A step is one linearisation (the right-
hand side and its 19 Jacobian columns), one LU of the 18 x 18 step matrix,
five more right-hand sides, six back-substitutions and the step controller.
This measures:

1. **The pieces of a step**: a fixed-step loop of 400 Rodas4 steps with a
   fresh linearisation at every step, against the same loop with the
   linearisation held at its first value (the step size varies by 1e-9 per
   step, so XLA cannot hoist the LU out of the loop; the difference is the
   linearisation), the held loop on a trivial right-hand side (the solver's
   own work: LU, back-substitutions, combinations) and a loop of the
   right-hand side alone.
2. **XLA kernels** of the compiled right-hand side and of the linearisation
   (fusions, library calls, dots, loops): at this size a kernel costs more in
   its launch than in its arithmetic.
3. **Solver-side variants**, the whole cycle timed in turn with the solver
   as it is (median of the paired ratios): the stages' combinations as
   products ``weights @ increments`` (a library call each; the solver sums
   them elementwise) and the step matrix inverted once (each stage's solve
   a product, not two triangular solves and a permutation).
4. **The bushing grid**: Rodas4's steps (rtol 1e-4) and Tsit5's (rtol 1e-6)
   on the rig with 45 to 720 grid nodes (the study uses 180).

    python benchmarks/experiments/rosenbrock_step_profile.py [--json out.json]
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import diffrax  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402
from rosenbrock_rig_cycle import cycle_on  # noqa: E402

from diffwear.dynamics import Rodas4  # noqa: E402
from diffwear.dynamics.equations import Baumgarte, vector_field  # noqa: E402
from diffwear.dynamics.simulate import _args_for_state_jacobian  # noqa: E402

_KERNEL = re.compile(r"= \S+ (fusion|custom-call|dot|while|call|conditional)\(")


def kernel_count(compiled_text: str) -> int:
    """Kernels of the entry computation of an optimised HLO module (each a
    launch on the CPU runtime; the bodies of fusions are not counted)."""
    return len(_KERNEL.findall(compiled_text[compiled_text.index("ENTRY"):]))


class InvertedRodas4(Rodas4):
    """Rodas4 with the step matrix's stiff block inverted once per step."""

    def _w_solve(self, lin, h, y0):
        stiff, free = self._blocks(y0)
        jac = lin.columns[1:].T
        hg = h * self.tableau.gamma
        inverse = jnp.linalg.inv(jnp.eye(jac.shape[1], dtype=y0.dtype) / hg - jac[stiff])
        j_free = jac[free]

        def w_solve(rhs):
            top = jnp.sum(inverse * rhs[stiff][None, :], axis=1)
            return jnp.concatenate([top, hg * (rhs[free] + jnp.sum(j_free * top, axis=1))])

        return w_solve


def _stages_as_dots(self, terms, args, t0, h, y0, lin):
    """`AbstractRosenbrock._stages` with the combinations as products
    (``weights @ stacked``: a library call each)."""
    co = self._coefficients(y0.dtype)
    w_solve = self._w_solve(lin, h, y0)
    f_t = lin.columns[0]

    def stage(us, i):
        f_stage = terms.vf(t0 + co.alpha[i] * h, y0 + co.a[i] @ us, args)
        u = w_solve(f_stage + (co.c[i] @ us) / h + co.gammas[i] * h * f_t)
        return us.at[i].set(u), None

    us = jnp.zeros((co.m.size,) + y0.shape, y0.dtype)
    us = us.at[0].set(w_solve(lin.f0 + co.gammas[0] * h * f_t))
    us, _ = jax.lax.scan(stage, us, jnp.arange(1, co.m.size))
    return y0 + co.m @ us, co.error_weights @ us, us


class DotRodas4(Rodas4):
    _stages = _stages_as_dots


def _rig(n_theta=None):
    """(mechanism, state after a warm-up cycle) of the rig study, on its
    bushing grid or on ``n_theta`` nodes."""
    from diffwear.studies.rig_21400 import N_THETA, PERIOD, _setup

    _, mech, y0 = _setup(n_theta=N_THETA if n_theta is None else n_theta)
    return mech, cycle_on(1e-6, PERIOD)(mech, y0, 0.0).y_final


def linearisation_share(mech, ys, period, steps=400, rounds=11) -> dict:
    """Fixed-step loops with the linearisation fresh and held (see notes)."""
    ros = Rodas4(jacobian_states=mech.feedback_states, jacobian_args=_args_for_state_jacobian,
                 dense_output=False)
    terms = diffrax.ODETerm(vector_field)
    trivial = diffrax.ODETerm(lambda t, y, args: -1e-3 * y)
    h = period / 212

    def loop(fresh, stage_terms=terms):
        @jax.jit
        def run(mech, y):
            args = (mech, Baumgarte())
            held = ros._linearise(terms, period, y, args)

            def body(i, y):
                lin = ros._linearise(terms, period, y, args) if fresh else held
                y1, _, _ = ros._stages(stage_terms, args, period, h * (1 + 1e-9 * i), y, lin)
                return y + 1e-6 * (y1 - y)  # stays on the settled cycle's state

            return jax.lax.fori_loop(0, steps, body, y)
        return run

    @jax.jit
    def right_hand_sides(mech, y):
        args = (mech, Baumgarte())
        return jax.lax.fori_loop(
            0, steps, lambda i, y: y + 1e-9 * vector_field(period + 1e-9 * i, y, args), y)

    runs = {"fresh": loop(True), "held": loop(False), "trivial": loop(False, trivial),
            "vf": right_hand_sides}
    times = _interleaved(runs, (mech, ys), rounds)
    lin = jax.jit(lambda m, y: ros._linearise(terms, period, y, (m, Baumgarte())))
    vf = jax.jit(lambda m, y: vector_field(period, y, (m, Baumgarte())))
    return dict(
        us_per_step_fresh=1e6 * np.median(times["fresh"]) / steps,
        us_per_step_held=1e6 * np.median(times["held"]) / steps,
        us_per_step_held_trivial_rhs=1e6 * np.median(times["trivial"]) / steps,
        us_per_right_hand_side=1e6 * np.median(times["vf"]) / steps,
        kernels_vector_field=kernel_count(vf.lower(mech, ys).compile().as_text()),
        kernels_linearisation=kernel_count(lin.lower(mech, ys).compile().as_text()),
    )


def _interleaved(fns: dict, args, rounds: int) -> dict:
    """Each jitted fn compiled, then timed in turn ``rounds`` times."""
    for f in fns.values():
        jax.block_until_ready(f(*args))
    times = {k: [] for k in fns}
    for _ in range(rounds):
        for k, f in fns.items():
            t = time.perf_counter()
            jax.block_until_ready(f(*args))
            times[k].append(time.perf_counter() - t)
    return {k: np.asarray(v) for k, v in times.items()}


def solver_variants(mech, ys, period, rounds=25) -> list[dict]:
    """The whole cycle on each variant, in turn; paired ratios to Rodas4."""
    variants = {"Rodas4": Rodas4(), "combinations as products": DotRodas4(),
                "inverted step matrix": InvertedRodas4()}
    fns = {k: cycle_on(1e-4, period, s) for k, s in variants.items()}
    outs = {k: f(mech, ys, period) for k, f in fns.items()}
    times = _interleaved(fns, (mech, ys, period), rounds)
    base = times["Rodas4"]
    return [dict(variant=k, steps=int(outs[k].num_steps), s_median=float(np.median(t)),
                 paired_ratio=float(np.median(t / base)),
                 max_state_difference=float(jnp.max(jnp.abs(outs[k].y_final
                                                            - outs["Rodas4"].y_final))))
            for k, t in times.items()]


def grid_steps(period, sizes=(45, 90, 180, 360, 720)) -> list[dict]:
    rows = []
    for n in sizes:
        mech, ys = _rig(n)
        ros = cycle_on(1e-4, period, Rodas4())(mech, ys, period)
        tsit = cycle_on(1e-6, period)(mech, ys, period)
        rows.append(dict(n_theta=n, rodas4_steps=int(ros.num_steps),
                         rodas4_accepted=int(ros.num_accepted_steps),
                         tsit5_steps=int(tsit.num_steps)))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    from diffwear.studies.rig_21400 import PERIOD

    mech, ys = _rig()
    share = linearisation_share(mech, ys, PERIOD)
    print(f"Rodas4 step, fixed-step loop: {share['us_per_step_fresh']:.0f} us fresh, "
          f"{share['us_per_step_held']:.0f} us with the linearisation held, "
          f"{share['us_per_step_held_trivial_rhs']:.0f} us held on a trivial right-hand side; "
          f"one right-hand side {share['us_per_right_hand_side']:.1f} us; kernels: right-hand "
          f"side {share['kernels_vector_field']}, linearisation "
          f"{share['kernels_linearisation']}")
    variants = solver_variants(mech, ys, PERIOD)
    print("\n| variant | steps | s per cycle, median | paired ratio | max state difference |")
    print("|---|---:|---:|---:|---:|")
    for r in variants:
        print(f"| {r['variant']} | {r['steps']} | {r['s_median']:.4f} | {r['paired_ratio']:.3f} | "
              f"{r['max_state_difference']:.1e} |")
    grid = grid_steps(PERIOD)
    print("\n| grid nodes | Rodas4 1e-4 steps (accepted) | Tsit5 1e-6 steps |")
    print("|---:|---:|---:|")
    for r in grid:
        print(f"| {r['n_theta']} | {r['rodas4_steps']} ({r['rodas4_accepted']}) | "
              f"{r['tsit5_steps']} |")
    if args.json:
        write_record(args.json, linearisation=share, variants=variants, grid=grid)


if __name__ == "__main__":
    main()
