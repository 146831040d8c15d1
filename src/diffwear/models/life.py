"""`cycles_to_limit`: crank cycles until each wearing joint reaches a depth limit."""

from __future__ import annotations

import equinox as eqx
from jaxtyping import Array, Float

from .._checks import require_float64
from ..errors import InputError
from ..mechanism import Mechanism
from ..wear.life import LifeResult, not_computed_is_nan
from ._base import AbstractWearModel
from .dynamic import Dynamic


def cycles_to_limit(mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
                    period, limit, model: AbstractWearModel | None = None) -> LifeResult:
    """Crank cycles until the peak wear depth of each of ``joints`` (clearance
    joints of ``mech`` with wear) reaches ``limit`` [m], starting from state
    ``y0`` (pins centred) with unworn bushings.

    ``model``: the wear model (`Dynamic()`, the default, or `QuasiStatic()`,
    with their settings).  Pure and jit-able; failures are reported in the
    result's ``status`` (`diffwear.wear.status`); a life not computed is NaN,
    with NaN derivatives.
    """
    require_float64("cycles_to_limit")
    model = Dynamic() if model is None else model
    if not callable(getattr(model, "life", None)):
        raise InputError(f"cycles_to_limit: model must be a wear model (Dynamic(), "
                         f"QuasiStatic()), got {model!r}")
    res = model.life(mech, tuple(joints), y0, period=period, limit=limit)
    # a life not computed (NaN) has NaN derivatives, never a silent 0
    return eqx.tree_at(lambda r: r.cycles, res,
                       not_computed_is_nan(res.cycles, (model, mech, y0, period, limit)))


__all__ = ["cycles_to_limit"]
