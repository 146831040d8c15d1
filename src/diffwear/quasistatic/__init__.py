"""The quasi-static joint model: the pin at the equilibrium of the EFM springs."""

from .joint import Equilibrium, QuasiStaticJoint
from .loads import CycleLoads, JointLoads, cycle_loads, ideal_parent

__all__ = ["Equilibrium", "QuasiStaticJoint", "CycleLoads", "JointLoads", "cycle_loads",
           "ideal_parent"]
