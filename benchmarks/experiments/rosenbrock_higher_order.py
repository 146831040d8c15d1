"""Experiment: does a fifth-order Rosenbrock method take fewer steps than Rodas4
on the rig?

Rodas4 needs ~210 steps a rig wear cycle at its preset rtol 1e-4, and looser
tolerances do not lower that (`rosenbrock_rig_cycle.py`): the step is set by
accuracy.  A higher order is the remaining lever on the step count.  Rodas5P
(Steinebach 2023, BIT Numer. Math. 63:27; eight stages, fifth order with a
fourth-order embedded solution, stiffly accurate, L-stable) costs two more
evaluations a step than Rodas4, so it pays only below ~170 steps.

Rodas5P is defined here, not in the library: this experiment is the reason it
is not there.  Its coefficients are checked by its observed order on a
two-state test problem (printed first).

    python benchmarks/experiments/rosenbrock_higher_order.py [--json out.json]

Prints the observed orders, then one rig wear cycle (after the warm-up) on
Rodas4 and Rodas5P at rtol = atol 1e-4, 3e-4 and 1e-3: steps (accepted), wall
time (median of 3 after compile) and the end state's error against Tsit5 at
rtol 1e-10 (as `rosenbrock_rig_cycle.py`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any, ClassVar

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import diffrax  # noqa: E402
import equinox as eqx  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402
from rosenbrock_rig_cycle import RigCycleReference, print_rows  # noqa: E402

from diffwear.dynamics import Rodas4  # noqa: E402
from diffwear.dynamics.rosenbrock import AbstractRosenbrock, RosenbrockTableau  # noqa: E402

# Rodas5P (Steinebach 2023) in the transformed form of `RosenbrockTableau`
# (the notation of Hairer-Wanner Eq. IV.7.25).
# Stiffly accurate: stages 6-8 are evaluated at t + h on the solution so far,
# the solution adds their increments, the embedded one leaves out the last.
_GAMMA = 0.21193756319429014
_A6 = (-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
       0.030198172008377946)
RODAS5P_TABLEAU = RosenbrockTableau(
    gamma=_GAMMA,
    a=((), (3.0,), (2.849394379747939, 0.45842242204463923),
       (-6.954028509809101, 2.489845061869568, -10.358996098473584),
       (2.8029986275628964, 0.5072464736228206, -0.3988312541770524, -0.04721187230404641),
       _A6, _A6 + (1.0,), _A6 + (1.0, 1.0)),
    c=((), (-14.155112264123755,), (-17.97296035885952, -2.859693295451294),
       (147.12150275711716, -1.41221402718213, 71.68940251302358),
       (165.43517024871676, -0.4592823456491126, 42.90938336958603, -5.961986721573306),
       (24.854864614690072, -3.0009227002832186, 47.4931110020768, 5.5814197821558125,
        -0.6610691825249471),
       (30.91273214028599, -3.1208243349937974, 77.79954646070892, 34.28646028294783,
        -19.097331116725623, -28.087943162872662),
       (37.80277123390563, -3.2571969029072276, 112.26918849496327, 66.9347231244047,
        -40.06618937091002, -54.66780262877968, -9.48861652309627)),
    alpha=(0.0, 0.6358126895828704, 0.4095798393397535, 0.9769306725060716,
           0.4288403609558664, 1.0, 1.0, 1.0),
    gammas=(_GAMMA, -0.42387512638858027, -0.3384627126235924, 1.8046452872882734,
            2.325825639765069, 0.0, 0.0, 0.0),
    m=_A6 + (1.0, 1.0, 1.0),
    m_embedded=_A6 + (1.0, 1.0, 0.0),
    order=5,
)


class Rodas5P(AbstractRosenbrock):
    jacobian_states: Any = eqx.field(static=True, default=None)
    jacobian_args: Any = eqx.field(static=True, default=None)
    differentiate_jacobian: bool = eqx.field(static=True, default=True)
    dense_output: bool = eqx.field(static=True, default=True)
    tableau: ClassVar[RosenbrockTableau] = RODAS5P_TABLEAU


def observed_orders(solver, steps=(10, 20, 40)) -> list[float]:
    """Error at t = 1 of y0' = -2 (y0 - cos t), y1' = y0 y1 / 2 (non-autonomous,
    nonlinear, mildly stiff: the classical order shows) with constant steps
    against Tsit5 at 1e-14; log2 of successive error ratios."""
    term = diffrax.ODETerm(lambda t, y, a: jnp.stack([-2.0 * (y[0] - jnp.cos(t)),
                                                      0.5 * y[0] * y[1]]))
    y0 = jnp.array([1.0, 1.0])
    ref = diffrax.diffeqsolve(term, diffrax.Tsit5(), 0.0, 1.0, 1e-4, y0, max_steps=100_000,
                              stepsize_controller=diffrax.PIDController(rtol=1e-14, atol=1e-14))
    errors = [float(jnp.max(jnp.abs(diffrax.diffeqsolve(
        term, solver, 0.0, 1.0, 1.0 / n, y0).ys[-1] - ref.ys[-1]))) for n in steps]
    return [float(np.log2(a / b)) for a, b in zip(errors, errors[1:])]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    orders = {name: observed_orders(s) for name, s in (("Rodas4", Rodas4()),
                                                        ("Rodas5P", Rodas5P()))}
    for name, o in orders.items():
        print(f"{name}: observed orders {', '.join(f'{x:.2f}' for x in o)} (10 -> 20 -> 40 steps)")
    ref = RigCycleReference()
    rows = [ref.row(name, rtol, solver) for name, solver in (("Rodas4", Rodas4()),
                                                             ("Rodas5P", Rodas5P()))
            for rtol in (1e-4, 3e-4, 1e-3)]
    print_rows(rows)
    if args.json:
        write_record(args.json, observed_orders=orders, rows=rows)


if __name__ == "__main__":
    main()
