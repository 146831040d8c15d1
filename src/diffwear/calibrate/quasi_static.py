"""The calibration's quasi-static forward model (`QuasiStaticRigHistory`).

The rig's crank-rod joint on the quasi-static wear model
(`diffwear.models.QuasiStatic`) with the effects as its modifier
(`effects.EffectsModifier`): the ideal mechanism's joint loads over one cycle
(with the guide friction of the effects), the pin at the equilibrium of the
EFM springs, the profile integrated in the cycle count on this model's grid
by the linearly implicit Euler step with the exact wear response A
(`diffwear.wear.modifier`):

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

from ..errors import InputError
from ..mechanism.geometry import safe_norm
from ..models import QuasiStatic
from ..presets import TABLE_7_1, SliderCrankParameters
from ..wear.status import not_computed
from .effects import EffectsModifier, EffectValues
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

    def wear_model(self, effects: EffectValues) -> QuasiStatic:
        """`diffwear.models.QuasiStatic` on this model's cycle grid with the
        effects as its modifier."""
        return QuasiStatic(samples=self.samples, grid=jnp.asarray(self.grid),
                           modifier=EffectsModifier(effects, self.fit_window))

    def __call__(self, base: dict, effects: EffectValues) -> History:
        mech, y0 = self.mechanism(base, effects)
        el = mech.element(self.joint)
        joints = (self.joint,)
        model = self.wear_model(effects).prepared(mech, joints, y0, self.period)
        solution = model.solve(mech, joints, y0, period=self.period, cycles=self.grid[-1])
        lo = model.loads(mech, joints, y0, self.period).joints[0]
        wear = solution.history[0].depth
        grow = effects.growth()
        angle = self.crank_angle(mech, y0) + 2 * jnp.pi * jnp.arange(self.samples) / self.samples
        angle, force = sorted_trace(angle, safe_norm(lo.force)[None])
        return History(
            cycles=jnp.asarray(self.grid), wear=wear, creep=(grow - 1.0) * wear, force=force,
            force_cycles=jnp.zeros(1), force_angle=angle, theta=el.profile.theta,
            bushing_radius=el.bushing_radius, bushing_depth=el.law.depth,
            ok=~not_computed(solution.result))
