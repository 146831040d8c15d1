"""Wear: Archard's law (`diffwear.contact.archard`, re-exported), one-cycle wear
increments, evolution over many cycles and the life.  The wear models and
their runs (in chunks, with checkpoints) are `diffwear.models`."""

from ..contact.archard import MM3_PER_NM, SLIP_RATE_WIDTH, ArchardWear
from ._engine import WearState
from .cycle import (
    CycleResult,
    JointsCycleResult,
    reset_wear,
    wear_cycle,
    wear_cycle_joints,
)
from .dynamic_term import CycleSettings, DynamicWear
from .evolution import (
    Evolver,
    evolve,
    smooth_max,
    worn_mechanism,
    worn_volume,
)
from .extrapolation import (
    AbstractExtrapolation,
    Adaptive,
    Constant,
    ErrorControlled,
)
from .peak import (
    arc_peak_depth,
    peak_depth,
)
from .solution import WearLimitError, WearSolution
from .status import (
    RESULTS,
    not_an_answer,
    not_computed,
)

__all__ = [
    "MM3_PER_NM", "SLIP_RATE_WIDTH", "ArchardWear",
    "CycleResult", "wear_cycle", "reset_wear", "JointsCycleResult", "wear_cycle_joints",
    "peak_depth", "arc_peak_depth",
    "RESULTS", "not_an_answer", "not_computed",
    "WearSolution", "evolve", "smooth_max", "worn_volume", "worn_mechanism", "WearLimitError",
    "AbstractExtrapolation", "Constant", "Adaptive", "ErrorControlled",
    "Evolver", "WearState", "CycleSettings", "DynamicWear",
]
