"""The command line's option strings as the library's objects: the one place
where a name (``--method adaptive``, ``--model quasi-static``, ``--contact
fem``, ``--integrator rodas4``) becomes a model or a solver.  The names are
`diffwear.choices`'s."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..choices import CALIBRATION_MODELS, WEAR_CONTACTS, WEAR_METHODS, WEAR_MODELS
from ..errors import InputError
from ..models import AbstractWearModel, Dynamic, FemRoute, QuasiStatic
from ..wear import CycleSettings
from ..wear.cycle import cycle_integrator
from ..wear.extrapolation import AbstractExtrapolation, Adaptive, Constant, ErrorControlled

if TYPE_CHECKING:
    from ..calibrate.fit import ForwardModel


def extrapolation_method(method, *, extrapolation=1.0, rtol=1e-2, atol=1e-7,
                         adaptive: dict | None = None) -> AbstractExtrapolation:
    """A strategy object as given, or one built from its name (``"constant"``
    with A = ``extrapolation``; ``"adaptive"`` with A_0 = ``extrapolation``
    and the ``adaptive`` settings; ``"error"`` with ``rtol``/``atol`` [m] and
    the first step ``extrapolation``)."""
    if isinstance(method, AbstractExtrapolation):
        return method
    if method not in WEAR_METHODS:
        raise InputError(f"method must be one of {', '.join(map(repr, WEAR_METHODS))} "
                         f"or an extrapolation object, got {method!r}")
    ex = None if extrapolation is None else float(extrapolation)
    if method == "constant":
        return Constant(1.0 if ex is None else ex)
    if method == "adaptive":
        opts = dict(adaptive or {})
        # A_0 comes from ``extrapolation``, not from the settings
        unknown = sorted(set(opts) - set(Adaptive.__dataclass_fields__) - {"name", "a0"})
        if unknown:
            raise InputError(f"adaptive settings {unknown}; allowed: a0_fraction, "
                             "inc_fraction, dec_fraction, criterion, change_fraction, "
                             "p_crit_fraction")
        return Adaptive(a0=ex, **opts)
    return ErrorControlled(rtol=float(rtol), atol=float(atol), dn0=ex)


def check_wear_model(model: str, dynamic_only=()) -> None:
    """`InputError` for a wear model that does not exist, or for an option
    given (``(given, "--option value")`` pairs) that only the dynamic model
    takes: the quasi-static model has no extrapolation, no checkpoints and no
    FEM pressure, it integrates the wear in the cycle count itself."""
    if model not in WEAR_MODELS:
        raise InputError(f"--model {model!r}; allowed: {', '.join(WEAR_MODELS)}")
    if model == "quasi-static":
        for given, option in dynamic_only:
            if given:
                raise InputError(f"{option} belongs to the dynamic model (--model dynamic); "
                                 "the quasi-static model integrates the wear in the cycle "
                                 "count itself (seconds, no checkpoints) with the EFM pressure")


def calibration_model(model: str) -> "ForwardModel":
    """The forward model class a calibration fits, by its ``--model`` name
    (`CALIBRATION_MODELS`): the quasi-static or the dynamic rig history."""
    from ..calibrate.model import RigHistory
    from ..calibrate.quasi_static import QuasiStaticRigHistory

    classes: dict[str, ForwardModel] = {QuasiStaticRigHistory.name: QuasiStaticRigHistory,
                                        RigHistory.name: RigHistory}
    assert set(classes) == set(CALIBRATION_MODELS)
    if model not in classes:
        raise InputError(f"--model {model!r}; allowed: {', '.join(CALIBRATION_MODELS)}")
    return classes[model]


def check_contact(contact: str) -> str:
    """``contact`` if it names a pressure model of the wear (`WEAR_CONTACTS`)."""
    if contact not in WEAR_CONTACTS:
        raise InputError(f"--contact must be one of {', '.join(WEAR_CONTACTS)} (the pressure "
                         f"model of the wear), got {contact!r}")
    return contact


def cycle_settings(integrator: str) -> CycleSettings:
    """The dynamic cycles' integrator by name, at its tolerance
    (`diffwear.wear.cycle.CYCLE_INTEGRATORS`)."""
    solver, tol = cycle_integrator(integrator)
    return CycleSettings(rtol=tol, atol=tol, solver=solver)


def default_constant_a(cycles, target_dynamic) -> float:
    """A = ceil(cycles / ``target_dynamic``): about that many dynamic cycles."""
    return max(1.0, float(math.ceil(cycles / target_dynamic)))


def wear_model(model: str, *, cycles, method: str = "constant", target_dynamic: int = 50,
               extrapolation=None, integrator: str = "tsit5", fem=None
               ) -> AbstractWearModel:
    """The wear model of ``--model`` (with ``--method``, ``--integrator`` and,
    given ``fem`` (a `FemWearModel`), the FEM wear pressure): the dynamic
    model extrapolates from A (or A_0) = ``extrapolation``, default
    `default_constant_a`."""
    if model == "quasi-static":
        return QuasiStatic()
    a = extrapolation or default_constant_a(cycles, target_dynamic)
    solver = extrapolation_method(method, extrapolation=a, atol=1e-6)
    cycle = cycle_settings(integrator)
    if fem is not None:
        return FemRoute(fem=fem, extrapolation=solver, cycle=cycle,
                        dynamic_cycles=int(target_dynamic))
    return Dynamic(extrapolation=solver, cycle=cycle, dynamic_cycles=int(target_dynamic))


__all__ = ["extrapolation_method", "check_wear_model", "check_contact", "cycle_settings",
           "default_constant_a", "wear_model"]
