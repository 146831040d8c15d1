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
``depth``          steps s((h - d_j) / w_j) - s(-d_j / w_j),           1
                   d_j = 25, 50, 100, 200, 400 um, w_j = d_j / 16,
                   s(u) = (1 + tanh u) / 2: layers of the bore
=================  ==================================================  ==========

No basis holds a constant: a constant delta is a change of k, which the fit
already has.  The prior std falls as 1 / order (a roughness penalty: a
first harmonic of +-100 % is as plausible as a third of +-33 %).  The factor
is floored at `FLOOR` so that a large fitted delta never gives a negative
rate.  At zero coefficients every factor is exactly 1.0 and the model is the
base model bit for bit.

Each variable is one class (`Variable`): its basis, its prior, where the
model reads it (``stage``: the wear law's pressure and sliding speed, or
the rate's angle, cycle count and depth), what data can show it and how it
is drawn.  A new variable is one subclass, added to a calibration's library
(`diffwear.calibrate.effects.Library.extended`).  The coefficients of a
library's variables live in one flat vector (`EffectValues.discrepancy`,
`Library.slices` gives each variable's part); the model multiplies every
factor, so one compiled program serves every variable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import jax.numpy as jnp
import numpy as np

HARMONICS = 4       # angle: cos / sin of orders 1..HARMONICS
DEGREE = 3          # the other variables: orders 1..DEGREE
# Depth: the bore as layers whose wear coefficients differ (a coating, a
# moulded skin, a transfer layer): a step of k at each of these depths,
# doubling from 25 um (the scale of a transfer film or a moulded skin) to
# 0.4 mm (the rig wears 0.45 mm in 21,400 cycles, Ch. 7).  A layer's
# interface is sharp (a coating's is microns wide): each step is a
# sixteenth of its depth wide, so k is near constant between two steps and
# a step deeper than the fit data reach stays at its prior mean, zero:
# below the deepest data the last layer seen is held
LAYERS = (25e-6, 50e-6, 100e-6, 200e-6, 400e-6)  # m
LAYER_WIDTH = 1.0 / 16.0  # of the layer's depth
# Pressure scale: 1 MPa, the reference of the pressure exponent (`effects.P_REF`).
P_REF = 1.0e6  # Pa
# Sliding-speed scale: the rig's pin radius 9.5 mm x crank speed pi rad/s
# (Table 7-1) = 30 mm/s, the order of the relative sliding speed.
V_REF = 0.03  # m/s
FLOOR = 0.02    # smallest factor 1 + delta (a rate cut 50-fold at most)


class LawPoint(NamedTuple):
    """Where the wear law is evaluated: contact ``pressure`` [Pa] and
    ``sliding_rate`` [m/s] (per node)."""

    pressure: object
    sliding_rate: object


class RatePoint(NamedTuple):
    """Where the rate factor of a model step is evaluated: the profile's node
    angles ``theta`` [rad] and wear ``depth`` [m] (per node), the worn
    ``volume`` [m^3], the step's real cycles [``n_start``, ``n_start +
    span``] and the fit window's end ``window`` (cycles)."""

    theta: object
    depth: object
    volume: object
    n_start: object
    span: object
    window: float

    @property
    def middle(self):
        """The step's middle cycle count."""
        return self.n_start + 0.5 * self.span


@dataclass(frozen=True)
class Variable:
    """One variable a learned discrepancy of k may be a function of.

    ``stage``: "law" (read from a `LawPoint`) or "rate" (from a
    `RatePoint`); ``words`` and ``unit`` name it in reports, ``scale``
    turns SI into the report's unit; ``log_spaced``: drawn on a
    logarithmic axis."""

    name: str
    words: str
    unit: str
    scale: float = 1.0
    stage: ClassVar[str] = "rate"
    log_spaced: ClassVar[bool] = False

    @property
    def axis(self) -> str:
        """The variable as a plot's axis label."""
        return f"{self.words.removeprefix('the ')} [{self.unit}]"

    @property
    def size(self) -> int:
        return int(self.prior_std().size)

    def prior_std(self) -> np.ndarray:
        """Prior 1-sigma of each coefficient: 1 / order (module notes)."""
        return 1.0 / np.arange(1, DEGREE + 1)

    def basis(self, x, window: float = 1.0):
        """phi(x) with a trailing axis of `size`; ``x`` in SI; ``window``: the
        fit window's end in cycles (the cycle count's time scale)."""
        raise NotImplementedError

    def read(self, point):
        """The variable's value at a `LawPoint` or `RatePoint` (SI)."""
        raise NotImplementedError

    def span(self, data) -> tuple:
        """The range (SI) over which delta is drawn and described for ``data``."""
        raise NotImplementedError

    def unsupported(self, data) -> str | None:
        """Why ``data`` cannot show a discrepancy in this variable (None: they can)."""
        return None

    def factor(self, coefficients, x, window: float = 1.0):
        """1 + delta(x), floored at `FLOOR` (``coefficients``: this variable's)."""
        return jnp.maximum(1.0 + self.basis(x, window) @ coefficients, FLOOR)


def _powers(xi):
    return jnp.stack([xi ** j for j in range(1, DEGREE + 1)], axis=-1)


@dataclass(frozen=True)
class BushingAngle(Variable):
    """The bushing angle: a Fourier series of orders 1..`HARMONICS`."""

    name: str = "angle"
    words: str = "the bushing angle"
    unit: str = "deg"
    scale: float = 180.0 / math.pi

    def prior_std(self) -> np.ndarray:
        return np.repeat(1.0 / np.arange(1, HARMONICS + 1), 2)

    def basis(self, x, window: float = 1.0):
        x = jnp.asarray(x, dtype=float)
        m = jnp.arange(1, HARMONICS + 1, dtype=float)
        mx = x[..., None] * m
        return jnp.stack([jnp.cos(mx), jnp.sin(mx)], axis=-1).reshape(*x.shape, 2 * HARMONICS)

    def read(self, point):
        return point.theta

    def span(self, data) -> tuple:
        return (0.0, 2 * math.pi)

    def unsupported(self, data) -> str | None:
        angles = sum(s.x.size for s in data.series if s.kind == "profile")
        if angles < 2 * self.size:
            return ("it needs worn profiles over the bushing angle (at least "
                    f"{2 * self.size} points); the dataset has {angles}")
        return None


@dataclass(frozen=True)
class LogScaled(Variable):
    """A positive variable about a reference ``ref``: powers 1..`DEGREE` of
    xi = tanh(ln(x / ref) / ln 10), drawn over [``low``, ``high``] (a decade
    either side of ``ref``)."""

    ref: float = 1.0
    low: float = 0.1     # the drawn range [SI]
    high: float = 10.0
    stage: ClassVar[str] = "law"
    log_spaced: ClassVar[bool] = True

    def basis(self, x, window: float = 1.0):
        x = jnp.asarray(x, dtype=float)
        positive = x > 0.0
        safe = jnp.where(positive, x, self.ref)  # double where: log(0) has no derivative
        xi = jnp.where(positive, jnp.tanh(jnp.log(safe / self.ref) / math.log(10.0)), -1.0)
        return _powers(xi)

    def span(self, data) -> tuple:
        return (self.low, self.high)


@dataclass(frozen=True)
class ContactPressure(LogScaled):
    name: str = "pressure"
    words: str = "the contact pressure"
    unit: str = "MPa"
    scale: float = 1e-6
    ref: float = P_REF
    low: float = 1e5     # 0.1-10 MPa
    high: float = 1e7

    def read(self, point):
        return point.pressure


@dataclass(frozen=True)
class SlidingSpeed(LogScaled):
    name: str = "sliding_speed"
    words: str = "the sliding speed"
    unit: str = "mm/s"
    scale: float = 1e3
    ref: float = V_REF
    low: float = 3e-3    # 3-300 mm/s
    high: float = 3e-1

    def read(self, point):
        return jnp.abs(point.sliding_rate)


@dataclass(frozen=True)
class CycleCount(Variable):
    """The cycle count: Legendre P_1..P_3 of 2 N / N_end - 1, held beyond
    the fit window's end N_end (the data say nothing of the trend there)."""

    name: str = "cycles"
    words: str = "the cycle count"
    unit: str = "cycles"

    def basis(self, x, window: float = 1.0):
        xi = jnp.clip(2.0 * jnp.asarray(x, dtype=float) / window - 1.0, -1.0, 1.0)
        return jnp.stack([xi, 0.5 * (3 * xi ** 2 - 1), 0.5 * (5 * xi ** 3 - 3 * xi)], axis=-1)

    @property
    def axis(self) -> str:
        return "cycles"

    def read(self, point):
        return point.middle

    def span(self, data) -> tuple:
        return (0.0, float(data.max_cycles))

    def unsupported(self, data) -> str | None:
        counts = {float(c) for s in data.series if s.kind != "force"
                  for c in np.unique(s.cycle_counts)}
        if len(counts) < 2:
            return "it needs wear measured at two or more cycle counts"
        return None


@dataclass(frozen=True)
class WearDepth(Variable):
    """The wear depth: smoothed steps at the layers' depths (`LAYERS`), zero
    at the unworn surface; a layer's k may differ by its whole value."""

    name: str = "depth"
    words: str = "the wear depth"
    unit: str = "mm"
    scale: float = 1e3

    def prior_std(self) -> np.ndarray:
        return np.ones(len(LAYERS))

    def basis(self, x, window: float = 1.0):
        x = jnp.asarray(x, dtype=float)
        d = jnp.asarray(LAYERS)
        w = LAYER_WIDTH * d
        step = 0.5 * (1.0 + jnp.tanh((x[..., None] - d) / w))
        return step - 0.5 * (1.0 + jnp.tanh(-d / w))   # zero at the unworn surface

    def read(self, point):
        return point.depth

    def span(self, data) -> tuple:
        deepest = max((float(np.max(s.y)) for s in data.series if s.kind == "profile"),
                      default=LAYERS[-1])
        return (0.0, max(deepest, 1e-6))


DEFAULT_VARIABLES: tuple[Variable, ...] = (BushingAngle(), ContactPressure(), SlidingSpeed(),
                                           CycleCount(), WearDepth())

# The default variables by name (the calibration's library may add more:
# `diffwear.calibrate.effects.Library`)
VARIABLES = tuple(v.name for v in DEFAULT_VARIABLES)
_BY_NAME = {v.name: v for v in DEFAULT_VARIABLES}
SIZES = {v.name: v.size for v in DEFAULT_VARIABLES}
_STARTS = np.cumsum([0] + [SIZES[v] for v in VARIABLES])
SLICES = {v: slice(int(_STARTS[i]), int(_STARTS[i + 1])) for i, v in enumerate(VARIABLES)}
SIZE = int(_STARTS[-1])
WORDS = {v.name: v.words for v in DEFAULT_VARIABLES}
UNITS = {v.name: v.unit for v in DEFAULT_VARIABLES}


def variable(name: str) -> Variable:
    """The default variable called ``name``."""
    try:
        return _BY_NAME[name]
    except KeyError:
        raise KeyError(f"unknown discrepancy variable {name!r}; allowed: "
                       f"{', '.join(VARIABLES)}") from None


def prior_std(name: str) -> np.ndarray:
    """Prior 1-sigma of each coefficient of default variable ``name``."""
    return variable(name).prior_std()


def basis(name: str, x, total_cycles: float = 1.0):
    """phi(x) of default variable ``name`` (`Variable.basis`)."""
    return variable(name).basis(x, total_cycles)


def factor(coefficients, name: str, x, total_cycles: float = 1.0):
    """1 + delta(x) (floored at `FLOOR`) for the default flat coefficient vector."""
    return variable(name).factor(coefficients[SLICES[name]], x, total_cycles)


def delta(coefficients, name: str, x, total_cycles: float = 1.0):
    """delta(x) (unfloored) for ``name``'s coefficients alone."""
    return basis(name, x, total_cycles) @ jnp.asarray(coefficients)
