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

import math
from collections.abc import Callable
from dataclasses import dataclass

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..contact import smoothing
from ..contact.archard import ArchardWear
from . import discrepancy as _discrepancy

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
    name: str
    description: str
    scale: float      # typical strength (optimiser unit)
    lower: float      # physically allowed lower bound of the strength
    shape: Shape | None = None
    source: str = ""


EFFECTS: tuple[Effect, ...] = (
    Effect("run_in", "higher early wear rate k (1 + s exp(-N/N_r))", 1.0, 0.0,
           Shape("run_in_cycles", RUN_IN_CYCLES, "cycles", math.log(10.0)),
           "Blanchet & Kennedy, Wear 153 (1992) 229"),
    Effect("pressure_exponent", "non-linear Archard k p (p/1 MPa)^s", 0.1, -1.0,
           source="polymer wear exponents: Lancaster, Tribology 4 (1971) 82"),
    Effect("pv_wear", "k (1 + s ramp(p v - pv_t) / 0.1 MPa m/s) above a p v threshold",
           1.0, -1.0, Shape("pv_threshold", PV_THRESHOLD, "Pa m/s", math.log(3.0)),
           "Lancaster, Tribology 4 (1971) 82"),
    Effect("creep", "bushing creep: profile change s x wear, no mass loss", 0.1, 0.0),
    Effect("guide_friction", "Coulomb friction s x slider weight in the slider guide",
           0.05, 0.0),
    Effect("transfer_film", "transfer film: k (1 - s (1 - exp(-h/h_f))) per node", 0.3, 0.0,
           Shape("film_depth", FILM_DEPTH, "m", math.log(10.0)),
           "Bahadur, Wear 245 (2000) 92"),
    Effect("third_body", "retained debris: k (1 + s (1 - exp(-V/V_d)))", 0.3, 0.0,
           Shape("debris_volume", DEBRIS_VOLUME, "m^3", math.log(10.0)),
           "Godet, Wear 100 (1984) 437"),
)
NAMES = tuple(e.name for e in EFFECTS)
INDEX = {n: i for i, n in enumerate(NAMES)}
SHAPED = tuple(e.shape is not None for e in EFFECTS)


def log_shape(name: str, value: float) -> float:
    """ln(value / default) of effect ``name``'s shape (SI ``value``)."""
    shape = EFFECTS[INDEX[name]].shape
    if shape is None:
        raise KeyError(f"effect {name!r} has no shape parameter")
    return math.log(value / shape.default)


class EffectValues(eqx.Module):
    """Strength of every effect (`NAMES` order; zeros: the base model), the
    logarithm of each shape over its default (zeros: the defaults; ignored
    for effects without a shape) and the coefficients of the learned
    discrepancy of k (`discrepancy`; zeros: none)."""

    strength: Float[Array, " E"]
    log_shape: Float[Array, " E"]
    discrepancy: Float[Array, " D"]
    # A rate factor from outside the library and the discrepancy's bases,
    # (theta, depth, cycles) -> factor per node: what a synthetic campaign's
    # truth may hold that no candidate can give exactly (None: none; the
    # calibration never sets it)
    outside: Callable | None = eqx.field(static=True, default=None)

    def __init__(self, strength, log_shape, discrepancy=None, outside=None):
        self.strength = jnp.asarray(strength, dtype=float)
        self.log_shape = jnp.asarray(log_shape, dtype=float)
        self.discrepancy = (jnp.zeros(_discrepancy.SIZE) if discrepancy is None
                            else jnp.asarray(discrepancy, dtype=float))
        self.outside = outside

    @classmethod
    def zero(cls) -> "EffectValues":
        return cls(jnp.zeros(len(NAMES)), jnp.zeros(len(NAMES)))

    def with_discrepancy(self, variable: str, coefficients) -> "EffectValues":
        """These values with ``variable``'s discrepancy coefficients set."""
        d = self.discrepancy.at[_discrepancy.SLICES[variable]].set(
            jnp.asarray(coefficients, dtype=float))
        return EffectValues(self.strength, self.log_shape, d, self.outside)

    def with_outside(self, factor: Callable) -> "EffectValues":
        """These values with the outside rate ``factor`` (theta, depth, cycles)
        -> multiplier (a synthetic truth)."""
        return EffectValues(self.strength, self.log_shape, self.discrepancy, factor)

    @classmethod
    def of(cls, **strengths) -> "EffectValues":
        """``EffectValues.of(run_in=2.0)``; a shape as ``<shape name>=value`` (SI)."""
        s, g = [0.0] * len(NAMES), [0.0] * len(NAMES)
        shapes = {e.shape.name: (i, e.shape) for i, e in enumerate(EFFECTS) if e.shape}
        for key, value in strengths.items():
            if key in INDEX:
                s[INDEX[key]] = value
            elif key in shapes:
                i, shape = shapes[key]
                g[i] = math.log(value / shape.default)
            else:
                raise KeyError(f"unknown effect or shape {key!r}; effects: {NAMES}")
        return cls(jnp.asarray(s, dtype=float), jnp.asarray(g, dtype=float))

    def __getitem__(self, name: str):
        return self.strength[INDEX[name]]

    def shape(self, name: str):
        """The shape of effect ``name`` in SI."""
        i = INDEX[name]
        shape = EFFECTS[i].shape
        if shape is None:
            raise KeyError(f"effect {name!r} has no shape parameter")
        return shape.default * jnp.exp(self.log_shape[i])


class ModifiedArchardWear(ArchardWear):
    """Archard's law with the pressure exponent and the p v term:
    dh/dt = k p v (p / p_ref)^a (1 + b ramp(p v - pv_t) / pv_ref); a = b = 0 is
    `ArchardWear`."""

    exponent: jnp.ndarray
    pv_strength: jnp.ndarray
    pv_threshold: jnp.ndarray
    discrepancy: jnp.ndarray | None

    def __init__(self, coefficient, exponent=0.0, pv_strength=0.0, pv_threshold=PV_THRESHOLD,
                 discrepancy=None):
        super().__init__(coefficient)
        self.exponent = jnp.asarray(exponent, dtype=float)
        self.pv_strength = jnp.asarray(pv_strength, dtype=float)
        self.pv_threshold = jnp.asarray(pv_threshold, dtype=float)
        self.discrepancy = None if discrepancy is None else jnp.asarray(discrepancy, dtype=float)

    def depth_rate(self, pressure, sliding_rate):
        base = self.coefficient * pressure * sliding_rate
        loaded = pressure > 0.0
        safe = jnp.where(loaded, pressure, P_REF)  # double where: log(0) has no gradient
        power = jnp.where(loaded, jnp.exp(self.exponent * jnp.log(safe / P_REF)), 1.0)
        excess = smoothing.ramp(pressure * sliding_rate - self.pv_threshold, PV_BAND)
        pv = 1.0 + self.pv_strength * excess / PV_REF
        rate = base * power * pv
        if self.discrepancy is None:
            return rate
        # the learned discrepancy's pressure and sliding-speed factors (exactly
        # 1.0 at zero coefficients)
        return (rate * _discrepancy.factor(self.discrepancy, "pressure", pressure)
                * _discrepancy.factor(self.discrepancy, "sliding_speed", jnp.abs(sliding_rate)))


def wear_law(k, effects: EffectValues) -> ModifiedArchardWear:
    return ModifiedArchardWear(k, effects["pressure_exponent"], effects["pv_wear"],
                               effects.shape("pv_wear"), effects.discrepancy)


def run_in_factor(strength, n_start, span, cycles=RUN_IN_CYCLES):
    """Mean of 1 + s exp(-N / N_r) over the real cycles [n_start, n_start + span]."""
    mean_decay = (cycles / span) * (jnp.exp(-n_start / cycles)
                                    - jnp.exp(-(n_start + span) / cycles))
    return 1.0 + strength * mean_decay


def rate_factor(effects: EffectValues, depth, volume, n_start, span, theta=None,
                total_cycles: float = 1.0):
    """Multiplier of the wear rate per profile node over the real cycles
    [n_start, n_start + span] at wear ``depth`` [m] (n,) and worn volume
    ``volume`` [m^3] (module notes); with the node angles ``theta`` (n,) and
    the campaign's length ``total_cycles``, the learned discrepancy's angle,
    cycle-count (at the span's middle) and depth factors as well."""
    run_in = run_in_factor(effects["run_in"], n_start, span, effects.shape("run_in"))
    film = 1.0 - effects["transfer_film"] * (
        1.0 - jnp.exp(-depth / effects.shape("transfer_film")))
    debris = 1.0 + effects["third_body"] * (
        1.0 - jnp.exp(-volume / effects.shape("third_body")))
    g = run_in * debris * film
    if theta is None:
        return g
    d = effects.discrepancy
    middle = n_start + 0.5 * span
    g = (g * _discrepancy.factor(d, "angle", theta)
         * _discrepancy.factor(d, "cycles", middle, total_cycles)
         * _discrepancy.factor(d, "depth", depth))
    if effects.outside is not None:
        g = g * effects.outside(theta, depth, middle)
    return g
