"""diffwear: differentiable planar multibody dynamics with clearance and wear.

diffwear computes in float64 (contact penetrations of micrometres on
metre-scale positions are lost in float32) but does not switch JAX's
process-wide flag on import: call ``jax.config.update("jax_enable_x64", True)``
first (the ``diffwear`` command does); every simulation entry point raises an
`InputError` that says so otherwise.

The names most users need, by task::

    mechanism   Mechanism, Body, RevoluteJoint, TranslationalJoint, Driver, Gravity,
                LinearSpring, presets (the thesis mechanisms)
    dynamics    simulate, consistent_state
    contact     ClearanceJoint, with_clearance, contact_history, LankaraniNikravesh,
                KelvinVoigt, ElasticFoundation, CoulombFriction, ArchardWear
    wear        evolve (method=Constant(A) | Adaptive() | ErrorControlled()),
                CycleSettings, worn_volume
    models      Dynamic, QuasiStatic, FemRoute, cycles_to_limit
    results     WearSolution (what every wear model and evolve return),
                WearLimitError (WearSolution.check: a run that stopped early)
    design      TwoJointLife
    sweeps      sweep.sweep, sensitivity, finite_differences
    data        load_dataset, calibrate.calibrate

    checks      gradcheck, GradCheck
    errors      DiffwearError, InputError, SolverError

(``sweep`` and ``calibrate`` are the subpackages: a function of the same name
at the top would hide them.)
"""

from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _version

from . import calibrate, presets, sweep
from .calibrate import load_dataset
from .contact import (
    ArchardWear,
    ClearanceJoint,
    CoulombFriction,
    ElasticFoundation,
    KelvinVoigt,
    LankaraniNikravesh,
    contact_history,
    with_clearance,
)
from .design import TwoJointLife
from .dynamics import consistent_state, simulate
from .errors import DiffwearError, InputError, SolverError
from .gradient_check import GradCheck, gradcheck
from .mechanism import (
    Body,
    Driver,
    Gravity,
    LinearSpring,
    Mechanism,
    RevoluteJoint,
    TranslationalJoint,
)
from .models import Dynamic, FemRoute, QuasiStatic, cycles_to_limit
from .sweep.sensitivity import finite_differences, sensitivity
from .wear import (
    Adaptive,
    Constant,
    CycleSettings,
    ErrorControlled,
    WearLimitError,
    WearSolution,
    evolve,
    worn_volume,
)

try:  # the one version string is pyproject.toml's
    __version__ = _version("diffwear")
except PackageNotFoundError:  # pragma: no cover - a source tree without metadata
    __version__ = "0+unknown"

__all__ = [
    "presets", "Mechanism", "Body", "RevoluteJoint", "TranslationalJoint", "Driver",
    "Gravity", "LinearSpring", "simulate", "consistent_state", "ClearanceJoint",
    "with_clearance", "contact_history", "LankaraniNikravesh", "KelvinVoigt",
    "ElasticFoundation", "CoulombFriction", "ArchardWear", "evolve", "Constant",
    "Adaptive", "ErrorControlled", "CycleSettings", "cycles_to_limit",
    "Dynamic", "QuasiStatic", "FemRoute", "WearSolution", "WearLimitError", "worn_volume",
    "TwoJointLife", "sweep", "sensitivity",
    "finite_differences", "load_dataset", "calibrate", "gradcheck", "GradCheck",
    "DiffwearError", "InputError", "SolverError",
]
