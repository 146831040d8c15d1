"""Wear models: how the wear of one crank cycle is computed, as strategy objects.

Every consumer of wear (`cycles_to_limit`, the wear studies, the bushing
design, the calibration, the sweeps) takes a model object, as diffrax takes
a solver:

* `Dynamic` (this module): the reference.  The mechanism with its clearance
  joints is integrated over each simulated cycle (Baumgarte DAE with the
  stiff EFM contact, diffrax); the pin may impact and leave the wall.
* `diffwear.quasistatic.QuasiStatic`: the pin at the equilibrium of the EFM
  springs under the loads of the ideal mechanism; smooth, exact gradients,
  milliseconds per cycle; valid while the contact is kept (it checks).
"""

from __future__ import annotations

import abc
from typing import ClassVar

import diffrax
import equinox as eqx
from jaxtyping import Array, Float

from .._checks import require_float64
from ..errors import InputError
from ..mechanism import Mechanism
from .cycle import CYCLE_ATOL, CYCLE_RTOL
from .life import LifeResult, dynamic_cycles_to_limit, not_computed_is_nan


class AbstractWearModel(eqx.Module):
    """How the wear of one crank cycle is computed (see the module notes)."""

    name: eqx.AbstractClassVar[str]
    # True when the pointwise derivative of its lives is the slope users want
    # (the quasi-static model), False when callers should difference (dynamic).
    exact_gradients: eqx.AbstractClassVar[bool]

    @abc.abstractmethod
    def life(self, mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
             period, limit):
        """Cycles until the peak wear depth of each joint reaches ``limit`` [m]:
        a `diffwear.wear.LifeResult`."""


class Dynamic(AbstractWearModel):
    """The dynamic model (the reference): each simulated cycle integrates the
    mechanism with its EFM clearance joints.

    ``steps``: scan slots the fastest-wearing joint takes to reach a wear
    limit (the life's accuracy knob; error ~ 1 / steps); ``scheme``:
    "implicit" (linearly implicit profile update) or "euler";
    ``cycle_rtol``/``cycle_atol``: tolerances of each dynamic cycle;
    ``cycle_solver``: its integrator (default Tsit5; ``Rodas4()`` with
    tolerances 1e-4 is several times faster, see
    `diffwear.wear.cycle.CYCLE_INTEGRATORS`; for derivatives on a stiff
    contact use ``Rodas4()`` at 1e-6, or, while the pin stays in contact,
    ``Rodas4(sensitivity="ros2")`` at a quarter of the cost: the tangents
    are not error-controlled, see the guide "Which derivatives to trust");
    ``forward_mode``: differentiate with diffrax's `ForwardMode` (for
    `jax.jacfwd`) instead of checkpointed reverse mode; ``warmup_cycles``
    dynamic cycles run first with their wear discarded.
    """

    name: ClassVar[str] = "dynamic"
    exact_gradients: ClassVar[bool] = False
    steps: int = eqx.field(static=True, default=10)
    scheme: str = eqx.field(static=True, default="implicit")
    cycle_rtol: float = eqx.field(static=True, default=CYCLE_RTOL)
    cycle_atol: float = eqx.field(static=True, default=CYCLE_ATOL)
    forward_mode: bool = eqx.field(static=True, default=False)
    warmup_cycles: int = eqx.field(static=True, default=1)
    cycle_solver: diffrax.AbstractSolver | None = None

    def life(self, mech, joints, y0, *, period, limit) -> LifeResult:
        return dynamic_cycles_to_limit(
            mech, joints, y0, period=period, limit=limit, steps=self.steps, scheme=self.scheme,
            warmup_cycles=self.warmup_cycles, cycle_rtol=self.cycle_rtol,
            cycle_atol=self.cycle_atol, cycle_solver=self.cycle_solver,
            adjoint=diffrax.ForwardMode() if self.forward_mode else None)


def cycles_to_limit(mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
                    period, limit, model: AbstractWearModel | None = None,
                    **dynamic_options) -> LifeResult:
    """Crank cycles until the peak wear depth of each of ``joints`` (clearance
    joints of ``mech`` with wear) reaches ``limit`` [m], starting from state
    ``y0`` (pins centred) with unworn bushings.

    ``model``: the wear model (`Dynamic`, the default, or
    `diffwear.quasistatic.QuasiStatic`).  ``dynamic_options`` (only without
    ``model``) go to the dynamic route: ``steps``, ``scheme``,
    ``warmup_cycles``, ``cycle_rtol``, ``cycle_atol``, ``cycle_solver``, ``adjoint``,
    ``operator_samples``, ``operator_width``, ``slots``, ``max_steps`` (see
    `diffwear.wear.life`).  Pure and jit-able; failures are reported in the
    result's ``status`` (`diffwear.wear.status`).
    """
    require_float64("cycles_to_limit")
    if model is None:
        res = dynamic_cycles_to_limit(mech, joints, y0, period=period, limit=limit,
                                      **dynamic_options)
        return _undefined_where_not_computed(res, (mech, y0, period, limit))
    if dynamic_options:
        raise InputError(f"cycles_to_limit: options {sorted(dynamic_options)} belong to the "
                         "model object; pass them to it (e.g. Dynamic(steps=20))")
    if not isinstance(model, AbstractWearModel):
        raise InputError(f"cycles_to_limit: model must be a wear model (Dynamic(), "
                         f"QuasiStatic()), got {model!r}")
    res = model.life(mech, tuple(joints), y0, period=period, limit=limit)
    return _undefined_where_not_computed(res, (model, mech, y0, period, limit))


def _undefined_where_not_computed(res: LifeResult, inputs) -> LifeResult:
    """A life not computed (NaN) has NaN derivatives, never a silent 0
    (`diffwear.wear.life.not_computed_is_nan`)."""
    return eqx.tree_at(lambda r: r.cycles, res, not_computed_is_nan(res.cycles, inputs))
