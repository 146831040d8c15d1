"""Gradient-based bushing design (thesis Ch. 8)."""

from .optimise import (
    DesignResult,
    bushing_volume,
    equal_life,
    finite_difference_jacobian,
    jacobian,
    kkt_check,
    least_material,
    longest_common_life,
)
from .two_joint import (
    DEPTH_BOUNDS,
    DIAMETER_BOUNDS,
    JOINTS,
    LOWER,
    SWEEP_MODEL,
    TABLE_8_4,
    TABLE_8_5,
    UPPER,
    VARIABLES,
    WEAR_LIMIT,
    TwoJointLife,
    bushing,
    check_design,
)

__all__ = [
    "DesignResult", "bushing_volume", "equal_life", "finite_difference_jacobian",
    "jacobian", "kkt_check", "least_material", "longest_common_life",
    "DEPTH_BOUNDS", "DIAMETER_BOUNDS", "JOINTS", "LOWER", "SWEEP_MODEL", "TABLE_8_4", "TABLE_8_5",
    "UPPER", "VARIABLES", "WEAR_LIMIT", "TwoJointLife", "bushing", "check_design",
]
