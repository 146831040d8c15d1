"""Gradient-based bushing design (thesis Ch. 8)."""

from .two_joint import (
    DEPTH_BOUNDS,
    DIAMETER_BOUNDS,
    JOINTS,
    LOWER,
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
    "DEPTH_BOUNDS", "DIAMETER_BOUNDS", "JOINTS", "LOWER", "TABLE_8_4", "TABLE_8_5", "UPPER",
    "VARIABLES", "WEAR_LIMIT", "TwoJointLife", "bushing", "check_design",
]
