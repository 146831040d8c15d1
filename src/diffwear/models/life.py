"""`cycles_to_limit`: crank cycles until each wearing joint reaches a depth limit."""

from __future__ import annotations

import equinox as eqx
from jaxtyping import Array, Float

from .._checks import check_positive, require_float64
from ..contact.clearance_joint import ClearanceJoint
from ..errors import InputError
from ..mechanism import Mechanism
from ..wear.life import not_computed_is_nan
from ..wear.solution import WearSolution
from ._base import AbstractWearModel
from .dynamic import Dynamic


def cycles_to_limit(mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
                    period, limit, model: AbstractWearModel | None = None) -> WearSolution:
    """Crank cycles until the peak wear depth of each of ``joints`` (clearance
    joints of ``mech`` with wear) reaches ``limit`` [m], starting from state
    ``y0`` (pins centred) with unworn bushings.

    ``model``: the wear model (`Dynamic()`, the default, or `QuasiStatic()`,
    with their settings): its `WearSolution`, the lives in ``.life``.  Pure
    and jit-able; failures are reported in the solution's ``result``
    (`diffwear.wear.RESULTS`); a life not computed is NaN, with NaN
    derivatives.
    """
    require_float64("cycles_to_limit")
    model = Dynamic() if model is None else model
    if not callable(getattr(model, "life", None)):
        raise InputError(f"cycles_to_limit: model must be a wear model (Dynamic(), "
                         f"QuasiStatic()), got {model!r}")
    check_wearing_joints("cycles_to_limit", mech, joints)
    # a depth limit and a cycle period: positive and finite (checked when concrete)
    check_positive("cycles_to_limit: limit [m]", limit)
    check_positive("cycles_to_limit: period [s]", period)
    res = model.life(mech, tuple(joints), y0, period=period, limit=limit)
    # a life not computed (NaN) has NaN derivatives, never a silent 0
    return eqx.tree_at(lambda r: r.life, res,
                       not_computed_is_nan(res.life, (model, mech, y0, period, limit)))


def check_wearing_joints(what: str, mech: Mechanism, joints) -> None:
    """`InputError` unless ``joints`` names one or more distinct clearance
    joints of ``mech`` that have a wear law."""
    if isinstance(joints, str):
        raise InputError(f"{what}: joints must be a tuple of joint names, got the string "
                         f"{joints!r}; allowed: ({joints!r},)")
    joints = tuple(joints)
    wearing = sorted(f.name for f in mech.forces
                     if isinstance(f, ClearanceJoint) and f.wear is not None)
    if not joints:
        raise InputError(f"{what}: no joint named; allowed: one or more of the mechanism's "
                         f"clearance joints with a wear law {wearing}")
    repeated = sorted({j for j in joints if joints.count(j) > 1})
    if repeated:
        raise InputError(f"{what}: joint {repeated[0]!r} is named twice; allowed: distinct "
                         f"joints of {wearing}")
    unknown = [j for j in joints if j not in wearing]
    if unknown:
        raise InputError(f"{what}: {unknown[0]!r} is not a clearance joint with a wear law "
                         f"of the mechanism; allowed: {wearing or 'none (add a wear law)'}")


__all__ = ["cycles_to_limit", "check_wearing_joints"]
