"""Planar multibody model: bodies, constraints, force elements, `Mechanism`."""

from .body import GROUND, Body
from .constraints import AbstractConstraint, Driver, RevoluteJoint, TranslationalJoint
from .forces import STANDARD_GRAVITY, AbstractForceElement, Gravity, GuideFriction, LinearSpring
from .frames import Frames
from .geometry import cross, perp, rotation, safe_norm
from .mechanism import Mechanism

__all__ = [
    "GROUND", "Body", "AbstractConstraint", "Driver", "RevoluteJoint", "TranslationalJoint",
    "STANDARD_GRAVITY", "AbstractForceElement", "GuideFriction", "Gravity", "LinearSpring",
    "Frames", "cross", "perp", "rotation", "safe_norm", "Mechanism",
]
