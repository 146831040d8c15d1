"""Candidate effects the base wear model lacks (the effect library).

Each effect is an optional model component with one strength ``s``; at
``s = 0`` the model is *exactly* the base model (the same floating-point
operations give the same numbers, checked in tests/test_calibrate_effects.py),
so a score test at zero strength asks "would a little of this effect explain
the residual?".  Strengths are dimensionless; ``scale`` is the size of a
strength that changes the rig's wear by tens of per cent (the optimiser works
in units of it).

=====================  ==========================================================
name                   model change (base: dh/dt = k p v, v = R |omega_rel|)
=====================  ==========================================================
``run_in``             higher early wear rate: k (1 + s exp(-N / N_r)),
                       N_r = `RUN_IN_CYCLES`; averaged exactly over the A real
                       cycles a dynamic cycle stands for.
``pressure_exponent``  non-linear Archard: k p (p / p_ref)^s, p_ref = `P_REF`.
``pv_wear``            temperature (p v) dependent coefficient:
                       k (1 + s p v / pv_ref), pv_ref = `PV_REF`.
``creep``              bushing creep: a profile change without mass loss,
                       d(delta)/dN = s dh/dN (it grows where the bushing is
                       loaded; on the rig the sliding speed is nearly uniform
                       over the contact arc, so pressure-driven flow and
                       pressure x sliding wear share their shape).  The
                       clearance is c0 + h + delta; mass-based volume sees h only.
``guide_friction``     Coulomb friction in the slider guide: s x slider weight
                       x tanh(v / v_s), v_s = `GUIDE_SLIP_WIDTH` (the thesis
                       rig's force trace has a burst at slider reversal, Ch. 7).
=====================  ==========================================================

Constants are scales, not fitted values: their choice only rescales ``s``.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp

from ..contact.archard import ArchardWear

# Run-in length: PTFE transfer films form over the first ~10^2-10^3 cycles
# (Blanchet & Kennedy, Wear 153 (1992) 229); 500 cycles sits in that range and
# is short against the rig's 21,400-cycle run.
RUN_IN_CYCLES = 500.0
# Reference pressure of the non-linear Archard law: 1 MPa, the order of the
# rig's projected pressure (130 N / (19 mm x 13.1 mm) = 0.52 MPa) so that k
# keeps its meaning near the operating point and k and s are not collinear.
P_REF = 1.0e6  # Pa
# p v scale: 0.1 MPa m/s, the order of unfilled PTFE's PV limit (0.035-0.1 MPa
# m/s in bearing catalogues); the rig runs at p v ~ 0.01-0.05 MPa m/s.
PV_REF = 1.0e5  # Pa m/s
# Smoothing of the guide friction's sign: 10 mm/s, against the slider's peak
# speed of ~0.24 m/s (crank radius 2 x 38.1 mm at pi rad/s).
GUIDE_SLIP_WIDTH = 1e-2  # m/s


@dataclass(frozen=True)
class Effect:
    name: str
    description: str
    scale: float      # typical strength (optimiser unit)
    lower: float      # physically allowed lower bound of the strength


EFFECTS: tuple[Effect, ...] = (
    Effect("run_in", "higher early wear rate k (1 + s exp(-N/500))", 1.0, 0.0),
    Effect("pressure_exponent", "non-linear Archard k p (p/1 MPa)^s", 0.1, -1.0),
    Effect("pv_wear", "p v (temperature) dependent k (1 + s p v / 0.1 MPa m/s)", 1.0, -1.0),
    Effect("creep", "bushing creep: profile change s x wear, no mass loss", 0.1, 0.0),
    Effect("guide_friction", "Coulomb friction s x slider weight in the slider guide",
           0.05, 0.0),
)
NAMES = tuple(e.name for e in EFFECTS)
INDEX = {n: i for i, n in enumerate(NAMES)}


class ModifiedArchardWear(ArchardWear):
    """Archard's law with the pressure exponent and the p v term:
    dh/dt = k p v (p / p_ref)^a (1 + b p v / pv_ref); a = b = 0 is `ArchardWear`."""

    exponent: jnp.ndarray
    pv_strength: jnp.ndarray

    def __init__(self, coefficient, exponent=0.0, pv_strength=0.0):
        super().__init__(coefficient)
        self.exponent = jnp.asarray(exponent, dtype=float)
        self.pv_strength = jnp.asarray(pv_strength, dtype=float)

    def depth_rate(self, pressure, sliding_rate):
        base = self.coefficient * pressure * sliding_rate
        loaded = pressure > 0.0
        safe = jnp.where(loaded, pressure, P_REF)  # double where: log(0) has no gradient
        power = jnp.where(loaded, jnp.exp(self.exponent * jnp.log(safe / P_REF)), 1.0)
        pv = 1.0 + self.pv_strength * pressure * sliding_rate / PV_REF
        return base * power * pv


def run_in_factor(strength, n_start, span):
    """Mean of 1 + s exp(-N / N_r) over the real cycles [n_start, n_start + span]."""
    n_r = RUN_IN_CYCLES
    mean_decay = (n_r / span) * (jnp.exp(-n_start / n_r) - jnp.exp(-(n_start + span) / n_r))
    return 1.0 + strength * mean_decay
