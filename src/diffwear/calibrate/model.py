"""The calibration's forward models: the Ch. 7 rig's wear history with the
candidate effects, as pure JAX functions of the parameters.

Both models return a `History`: the wear profile h and the creep profile
delta at increasing cycle counts, and joint-force traces.  `Observation` maps
it onto one measured series (profile at N, volume or maximum depth against N,
force against crank angle at N): profiles are linear in N between snapshots
and periodic-linear in angle between grid nodes.

* `RigHistory` (dynamic): `diffwear.models.Dynamic` with the effects as its
  modifier (`effects.EffectsModifier`): a warm-up cycle (wear discarded, the
  pin's start-up transient), then ``dynamic_cycles`` dynamic cycles with a
  constant extrapolation factor A = cycles / dynamic_cycles (thesis Eq.
  4-18), keeping the profiles after every dynamic cycle (at N_j = j A) and
  each cycle's joint-force trace (``force_samples``).  A must stay below
  ~1/lambda (lambda = k k_f s ~ 1e-3 per cycle on the rig, see `wear.life`):
  `MAX_EXTRAPOLATION` is enforced.
* `quasi_static.QuasiStaticRigHistory`: `diffwear.models.QuasiStatic` on a
  cycle grid with the same modifier (milliseconds per step, exact
  derivatives), the model the calibration runs on by default.

`RigParameters` names what a dataset may fit or hold: the joint (wear
coefficient, clearance, bushing depth, pin diameter, friction, wall), the
spring (free length, rate) and the linkage (lengths, masses, inertias); the
last two groups are the "mechanism suspects" of `identify`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..contact import centred_state
from ..dynamics import consistent_state
from ..errors import InputError
from ..models import Dynamic
from ..presets import (
    RIG_JOINT,
    RIG_SPRING_FREE_LENGTH,
    RIG_SPRING_STIFFNESS,
    TABLE_7_1,
    SliderCrankParameters,
    WearJointDesign,
    rig_slider_crank,
    with_wear_joint,
)
from ..wear import smooth_max, worn_volume
from ..wear.cycle import clearance_element
from ..wear.dynamic_term import CycleSettings
from ..wear.extrapolation import Constant
from ..wear.status import not_computed
from .effects import EffectsModifier, EffectValues, wear_law
from .parameters import NAMES

JOINT = "crank_rod"
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

BASE_NAMES = NAMES  # every rig parameter (`parameters.RIG_PARAMETERS`)


def rig_defaults() -> dict[str, float]:
    """The thesis rig: Table 7-1 linkage (its lengths are joint-to-centre
    half-lengths, `presets.TABLE_7_1`), Table 7-2 joint, Table 7-3 spring rate,
    calibrated spring free length."""
    d, p = RIG_JOINT, TABLE_7_1
    return {"k": float(d.k), "clearance": float(d.clearance), "depth": float(d.depth),
            "diameter": float(d.diameter), "mu": float(d.mu), "wall": float(d.wall),
            "free_length": float(RIG_SPRING_FREE_LENGTH),
            "spring_stiffness": float(RIG_SPRING_STIFFNESS),
            "crank_length": 2 * float(p.l1), "rod_length": 2 * float(p.l2),
            "crank_mass": float(p.m1), "rod_mass": float(p.m2), "slider_mass": float(p.m3),
            "crank_inertia": float(p.inertia1), "rod_inertia": float(p.inertia2)}


def rig_mechanism(base: dict, effects: EffectValues, *, n_theta: int,
                  penetration_width: float | None = PENETRATION_WIDTH,
                  p: SliderCrankParameters = TABLE_7_1):
    """The rig with its wearing crank-rod joint for parameters ``base`` (SI,
    `parameters.RIG_PARAMETERS`) and the effects' wear law and guide friction: (the
    mechanism, its state at t = 0 with the pin centred)."""
    params = SliderCrankParameters(
        l1=base["crank_length"] / 2, l2=base["rod_length"] / 2, m1=base["crank_mass"],
        inertia1=base["crank_inertia"], m2=base["rod_mass"], inertia2=base["rod_inertia"],
        m3=base["slider_mass"], inertia3=p.inertia3, omega=p.omega)
    mech0, q_guess = rig_slider_crank(params, free_length=base["free_length"],
                                      spring_stiffness=base["spring_stiffness"],
                                      extra_forces=effects.forces(base))
    design = WearJointDesign(base["k"], base["clearance"], base["depth"], base["diameter"],
                             base["wall"], base["mu"], RIG_JOINT.restitution)
    mech = with_wear_joint(mech0, design, n_theta=n_theta, penetration_width=penetration_width)
    index, _ = clearance_element(mech, JOINT)
    mech = eqx.tree_at(lambda m: m.forces[index].wear, mech, wear_law(base["k"], effects))
    y0 = centred_state(mech0, consistent_state(mech0, q_guess, check=False), mech)
    return mech, y0


def check_campaign_cycles(cycles: float) -> None:
    """`InputError` unless the campaign's cycle count is finite and > 0."""
    if not (math.isfinite(cycles) and cycles > 0):
        raise InputError(f"calibration model: the campaign's cycles must be finite and > 0, "
                         f"got {cycles}")


class History(eqx.Module):
    """Snapshots at real cycles ``cycles`` (K,), increasing from 0: wear
    ``wear`` and creep ``creep`` profiles [m] (K, n); ``force`` [N]: |joint
    force| traces (F, S), trace f starting at cycle ``force_cycles[f]``, at
    crank angles ``force_angle`` [rad] (S, increasing in [0, 2 pi));
    ``theta``: profile grid; ``ok``: every cycle model succeeded."""

    cycles: jnp.ndarray
    wear: jnp.ndarray
    creep: jnp.ndarray
    force: jnp.ndarray
    force_cycles: jnp.ndarray
    force_angle: jnp.ndarray
    theta: jnp.ndarray
    bushing_radius: jnp.ndarray
    bushing_depth: jnp.ndarray
    ok: jnp.ndarray


def sorted_trace(angle, force):
    """(angles wrapped to [0, 2 pi) and sorted, the forces in the same order)."""
    wrapped = jnp.mod(angle, 2 * jnp.pi)
    order = jnp.argsort(wrapped)
    return wrapped[order], force[..., order]


class RigHistory(eqx.Module):
    """Dynamic wear history of the Ch. 7 rig's crank-rod PTFE bushing with the
    candidate effects of `calibrate.effects` (see the module notes).

    Call with ``base`` (a dict of the `BASE_NAMES` in SI) and ``effects``
    (`EffectValues`; zero strengths: the base model)."""

    cycles: float = eqx.field(static=True)
    dynamic_cycles: int = eqx.field(static=True, default=8)
    n_theta: int = eqx.field(static=True, default=90)
    force_samples: int = eqx.field(static=True, default=91)
    cycle_rtol: float = eqx.field(static=True, default=1e-6)
    cycle_atol: float = eqx.field(static=True, default=1e-6)
    penetration_width: float | None = eqx.field(static=True, default=PENETRATION_WIDTH)
    p: SliderCrankParameters = TABLE_7_1
    # the end of the fit window (None: ``cycles``): the cycle-count
    # discrepancy's time scale (`quasi_static.cycle_grid`)
    window: float | None = eqx.field(static=True, default=None)

    name: ClassVar[str] = "dynamic"
    # a fit on this model is the reference: nothing to check it against
    checked_on_dynamic: ClassVar[bool] = False
    # a user's mechanism file is calibrated on the quasi-static model only
    calibrates_files: ClassVar[bool] = False

    @classmethod
    def for_campaign(cls, cycles: float, checkpoints, settings, window=None) -> "RigHistory":
        """The model of a campaign of ``cycles`` (fit window ending at
        ``window``) at the resolution of ``settings`` (`fit.ModelSettings`):
        ``settings.dynamic_cycles`` dynamic cycles, default the fewest with A
        <= `MAX_EXTRAPOLATION`."""
        del checkpoints  # the dynamic history reports every dynamic cycle
        d = settings.dynamic_cycles or max(1, math.ceil(cycles / MAX_EXTRAPOLATION))
        return cls(cycles=float(cycles), dynamic_cycles=d, n_theta=settings.n_theta,
                   force_samples=settings.force_samples, cycle_rtol=settings.cycle_rtol,
                   cycle_atol=settings.cycle_rtol,
                   window=None if window is None else float(window))

    @property
    def fit_window(self) -> float:
        return self.cycles if self.window is None else min(self.window, self.cycles)

    def __check_init__(self):
        check_campaign_cycles(self.cycles)
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

    def describe(self) -> str:
        return (f"dynamic model: {self.dynamic_cycles} dynamic cycles of A = "
                f"{self.extrapolation:g} real cycles, {self.n_theta} profile nodes")

    def mechanism(self, base: dict, effects: EffectValues):
        return rig_mechanism(base, effects, n_theta=self.n_theta,
                             penetration_width=self.penetration_width, p=self.p)

    def wear_model(self, effects: EffectValues) -> Dynamic:
        """`diffwear.models.Dynamic` with this model's constant extrapolation,
        the effects as its modifier and each dynamic cycle's force trace kept;
        forward-mode adjoint (the calibration differentiates with jacfwd: few
        parameters, many residuals)."""
        return Dynamic(cycle=CycleSettings(self.cycle_rtol, self.cycle_atol,
                                           adjoint=diffrax.ForwardMode()),
                       warmup_cycles=1, extrapolation=Constant(self.extrapolation),
                       modifier=EffectsModifier(effects, self.fit_window),
                       force_samples=self.force_samples)

    def __call__(self, base: dict, effects: EffectValues) -> History:
        mech, y0 = self.mechanism(base, effects)
        el = mech.element(JOINT)
        solution = self.wear_model(effects).solve(mech, (JOINT,), y0, period=self.period,
                                                  cycles=self.cycles)
        d = self.dynamic_cycles
        zeros = jnp.zeros(self.n_theta)
        assert solution.slots is not None  # the dynamic evolution records its slots
        hs, forces = solution.slots["depth"][:d], solution.slots["force"][:d]
        crank0 = mech.frames(mech.split(y0)[0]).pose("crank")[2]
        # The samples span [a0, a0 + 2 pi]; drop the first: the cycle starts on
        # the profile just deepened by A cycles' wear, so the pin is
        # momentarily off the wall (force 0 for ~1 ms).  The end sample, a
        # full turn later, stands for the angle a0.
        angle = crank0 + jnp.linspace(0.0, 2 * jnp.pi, self.force_samples)[1:]
        angle, forces = sorted_trace(angle, forces[:, 1:])
        a = self.extrapolation
        grow = effects.growth()
        wear = jnp.concatenate([zeros[None], hs])
        return History(
            cycles=a * jnp.arange(self.dynamic_cycles + 1, dtype=float),
            wear=wear, creep=(grow - 1.0) * wear,
            force=forces, force_cycles=a * jnp.arange(self.dynamic_cycles, dtype=float),
            force_angle=angle, theta=el.profile.theta,
            bushing_radius=el.bushing_radius, bushing_depth=el.law.depth,
            ok=~not_computed(solution.result))


# ------------------------------------------------------------------ observation
def _interpolate(snapshots, n, cycles):
    """Snapshots (K, ...) at real cycles ``cycles`` (K,), linearly interpolated
    at N = ``n`` (held constant beyond the last)."""
    last = cycles.shape[0] - 1
    j = jnp.clip(jnp.searchsorted(cycles, n, side="right") - 1, 0, last - 1)
    span = cycles[j + 1] - cycles[j]
    frac = jnp.clip((n - cycles[j]) / jnp.where(span > 0, span, 1.0), 0.0, 1.0)
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
    (|joint force| at crank angles ``x`` during the model's force trace that
    starts nearest ``cycles``).  A plain (hashable by identity) object: it is
    closed over, not traced."""

    kind: str
    x: np.ndarray
    cycles: float = 0.0
    basis: str = "mass"

    def __call__(self, h: History):
        x = jnp.asarray(self.x)
        total = h.wear + h.creep
        if self.kind == "profile":
            return periodic_interp(x, h.theta, _interpolate(total, self.cycles, h.cycles))
        if self.kind == "max_depth":
            return jax.vmap(lambda n: smooth_max(_interpolate(total, n, h.cycles),
                                                 MAX_DEPTH_TEMPERATURE))(x)
        if self.kind == "volume":
            seen = h.wear if self.basis == "mass" else total
            prof = jax.vmap(lambda n: _interpolate(seen, n, h.cycles))(x)
            return worn_volume(prof, h.bushing_radius, h.bushing_depth)
        if self.kind == "force":
            trace = h.force[jnp.argmin(jnp.abs(h.force_cycles - self.cycles))]
            return periodic_interp(x, h.force_angle, trace)
        raise InputError(f"unknown series kind {self.kind!r}")
