"""The calibration's quasi-static forward model (`QuasiStaticRigHistory`).

The rig's crank-rod joint in the quasi-static reduction (`diffwear.quasistatic`):
the ideal mechanism's joint loads over one cycle (with the guide friction of
the effects), the pin at the equilibrium of the EFM springs, the profile
integrated in the cycle count by the linearly implicit Euler step with the
exact wear response A (`diffwear.wear.profile_ode` explains the step):

    (I + dN (1 + s_c) diag(g) A) dh = dN g w((1 + s_c) h),

w the wear per cycle at the clearance profile c0 + h + delta (delta = s_c h,
the creep), g the effects' rate factor (`effects.rate_factor`, held over the
step, its run-in part averaged exactly over it).  The step ends on every
cycle count a measurement needs (``checkpoints``) and is otherwise spaced
quadratically, N_j = N (j / steps)^2: short steps where the early effects
(run-in, film) act, long ones where the wear rate is steady.  The joint-force
trace is the ideal mechanism's load, which wear does not change in this
model: one trace stands for every cycle count.

Every number is traced, so the whole history (and a fit's Jacobian, by
forward-mode autodiff through the implicit-function derivative of the pin's
equilibrium) is one compiled program.
"""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..errors import InputError
from ..mechanism.geometry import safe_norm
from ..presets import TABLE_7_1, SliderCrankParameters
from ..quasistatic.joint import QuasiStaticJoint
from ..quasistatic.loads import JointLoads, cycle_loads
from ..wear import worn_volume
from ..wear.engine import AbstractWearTerm, CycleWear, Stop, initial_state, integrate
from ..wear.implicit import CycleGrid
from ..wear.status import RESULTS
from .effects import EffectValues, rate_factor
from .model import (
    JOINT,
    PENETRATION_WIDTH,
    History,
    check_campaign_cycles,
    rig_mechanism,
    sorted_trace,
)

# 40 quadratic steps: the rig's 21,400-cycle depth and volume within 0.1 % of
# 160 steps, with run-in (N_r = 50..5,000 cycles) and film effects switched on
# (tests/test_calibrate_quasi_static.py).
DEFAULT_STEPS = 40
# Load samples per cycle: the wear quadrature (the quasi-static model's 180)
DEFAULT_SAMPLES = 180
# Beyond the fit window (held-out inspections, a life), where the rate is
# nearly steady, each step is this much longer than the one before it: the
# rig's depth at 2x and 10x the window within 0.2 % of the window's own
# spacing continued (tests/test_calibrate_quasi_static.py).
EXTENSION_GROWTH = 1.1


def cycle_grid(cycles: float, steps: int, checkpoints=(), window: float | None = None
               ) -> np.ndarray:
    """0 = N_0 < N_1 < ... = ``cycles``: quadratic spacing up to ``window``
    (default ``cycles``), then steps growing by `EXTENSION_GROWTH` from the
    window's last, and every checkpoint (cycle counts below ``cycles``;
    nodes closer than 1e-9 N merged).  The nodes up to ``window`` do not
    depend on ``cycles``: a campaign's fit window is integrated on the same
    grid whether or not later (held-out) measurements extend it."""
    w = cycles if window is None else min(float(window), cycles)
    base = w * (np.arange(steps + 1) / steps) ** 2
    extension = []
    n, dn = w, base[-1] - base[-2]
    while n < cycles * (1.0 - 1e-9):
        dn *= EXTENSION_GROWTH
        n = min(n + dn, cycles)
        extension.append(n)
    extra = [float(c) for c in checkpoints if 0.0 < float(c) < cycles]
    grid = np.unique(np.concatenate([base, extension, extra]))
    keep = np.concatenate([[True], np.diff(grid) > 1e-9 * cycles])
    return grid[keep]


class QuasiStaticRigHistory(eqx.Module):
    """Quasi-static wear history of the Ch. 7 rig (module notes); called like
    `model.RigHistory` with ``base`` (SI) and `EffectValues`."""

    cycles: float = eqx.field(static=True)
    checkpoints: tuple = eqx.field(static=True, default=())
    # the end of the fit window (`Dataset.fit_cycles`; None: ``cycles``): the
    # quadratic grid's end and the cycle-count discrepancy's time scale
    window: float | None = eqx.field(static=True, default=None)
    steps: int = eqx.field(static=True, default=DEFAULT_STEPS)
    n_theta: int = eqx.field(static=True, default=90)
    samples: int = eqx.field(static=True, default=DEFAULT_SAMPLES)
    penetration_width: float | None = eqx.field(static=True, default=PENETRATION_WIDTH)
    p: SliderCrankParameters = TABLE_7_1

    name: ClassVar[str] = "quasi-static"
    # a fit on this model is checked on the dynamic one (`calibrate.reference`)
    checked_on_dynamic: ClassVar[bool] = True
    calibrates_files: ClassVar[bool] = True

    @classmethod
    def for_campaign(cls, cycles: float, checkpoints, settings, window=None
                     ) -> "QuasiStaticRigHistory":
        """The model of a campaign of ``cycles`` whose measurements are at
        ``checkpoints`` (cycle counts on its grid) and whose fit window ends at
        ``window``, at the resolution of ``settings`` (`fit.ModelSettings`)."""
        return cls(cycles=float(cycles), checkpoints=tuple(sorted({float(c) for c in checkpoints})),
                   steps=settings.steps, n_theta=settings.n_theta,
                   window=None if window is None else float(window))

    @property
    def fit_window(self) -> float:
        """The end of the fit window (module notes of `cycle_grid`)."""
        return self.cycles if self.window is None else min(self.window, self.cycles)

    def __check_init__(self):
        check_campaign_cycles(self.cycles)
        if int(self.steps) < 1:
            raise InputError(f"calibration model: steps must be >= 1, got {self.steps}")

    @property
    def period(self) -> float:
        return 2 * math.pi / float(self.p.omega)

    @property
    def grid(self) -> np.ndarray:
        return cycle_grid(self.cycles, self.steps, self.checkpoints, self.window)

    def describe(self) -> str:
        return (f"quasi-static model: {len(self.grid) - 1} steps in the cycle count, "
                f"{self.n_theta} profile nodes, {self.samples} load samples per cycle")

    @property
    def joint(self) -> str:
        return JOINT

    def mechanism(self, base: dict, effects: EffectValues):
        return rig_mechanism(base, effects, n_theta=self.n_theta,
                             penetration_width=self.penetration_width, p=self.p)

    def crank_angle(self, mech, y0):
        """The crank's angle at t = 0 (the force trace's angle origin)."""
        return mech.frames(mech.split(y0)[0]).pose("crank")[2]

    def __call__(self, base: dict, effects: EffectValues) -> History:
        mech, y0 = self.mechanism(base, effects)
        el = mech.element(self.joint)
        loads = cycle_loads(mech, (self.joint,), y0, self.period, samples=self.samples)
        lo = loads.joints[0]
        term = _RigWear(QuasiStaticJoint.from_joint(el), lo, effects, 1.0 + effects["creep"],
                        el.profile.theta, el.bushing_radius, el.law.depth, self.fit_window)
        solver = CycleGrid(jnp.asarray(self.grid))
        zeros = jnp.zeros(term.joint.n)
        state = initial_state((zeros,), jnp.full_like(lo.force, jnp.nan), ok=loads.ok)
        end, history = integrate(term, solver, state, stop=Stop(cycles=self.grid[-1]),
                                 slots=solver.slots(Stop(cycles=self.grid[-1]), None),
                                 keep_profiles=True)
        wear = jnp.concatenate([zeros[None], history["depth"][0]])
        angle = self.crank_angle(mech, y0) + 2 * jnp.pi * jnp.arange(self.samples) / self.samples
        angle, force = sorted_trace(angle, safe_norm(lo.force)[None])
        return History(
            cycles=solver.grid, wear=wear, creep=(term.grow - 1.0) * wear, force=force,
            force_cycles=jnp.zeros(1), force_angle=angle, theta=el.profile.theta,
            bushing_radius=el.bushing_radius, bushing_depth=el.law.depth,
            ok=end.status == RESULTS.ok)


class _RigWear(AbstractWearTerm):
    """The rig joint's quasi-static wear with the effects: the rate at the
    clearance profile c0 + (1 + s_c) h (creep), scaled by the effects' rate
    factor over each step (module notes)."""

    joint: QuasiStaticJoint
    loads: JointLoads
    effects: EffectValues
    grow: Float[Array, ""]
    theta: Float[Array, " n"]
    bushing_radius: Float[Array, ""]
    bushing_depth: Float[Array, ""]
    window: float = eqx.field(static=True)   # the cycle-count discrepancy's time scale

    def cycle(self, h, memory) -> CycleWear:
        dw, _, eq = self.joint.cycle_wear(self.grow * h[0], self.loads, memory)
        a = self.joint.wear_response(self.grow * h[0], self.loads, eq)
        return CycleWear(rate=(dw,), ok=eq.ok, memory=eq.offset, response=(a,))

    def modulate(self, cw: CycleWear, h, n, dn) -> CycleWear:
        volume = worn_volume(h[0], self.bushing_radius, self.bushing_depth)
        g = rate_factor(self.effects, h[0], volume, n, dn, self.theta, self.window)
        return CycleWear(rate=(g * cw.rate[0],), ok=cw.ok, memory=cw.memory,
                         response=(self.grow * g[:, None] * cw.response[0],))
