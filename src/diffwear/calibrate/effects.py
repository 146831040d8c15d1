"""Candidate effects the base wear model lacks (the effect library).

Each effect is an optional model component with a strength ``s`` and, where
physics gives it one, a shape parameter (a time scale, a threshold) that is
fitted with it.  At ``s = 0`` the model is *exactly* the base model whatever
the shape (the same floating-point operations give the same numbers, checked
in the tests), so a score test at zero strength asks "would a little of this
effect explain the residual?".  Strengths are dimensionless; ``scale`` is the
size of a strength that changes the rig's wear by tens of per cent (the
optimiser works in units of it).  A shape is fitted as its logarithm, with a
stated prior: the default and a spread in ln units (`Shape`).

======================  =========================================================
name                    model change (base: dh/dt = k p v, v = R |omega_rel|)
======================  =========================================================
``run_in``              higher early wear rate: k (1 + s exp(-N / N_r)),
                        shape N_r (cycles); averaged exactly over the real
                        cycles a model step stands for.
``pressure_exponent``   non-linear Archard: k p (p / p_ref)^s, p_ref = `P_REF`
                        (no shape: p_ref and k are collinear).
``pv_wear``             temperature (p v) dependent coefficient above a
                        threshold: k (1 + s ramp(p v - pv_t) / pv_ref), shape
                        pv_t; pv_ref = `PV_REF`.
``creep``               bushing creep: a profile change without mass loss,
                        d(delta)/dN = s dh/dN.  The clearance is c0 + h +
                        delta; mass-based volume sees h only.
``guide_friction``      Coulomb friction in the slider guide: s x slider weight
                        x tanh(v / v_s), v_s = `GUIDE_SLIP_WIDTH`.
``transfer_film``       a PTFE transfer film built from the bushing's own wear
                        debris lowers the local rate towards a plateau:
                        k (1 - s (1 - exp(-h(theta) / h_f))), shape h_f (m).
``third_body``          debris retained in the joint (three-body abrasion)
                        raises the rate as the worn volume V grows, saturating
                        when the gap holds no more: k (1 + s (1 - exp(-V / V_d))),
                        shape V_d (m^3); s >= 0 (a lubricating debris layer,
                        s < 0, would be a run-in in disguise: V grows nearly
                        linearly in N).
======================  =========================================================

The multiplier of the wear rate is `rate_factor`: one array per profile node,
the product of the run-in, transfer-film and third-body factors.  The models
(`model.RigHistory`, `quasi_static.QuasiStaticRigHistory`) hold it constant
over a step (it changes over hundreds of cycles; a step is tens).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..contact import smoothing
from ..contact.archard import ArchardWear
from ..mechanism import STANDARD_GRAVITY
from ..mechanism import GuideFriction as _GuideForce
from ..wear import worn_volume
from ..wear.modifier import AbstractWearModifier, JointGeometry
from . import discrepancy as _discrepancy
from .discrepancy import LawPoint, RatePoint, Variable

# Run-in length: PTFE surfaces run in over the first ~10^2-10^3 cycles
# (Blanchet & Kennedy, Wear 153 (1992) 229); 500 cycles sits in that range and
# is short against the rig's 21,400-cycle run.  Prior: a factor 10 either way.
RUN_IN_CYCLES = 500.0
# Reference pressure of the non-linear Archard law: 1 MPa, the order of the
# rig's projected pressure (130 N / (19 mm x 13.1 mm) = 0.52 MPa) so that k
# keeps its meaning near the operating point and k and s are not collinear.
P_REF = 1.0e6  # Pa
# p v scale: 0.1 MPa m/s, the order of unfilled PTFE's PV limit (0.035-0.1 MPa
# m/s in bearing catalogues; Lancaster, Tribology 4 (1971) 82, for the limit
# as a thermal threshold).  Threshold prior 0.01 MPa m/s (the rig runs at
# p v ~ 0.01-0.05 MPa m/s), a factor 3 either way; smoothing band 2 kPa m/s.
PV_REF = 1.0e5  # Pa m/s
PV_THRESHOLD = 1.0e4  # Pa m/s
PV_BAND = 2.0e3  # Pa m/s
# Smoothing of the guide friction's sign: 10 mm/s, against the slider's peak
# speed of ~0.24 m/s (crank radius 2 x 38.1 mm at pi rad/s).
GUIDE_SLIP_WIDTH = 1e-2  # m/s
# Transfer film: PTFE's film forms from its first microns of wear debris and
# then cuts the wear rate by up to two orders (Bahadur, Wear 245 (2000) 92;
# Blanchet & Kennedy 1992).  Film depth scale 10 um, prior a factor 10.
FILM_DEPTH = 1.0e-5  # m
# Third body: debris retained in the contact (Godet, Wear 100 (1984) 437)
# saturates once the gap holds what it can; scale 10 mm^3 (the rig wears ~20
# mm^3 in 4,000 cycles), prior a factor 10.
DEBRIS_VOLUME = 1.0e-8  # m^3


@dataclass(frozen=True)
class Shape:
    """A fitted shape parameter: ``default`` (SI, ``unit``) and the prior spread
    ``log_std`` of its logarithm."""

    name: str
    default: float
    unit: str
    log_std: float


@dataclass(frozen=True)
class Effect:
    """One candidate effect: its strength's ``scale`` (the optimiser's unit)
    and physical ``lower`` bound, its ``shape`` (None: none) and ``source``.
    At strength 0 every hook must give exactly the base model (a factor of
    exactly 1.0, no force).  The hooks return None where the effect does not
    act there."""

    name: str
    description: str
    scale: float
    lower: float
    shape: Shape | None = None
    source: str = ""

    def law(self, strength, shape, point: LawPoint):
        """A factor of the wear law's dh/dt at ``point`` (None: none)."""
        return None

    def rate(self, strength, shape, point: RatePoint):
        """A factor of a model step's rate per node at ``point`` (None: none)."""
        return None

    def growth(self, strength):
        """The clearance profile's growth per unit of worn depth minus 1 (None: none)."""
        return None

    def forces(self, strength, base: dict) -> tuple:
        """Forces added to the rig for parameters ``base`` (SI)."""
        return ()

    @property
    def adds_forces(self) -> bool:
        """Whether the effect adds forces to the rig (a user's mechanism file
        has no rig to add them to)."""
        return type(self).forces is not Effect.forces


@dataclass(frozen=True)
class RunIn(Effect):
    """k (1 + s exp(-N / N_r)), averaged exactly over a step's real cycles."""

    def rate(self, strength, shape, point):
        return run_in_factor(strength, point.n_start, point.span, shape)


@dataclass(frozen=True)
class PressureExponent(Effect):
    """k p (p / p_ref)^s, p_ref = `P_REF`."""

    def law(self, strength, shape, point):
        loaded = point.pressure > 0.0
        safe = jnp.where(loaded, point.pressure, P_REF)  # double where: log(0) has no gradient
        return jnp.where(loaded, jnp.exp(strength * jnp.log(safe / P_REF)), 1.0)


@dataclass(frozen=True)
class PvWear(Effect):
    """k (1 + s ramp(p v - pv_t) / `PV_REF`), pv_t the shape."""

    def law(self, strength, shape, point):
        excess = smoothing.ramp(point.pressure * point.sliding_rate - shape, PV_BAND)
        return 1.0 + strength * excess / PV_REF


@dataclass(frozen=True)
class Creep(Effect):
    """The clearance grows by (1 + s) times the worn depth; mass sees the wear only."""

    def growth(self, strength):
        return strength


@dataclass(frozen=True)
class SliderGuideFriction(Effect):
    """Coulomb friction s x slider weight x tanh(v / `GUIDE_SLIP_WIDTH`) in the guide."""

    def forces(self, strength, base):
        return (_GuideForce("guide_friction", "slider", strength,
                            base["slider_mass"] * STANDARD_GRAVITY,
                            slip_width=GUIDE_SLIP_WIDTH),)


@dataclass(frozen=True)
class TransferFilm(Effect):
    """k (1 - s (1 - exp(-h / h_f))) per node, h_f the shape."""

    def rate(self, strength, shape, point):
        return 1.0 - strength * (1.0 - jnp.exp(-point.depth / shape))


@dataclass(frozen=True)
class ThirdBody(Effect):
    """k (1 + s (1 - exp(-V / V_d))), V the worn volume, V_d the shape."""

    def rate(self, strength, shape, point):
        return 1.0 + strength * (1.0 - jnp.exp(-point.volume / shape))


EFFECTS: tuple[Effect, ...] = (
    RunIn("run_in", "higher early wear rate k (1 + s exp(-N/N_r))", 1.0, 0.0,
          Shape("run_in_cycles", RUN_IN_CYCLES, "cycles", math.log(10.0)),
          "Blanchet & Kennedy, Wear 153 (1992) 229"),
    PressureExponent("pressure_exponent", "non-linear Archard k p (p/1 MPa)^s", 0.1, -1.0,
                     source="polymer wear exponents: Lancaster, Tribology 4 (1971) 82"),
    PvWear("pv_wear", "k (1 + s ramp(p v - pv_t) / 0.1 MPa m/s) above a p v threshold",
           1.0, -1.0, Shape("pv_threshold", PV_THRESHOLD, "Pa m/s", math.log(3.0)),
           "Lancaster, Tribology 4 (1971) 82"),
    Creep("creep", "bushing creep: profile change s x wear, no mass loss", 0.1, 0.0),
    SliderGuideFriction("guide_friction",
                        "Coulomb friction s x slider weight in the slider guide", 0.05, 0.0),
    TransferFilm("transfer_film", "transfer film: k (1 - s (1 - exp(-h/h_f))) per node", 0.3,
                 0.0, Shape("film_depth", FILM_DEPTH, "m", math.log(10.0)),
                 "Bahadur, Wear 245 (2000) 92"),
    ThirdBody("third_body", "retained debris: k (1 + s (1 - exp(-V/V_d)))", 0.3, 0.0,
              Shape("debris_volume", DEBRIS_VOLUME, "m^3", math.log(10.0)),
              "Godet, Wear 100 (1984) 437"),
)


@dataclass(frozen=True)
class Library:
    """The effects and the discrepancy variables a calibration chooses among
    (their order is the order of `EffectValues`' arrays).  Hashable: models
    hold it as static data."""

    effects: tuple[Effect, ...] = EFFECTS
    variables: tuple[Variable, ...] = _discrepancy.DEFAULT_VARIABLES

    def __post_init__(self):
        for kind, names in (("effect", self.names), ("discrepancy variable", self.variable_names)):
            twice = sorted({n for n in names if names.count(n) > 1})
            if twice:
                raise ValueError(f"calibration library: {kind} {', '.join(twice)} given twice")
        for v in self.variables:
            if v.stage not in ("law", "rate"):
                raise ValueError(f"discrepancy variable {v.name!r}: stage {v.stage!r}; "
                                 "allowed 'law', 'rate'")

    def extended(self, effects=(), variables=()) -> "Library":
        """This library with ``effects`` and ``variables`` added after its own."""
        return replace(self, effects=self.effects + tuple(effects),
                       variables=self.variables + tuple(variables))

    def without(self, names) -> "Library":
        """This library without the effects ``names``."""
        return replace(self, effects=tuple(e for e in self.effects if e.name not in names))

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(e.name for e in self.effects)

    @property
    def shaped(self) -> tuple[bool, ...]:
        return tuple(e.shape is not None for e in self.effects)

    @property
    def variable_names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.variables)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"unknown effect {name!r}; effects: {', '.join(self.names)}") from None

    def effect(self, name: str) -> Effect:
        return self.effects[self.index(name)]

    def variable(self, name: str) -> Variable:
        for v in self.variables:
            if v.name == name:
                return v
        raise KeyError(f"unknown discrepancy variable {name!r}; allowed: "
                       f"{', '.join(self.variable_names)}")

    @functools.cached_property
    def slices(self) -> dict[str, slice]:
        """Each variable's part of the flat coefficient vector."""
        starts = np.cumsum([0] + [v.size for v in self.variables])
        return {v.name: slice(int(starts[i]), int(starts[i + 1]))
                for i, v in enumerate(self.variables)}

    @property
    def size(self) -> int:
        """Length of the flat coefficient vector of every variable."""
        return sum(v.size for v in self.variables)

    @property
    def scales(self) -> np.ndarray:
        return np.array([e.scale for e in self.effects])

    @property
    def log_std(self) -> np.ndarray:
        return np.array([e.shape.log_std if e.shape else 0.0 for e in self.effects])


LIBRARY = Library()
NAMES = LIBRARY.names
INDEX = {n: i for i, n in enumerate(NAMES)}
SHAPED = LIBRARY.shaped


def log_shape(name: str, value: float, library: Library = LIBRARY) -> float:
    """ln(value / default) of effect ``name``'s shape (SI ``value``)."""
    shape = library.effect(name).shape
    if shape is None:
        raise KeyError(f"effect {name!r} has no shape parameter")
    return math.log(value / shape.default)


class EffectValues(eqx.Module):
    """Strength of every effect of ``library`` (its order; zeros: the base
    model), the logarithm of each shape over its default (zeros: the
    defaults; ignored for effects without a shape) and the coefficients of
    the learned discrepancy of k (`discrepancy`, `Library.slices`; zeros:
    none)."""

    strength: Float[Array, " E"]
    log_shape: Float[Array, " E"]
    discrepancy: Float[Array, " D"]
    # A rate factor from outside the library and the discrepancy's bases,
    # (theta, depth, cycles) -> factor per node: what a synthetic campaign's
    # truth may hold that no candidate can give exactly (None: none; the
    # calibration never sets it)
    outside: Callable | None = eqx.field(static=True, default=None)
    library: Library = eqx.field(static=True, default=LIBRARY)

    def __init__(self, strength, log_shape, discrepancy=None, outside=None,
                 library: Library = LIBRARY):
        self.library = library
        self.strength = jnp.asarray(strength, dtype=float)
        self.log_shape = jnp.asarray(log_shape, dtype=float)
        self.discrepancy = (jnp.zeros(library.size) if discrepancy is None
                            else jnp.asarray(discrepancy, dtype=float))
        self.outside = outside

    @classmethod
    def zero(cls, library: Library = LIBRARY) -> "EffectValues":
        n = len(library.effects)
        return cls(jnp.zeros(n), jnp.zeros(n), library=library)

    def with_discrepancy(self, variable: str, coefficients) -> "EffectValues":
        """These values with ``variable``'s discrepancy coefficients set."""
        d = self.discrepancy.at[self.library.slices[variable]].set(
            jnp.asarray(coefficients, dtype=float))
        return EffectValues(self.strength, self.log_shape, d, self.outside, self.library)

    def with_outside(self, factor: Callable) -> "EffectValues":
        """These values with the outside rate ``factor`` (theta, depth, cycles)
        -> multiplier (a synthetic truth)."""
        return EffectValues(self.strength, self.log_shape, self.discrepancy, factor,
                            self.library)

    @classmethod
    def of(cls, library: Library = LIBRARY, **strengths) -> "EffectValues":
        """``EffectValues.of(run_in=2.0)``; a shape as ``<shape name>=value`` (SI)."""
        n = len(library.effects)
        s, g = [0.0] * n, [0.0] * n
        shapes = {e.shape.name: (i, e.shape) for i, e in enumerate(library.effects) if e.shape}
        for key, value in strengths.items():
            if key in library.names:
                s[library.index(key)] = value
            elif key in shapes:
                i, shape = shapes[key]
                g[i] = math.log(value / shape.default)
            else:
                raise KeyError(f"unknown effect or shape {key!r}; effects: {library.names}")
        return cls(jnp.asarray(s, dtype=float), jnp.asarray(g, dtype=float), library=library)

    def __getitem__(self, name: str):
        return self.strength[self.library.index(name)]

    def shape(self, name: str):
        """The shape of effect ``name`` in SI."""
        i = self.library.index(name)
        shape = self.library.effects[i].shape
        if shape is None:
            raise KeyError(f"effect {name!r} has no shape parameter")
        return shape.default * jnp.exp(self.log_shape[i])

    def _shape_or_none(self, i: int):
        shape = self.library.effects[i].shape
        return None if shape is None else shape.default * jnp.exp(self.log_shape[i])

    def coefficients(self, variable: Variable):
        return self.discrepancy[self.library.slices[variable.name]]

    def growth(self):
        """The clearance profile's growth per unit of worn depth (1: none)."""
        g = 1.0
        for i, e in enumerate(self.library.effects):
            d = e.growth(self.strength[i])
            if d is not None:
                g = g + d
        return jnp.asarray(g, dtype=float)

    def forces(self, base: dict) -> tuple:
        """The forces the effects add to the rig for parameters ``base``."""
        return tuple(f for i, e in enumerate(self.library.effects)
                     for f in e.forces(self.strength[i], base))

    def law_factors(self, pressure, sliding_rate) -> list:
        """The factors of the wear law's dh/dt, in the library's order: the
        effects' ``law`` hooks, then the discrepancy's law-stage variables
        (each exactly 1.0 at zero values)."""
        point = LawPoint(pressure, sliding_rate)
        out = []
        for i, e in enumerate(self.library.effects):
            f = e.law(self.strength[i], self._shape_or_none(i), point)
            if f is not None:
                out.append(f)
        for v in self.library.variables:
            if v.stage == "law":
                out.append(v.factor(self.coefficients(v), v.read(point)))
        return out


class ModifiedArchardWear(ArchardWear):
    """Archard's law with the effects' law factors (`EffectValues.law_factors`:
    the pressure exponent, the p v term, the discrepancy in pressure and
    sliding speed); zero values are `ArchardWear`."""

    effects: EffectValues

    def __init__(self, coefficient, effects: EffectValues | None = None):
        super().__init__(coefficient)
        self.effects = EffectValues.zero() if effects is None else effects

    def depth_rate(self, pressure, sliding_rate):
        rate = self.coefficient * pressure * sliding_rate
        for f in self.effects.law_factors(pressure, sliding_rate):
            rate = rate * f
        return rate


def wear_law(k, effects: EffectValues) -> ModifiedArchardWear:
    return ModifiedArchardWear(k, effects)


def run_in_factor(strength, n_start, span, cycles=RUN_IN_CYCLES):
    """Mean of 1 + s exp(-N / N_r) over the real cycles [n_start, n_start + span]."""
    mean_decay = (cycles / span) * (jnp.exp(-n_start / cycles)
                                    - jnp.exp(-(n_start + span) / cycles))
    return 1.0 + strength * mean_decay


def rate_factor(effects: EffectValues, depth, volume, n_start, span, theta=None,
                total_cycles: float = 1.0):
    """Multiplier of the wear rate per profile node over the real cycles
    [n_start, n_start + span] at wear ``depth`` [m] (n,) and worn volume
    ``volume`` [m^3] (module notes): the effects' ``rate`` hooks; with the
    node angles ``theta`` (n,) and the fit window's end ``total_cycles``,
    the learned discrepancy's rate-stage factors (angle, cycle count at the
    span's middle, depth) as well."""
    point = RatePoint(theta, depth, volume, n_start, span, total_cycles)
    g = jnp.ones_like(depth)
    for i, e in enumerate(effects.library.effects):
        f = e.rate(effects.strength[i], effects._shape_or_none(i), point)
        if f is not None:
            g = g * f
    if theta is None:
        return jnp.asarray(g, dtype=float)
    for v in effects.library.variables:
        if v.stage == "rate":
            g = g * v.factor(effects.coefficients(v), v.read(point), total_cycles)
    if effects.outside is not None:
        g = g * effects.outside(theta, depth, point.middle)
    return g


class EffectsModifier(AbstractWearModifier):
    """The effects as a wear model's modifier (`diffwear.wear.modifier`):
    the clearance grows by `EffectValues.growth` times the worn depth, and a
    step's rate is scaled by `rate_factor` over its real cycles (``window``:
    the fit window's end, the cycle-count discrepancy's time scale)."""

    effects: EffectValues
    window: float = eqx.field(static=True, default=1.0)

    def growth(self):
        return self.effects.growth()

    def rate(self, h, n, dn, geometry: JointGeometry):
        volume = worn_volume(h, geometry.bushing_radius, geometry.bushing_depth)
        return rate_factor(self.effects, h, volume, n, dn, geometry.theta, self.window)
