"""The calibration's forward model: the Ch. 7 rig's wear history with the
candidate effects, as one pure JAX function of the parameters.

`RigHistory` runs a warm-up cycle (wear discarded, the pin's start-up
transient) and then ``dynamic_cycles`` dynamic cycles with a constant
extrapolation factor A = cycles / dynamic_cycles (thesis Eq. 4-18), like
`wear.evolve` ("constant"), but it keeps what measurements need: the wear
profile h and the creep profile delta after every dynamic cycle (at real
cycles N_j = j A) and the joint-force trace of every dynamic cycle.  A must
stay below ~1/lambda (lambda = k k_f s ~ 1e-3 per cycle on the rig, see
`wear.life`): `MAX_EXTRAPOLATION` is enforced.

`Observation` maps that history onto one measured series (profile at N,
volume or maximum depth against N, force against crank angle at N):
profiles are linear in N between snapshots (exactly what the explicit update
makes them) and periodic-linear in angle between grid nodes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from ..contact import centred_state, contact_history
from ..dynamics import consistent_state
from ..errors import InputError
from ..mechanism import STANDARD_GRAVITY, GuideFriction
from ..presets import (
    RIG_JOINT,
    RIG_SPRING_FREE_LENGTH,
    TABLE_7_1,
    SliderCrankParameters,
    WearJointDesign,
    rig_slider_crank,
    with_wear_joint,
)
from ..wear import smooth_max, wear_cycle, worn_mechanism, worn_volume
from ..wear.cycle import clearance_element
from .effects import GUIDE_SLIP_WIDTH, INDEX, ModifiedArchardWear, run_in_factor

JOINT = "crank_rod"
BASE_NAMES = ("k", "clearance", "depth", "diameter", "mu", "free_length")
# Explicit extrapolation is stable for A lambda < ~1 (wear.life notes; lambda ~
# 1e-3 per cycle on the rig).  Measured on the rig over 4,000 cycles (n_theta
# 90): max depth 0.1089 / 0.0848 / 0.0896 mm and volume 19.18 / 18.95 / 18.90
# mm^3 at A = 1000 / 500 / 250: the peak still oscillates at A = 500 (-5 %),
# the volume has converged (0.3 %).  250 keeps the profile within a few %.
MAX_EXTRAPOLATION = 250.0
# Contact-onset band of the EFM springs: 1 um (as the Ch. 8 life model,
# design.two_joint): with the law's default band the forward-mode tangents of
# a cycle are ~100x the central differences (the smoothed onset is nearly a
# jump at fixed steps); with 1 um they agree (tests/test_calibrate.py).
PENETRATION_WIDTH = 1e-6  # m
MAX_DEPTH_TEMPERATURE = 1e-7  # m, smooth max of the profile (as sweep.RigWear)


def rig_defaults() -> dict[str, float]:
    """The thesis rig: Table 7-2 joint, calibrated spring free length."""
    d = RIG_JOINT
    return {"k": float(d.k), "clearance": float(d.clearance), "depth": float(d.depth),
            "diameter": float(d.diameter), "mu": float(d.mu),
            "free_length": float(RIG_SPRING_FREE_LENGTH)}


class History(eqx.Module):
    """Snapshots at real cycles ``cycles`` = (0, A, 2A, ..., D A): wear ``wear``
    and creep ``creep`` profiles [m] (D + 1, n); ``force`` [N]: |joint force|
    over dynamic cycle j (starting at N = j A), (D, force_samples), at crank
    angles ``crank_angle`` [rad] (increasing, spanning 2 pi); ``theta``:
    profile grid; ``ok``: every cycle integrated."""

    cycles: jnp.ndarray
    wear: jnp.ndarray
    creep: jnp.ndarray
    force: jnp.ndarray
    crank_angle: jnp.ndarray
    theta: jnp.ndarray
    bushing_radius: jnp.ndarray
    bushing_depth: jnp.ndarray
    ok: jnp.ndarray


class RigHistory(eqx.Module):
    """Wear history of the Ch. 7 rig's crank-rod PTFE bushing with the
    candidate effects of `calibrate.effects` (see the module notes).

    Call with ``base`` (a dict of the `BASE_NAMES` in SI) and ``strengths``
    (one per effect, `effects.NAMES` order; zeros: the base model)."""

    cycles: float = eqx.field(static=True)
    dynamic_cycles: int = eqx.field(static=True, default=8)
    n_theta: int = eqx.field(static=True, default=90)
    force_samples: int = eqx.field(static=True, default=91)
    cycle_rtol: float = eqx.field(static=True, default=1e-6)
    cycle_atol: float = eqx.field(static=True, default=1e-6)
    penetration_width: float | None = eqx.field(static=True, default=PENETRATION_WIDTH)
    p: SliderCrankParameters = TABLE_7_1

    def __check_init__(self):
        if not (math.isfinite(self.cycles) and self.cycles > 0):
            raise InputError(f"calibration model: the campaign's cycles must be finite and "
                             f"> 0, got {self.cycles}")
        if int(self.dynamic_cycles) < 1:
            raise InputError(f"calibration model: dynamic cycles (--dynamic-cycles) must be "
                             f">= 1, got {self.dynamic_cycles}")
        if self.extrapolation > MAX_EXTRAPOLATION:
            need = math.ceil(self.cycles / MAX_EXTRAPOLATION)
            raise InputError(
                f"calibration model: {self.cycles:,.0f} cycles in {self.dynamic_cycles} dynamic "
                f"cycles (--dynamic-cycles) is an extrapolation factor A = "
                f"{self.extrapolation:,.0f} > {MAX_EXTRAPOLATION:g}, where the explicit wear "
                f"extrapolation is unstable; use --dynamic-cycles {need} or more")

    @property
    def extrapolation(self) -> float:
        return self.cycles / self.dynamic_cycles

    @property
    def period(self) -> float:
        return 2 * math.pi / float(self.p.omega)

    def mechanism(self, base: dict, strengths):
        friction = GuideFriction("guide_friction", "slider", strengths[INDEX["guide_friction"]],
                                 self.p.m3 * STANDARD_GRAVITY, slip_width=GUIDE_SLIP_WIDTH)
        mech0, q_guess = rig_slider_crank(self.p, free_length=base["free_length"],
                                          extra_forces=(friction,))
        design = WearJointDesign(base["k"], base["clearance"], base["depth"], base["diameter"],
                                 RIG_JOINT.wall, base["mu"], RIG_JOINT.restitution)
        mech = with_wear_joint(mech0, design, n_theta=self.n_theta,
                               penetration_width=self.penetration_width)
        index, _ = clearance_element(mech, JOINT)
        wear = ModifiedArchardWear(base["k"], strengths[INDEX["pressure_exponent"]],
                                   strengths[INDEX["pv_wear"]])
        mech = eqx.tree_at(lambda m: m.forces[index].wear, mech, wear)
        # the ideal kinematics at t = 0 do not depend on the fitted parameters
        y0 = centred_state(mech0, consistent_state(mech0, q_guess, check=False), mech)
        return mech, y0

    def __call__(self, base: dict, strengths) -> History:
        strengths = jnp.asarray(strengths, dtype=float)
        mech, y0 = self.mechanism(base, strengths)
        el = mech.element(JOINT)
        period, a = self.period, self.extrapolation
        # forward-mode adjoint: the calibration differentiates with jacfwd
        # (few parameters, many residuals)
        kw = dict(rtol=self.cycle_rtol, atol=self.cycle_atol, adjoint=diffrax.ForwardMode())
        warm = wear_cycle(mech, JOINT, y0, 0.0, period, **kw)
        n = self.n_theta

        def step(c, j):
            h, delta, y, t, ok = c
            worn = worn_mechanism(mech, JOINT, h + delta)
            r = wear_cycle(worn, JOINT, y, t, period, n_save=self.force_samples, **kw)
            dh = a * run_in_factor(strengths[INDEX["run_in"]], j * a, a) * r.depth_increment
            force = contact_history(worn, JOINT, r.ys).force_magnitude
            ok = ok & r.ok
            h = jnp.where(ok, h + dh, h)
            delta = jnp.where(ok, delta + strengths[INDEX["creep"]] * dh, delta)
            return (h, delta, r.y_end, t + period, ok), (h, delta, force)

        zeros = jnp.zeros(n)
        init = (zeros, zeros, warm.y_end, jnp.asarray(period), warm.ok)
        (_, _, _, _, ok), (hs, ds, forces) = lax.scan(
            step, init, jnp.arange(self.dynamic_cycles, dtype=float))
        crank0 = mech.frames(mech.split(y0)[0]).pose("crank")[2]
        angle = crank0 + jnp.linspace(0.0, 2 * jnp.pi, self.force_samples)
        return History(
            cycles=a * jnp.arange(self.dynamic_cycles + 1, dtype=float),
            wear=jnp.concatenate([zeros[None], hs]), creep=jnp.concatenate([zeros[None], ds]),
            force=forces, crank_angle=angle, theta=el.profile.theta,
            bushing_radius=el.bushing_radius, bushing_depth=el.law.depth, ok=ok)


# ------------------------------------------------------------------ observation
def _interpolate(snapshots, n, extrapolation):
    """Snapshots (D + 1, ...) at N = j A, linearly interpolated at N = ``n``."""
    last = snapshots.shape[0] - 1
    w = jnp.clip(n / extrapolation, 0.0, float(last))
    j = jnp.clip(jnp.floor(w), 0, last - 1).astype(int)
    frac = w - j
    return (1.0 - frac) * snapshots[j] + frac * snapshots[j + 1]


def periodic_interp(x, xp, fp):
    """Linear interpolation of the 2 pi-periodic samples (xp, fp) at x."""
    return jnp.interp(x, xp, fp, period=2 * jnp.pi)


@dataclass(frozen=True, eq=False)
class Observation:
    """One measured series as a function of the `History` (SI values).

    ``kind``: "profile" (depth at bushing angles ``x`` after ``cycles``),
    "volume" (worn volume at cycle counts ``x``; ``basis`` "mass": wear only,
    "profile": wear + creep), "max_depth" (at cycle counts ``x``), "force"
    (|joint force| at crank angles ``x`` during the dynamic cycle that starts
    nearest ``cycles``).  ``extrapolation``/``dynamic_cycles``: the model's.
    A plain (hashable by identity) object: it is closed over, not traced."""

    kind: str
    x: np.ndarray
    extrapolation: float
    dynamic_cycles: int
    cycles: float = 0.0
    basis: str = "mass"

    @property
    def force_cycle(self) -> int:
        """The dynamic cycle whose force trace stands for the measurement."""
        return min(max(int(round(self.cycles / self.extrapolation)), 0), self.dynamic_cycles - 1)

    def __call__(self, h: History):
        x = jnp.asarray(self.x)
        a = self.extrapolation
        total = h.wear + h.creep
        if self.kind == "profile":
            return periodic_interp(x, h.theta, _interpolate(total, self.cycles, a))
        if self.kind == "max_depth":
            return jax.vmap(lambda n: smooth_max(_interpolate(total, n, a),
                                                 MAX_DEPTH_TEMPERATURE))(x)
        if self.kind == "volume":
            seen = h.wear if self.basis == "mass" else total
            prof = jax.vmap(lambda n: _interpolate(seen, n, a))(x)
            return worn_volume(prof, h.bushing_radius, h.bushing_depth)
        if self.kind == "force":
            trace = h.force[self.force_cycle]
            # The samples span [a0, a0 + 2 pi]; drop the first: the cycle starts
            # on the profile just deepened by A cycles' wear, so the pin is
            # momentarily off the wall (force 0 for ~1 ms).  The end sample, a
            # full turn later, stands for the angle a0.
            return periodic_interp(x, jnp.mod(h.crank_angle[1:], 2 * jnp.pi), trace[1:])
        raise InputError(f"unknown series kind {self.kind!r}")
