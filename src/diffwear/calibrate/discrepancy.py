"""A learned model discrepancy of the wear coefficient: k (1 + delta(x)).

When no effect of the library explains the data, the calibration fits a
smooth multiplicative correction of Archard's coefficient over one candidate
variable x at a time, in the spirit of Kennedy and O'Hagan's model
discrepancy (J. R. Stat. Soc. B 63 (2001) 425): delta is a short linear
expansion with a Gaussian smoothness prior on its coefficients, fitted by the
same compiled exact-derivative program as the parameters.  Each variable's
delta is a candidate beside the library's effects in the one forward
selection on the fit data (`diffwear.calibrate.selection`): the variable
chosen there is the one the model lacks.

=================  ==================================================  ==========
variable           basis phi_j(x) (delta = sum c_j phi_j)              prior std
=================  ==================================================  ==========
``angle``          cos(m theta), sin(m theta), m = 1..4 (bushing angle)  1 / m
``pressure``       xi, xi^2, xi^3; xi = tanh(ln(p / 1 MPa) / ln 10)     1 / j
``sliding_speed``  xi, xi^2, xi^3; xi = tanh(ln(v / 30 mm/s) / ln 10)   1 / j
``cycles``         Legendre P_1..P_3 of 2 N / N_end - 1 (N_end: the     1 / j
                   end of the fit window; held beyond it)
``depth``          smoothed steps s((h - d_j) / w_j) - s(-d_j / w_j),  1
                   d_j = 25, 50, 100, 200, 400 um, w_j = d_j / 4,
                   s(u) = (1 + tanh u) / 2: layers of the bore
=================  ==================================================  ==========

No basis holds a constant: a constant delta is a change of k, which the fit
already has.  The prior std falls as 1 / order (a roughness penalty: a
first harmonic of +-100 % is as plausible as a third of +-33 %).  The factor
is floored at `FLOOR` so that a large fitted delta never gives a negative
rate.  At zero coefficients every factor is exactly 1.0 and the model is the
base model bit for bit.

The coefficients of all five variables live in one flat vector
(`EffectValues.discrepancy`, `SLICES` gives each variable's part); the model
multiplies the five factors, so one compiled program serves every variable.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

VARIABLES = ("angle", "pressure", "sliding_speed", "cycles", "depth")
HARMONICS = 4       # angle: cos / sin of orders 1..HARMONICS
DEGREE = 3          # the other variables: orders 1..DEGREE
# Depth: the bore as layers whose wear coefficients differ (a coating, a
# moulded skin, a transfer layer): a smoothed step of k at each of these
# depths, doubling from 25 um (the scale of a transfer film or a moulded
# skin) to 0.4 mm (the rig wears 0.45 mm in 21,400 cycles, Ch. 7), each
# a quarter of its depth wide
LAYERS = (25e-6, 50e-6, 100e-6, 200e-6, 400e-6)  # m
LAYER_WIDTH = 0.25  # of the layer's depth
SIZES = {"angle": 2 * HARMONICS, "pressure": DEGREE, "sliding_speed": DEGREE,
         "cycles": DEGREE, "depth": len(LAYERS)}
_STARTS = np.cumsum([0] + [SIZES[v] for v in VARIABLES])
SLICES = {v: slice(int(_STARTS[i]), int(_STARTS[i + 1])) for i, v in enumerate(VARIABLES)}
SIZE = int(_STARTS[-1])
# Pressure scale: 1 MPa, the reference of the pressure exponent (`effects.P_REF`).
P_REF = 1.0e6  # Pa
# Sliding-speed scale: the rig's pin radius 9.5 mm x crank speed pi rad/s
# (Table 7-1) = 30 mm/s, the order of the relative sliding speed.
V_REF = 0.03  # m/s
FLOOR = 0.02    # smallest factor 1 + delta (a rate cut 50-fold at most)
WORDS = {"angle": "the bushing angle", "pressure": "the contact pressure",
         "sliding_speed": "the sliding speed", "cycles": "the cycle count",
         "depth": "the wear depth"}
UNITS = {"angle": "deg", "pressure": "MPa", "sliding_speed": "mm/s", "cycles": "cycles",
         "depth": "mm"}


def prior_std(variable: str) -> np.ndarray:
    """Prior 1-sigma of each coefficient of ``variable`` (module table)."""
    if variable == "angle":
        return np.repeat(1.0 / np.arange(1, HARMONICS + 1), 2)
    if variable == "depth":  # a layer's k may differ by its whole value
        return np.ones(len(LAYERS))
    return 1.0 / np.arange(1, DEGREE + 1)


def _powers(xi):
    return jnp.stack([xi ** j for j in range(1, DEGREE + 1)], axis=-1)


def basis(variable: str, x, total_cycles: float = 1.0):
    """phi(x) with a trailing axis of `SIZES` [variable] (module table); ``x``
    in SI (angle in rad, pressure Pa, speed m/s, cycles, depth m)."""
    x = jnp.asarray(x, dtype=float)
    if variable == "angle":
        m = jnp.arange(1, HARMONICS + 1, dtype=float)
        mx = x[..., None] * m
        return jnp.stack([jnp.cos(mx), jnp.sin(mx)], axis=-1).reshape(*x.shape, 2 * HARMONICS)
    if variable in ("pressure", "sliding_speed"):
        ref = P_REF if variable == "pressure" else V_REF
        positive = x > 0.0
        safe = jnp.where(positive, x, ref)  # double where: log(0) has no derivative
        xi = jnp.where(positive, jnp.tanh(jnp.log(safe / ref) / math.log(10.0)), -1.0)
        return _powers(xi)
    if variable == "cycles":
        # beyond the fit window the data say nothing of the trend: delta
        # holds its value at the window's end (no polynomial extrapolation)
        xi = jnp.clip(2.0 * x / total_cycles - 1.0, -1.0, 1.0)
        return jnp.stack([xi, 0.5 * (3 * xi ** 2 - 1), 0.5 * (5 * xi ** 3 - 3 * xi)], axis=-1)
    if variable == "depth":
        d = jnp.asarray(LAYERS)
        w = LAYER_WIDTH * d
        step = 0.5 * (1.0 + jnp.tanh((x[..., None] - d) / w))
        return step - 0.5 * (1.0 + jnp.tanh(-d / w))   # zero at the unworn surface
    raise KeyError(f"unknown discrepancy variable {variable!r}; allowed: {', '.join(VARIABLES)}")


def factor(coefficients, variable: str, x, total_cycles: float = 1.0):
    """1 + delta(x) (floored at `FLOOR`) for the flat coefficient vector."""
    c = coefficients[SLICES[variable]]
    return jnp.maximum(1.0 + basis(variable, x, total_cycles) @ c, FLOOR)


def delta(coefficients, variable: str, x, total_cycles: float = 1.0):
    """delta(x) (unfloored) for ``variable``'s coefficients alone (``coefficients``
    of length `SIZES` [variable])."""
    return basis(variable, x, total_cycles) @ jnp.asarray(coefficients)
